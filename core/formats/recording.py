"""Output formats: what a recorder is, and writing its output atomically.

A recorder receives finished frames (palette indices, already cropped and
scaled) and writes them to a path: a file, or for a recorder that writes a
folder of images, a folder. sandmod hands it a temporary path beside the real
output and renames it into place only when the recorder closes cleanly, so a
failed or interrupted render never leaves a half-written output.
"""

from __future__ import annotations

import contextlib
import fnmatch
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator, Protocol

import numpy as np


@dataclass(frozen=True)
class VideoSettings:
    """What a recorder needs to know about the frames it will get."""

    #: Frame width in pixels.
    width: int
    #: Frame height in pixels.
    height: int
    #: 768 bytes: 256 RGB triples.
    palette: bytes
    #: Frames a second.
    fps: float
    #: Times the animation plays in all; 0 = forever.
    loop: int = 0

    def rgb(self, frame: np.ndarray) -> np.ndarray:
        """A palette frame as a (height, width, 3) uint8 RGB array, for formats without palettes."""
        return np.frombuffer(self.palette, np.uint8).reshape(256, 3)[frame]

    @property
    def frame_ms(self) -> int:
        """How long each image shows, in whole milliseconds."""
        return max(1, round(1000 / self.fps))


class Recorder(Protocol):
    """Writes frames to one output."""

    def add_frame(self, frame: np.ndarray) -> None:
        """Add one frame: a (height, width) uint8 array of palette indices."""

    def close(self) -> None:
        """Finish the file. Called once, after the last frame."""


class SavedAtClose:
    """A recorder for formats written in one go: it keeps each frame (as an image, by default) and saves all on close.

    Subclasses say what is kept of a frame (:meth:`convert`) and how it is
    all saved (:meth:`save`).
    """

    #: The file to write.
    path: Path
    #: The frames' size, palette and speed.
    settings: VideoSettings

    def __init__(self, path: Path, settings: VideoSettings):
        self.path = path
        self.settings = settings
        self._images: list = []

    def convert(self, frame: np.ndarray):
        """The pillow image kept for a frame (by default in the shared palette)."""
        return palette_image(frame, self.settings.palette)

    def save(self, first, rest: list) -> None:
        """Write the images to ``self.path``."""
        raise NotImplementedError

    def add_frame(self, frame: np.ndarray) -> None:
        """Keep the frame, as :meth:`convert` makes it."""
        self._images.append(self.convert(frame))

    def close(self) -> None:
        """Save every frame kept, with :meth:`save`."""
        if not self._images:
            raise ValueError("no frames to write")
        first, *rest = self._images
        self.save(first, rest)
        self._images.clear()


@dataclass(frozen=True)
class RecorderSpec:
    """An output format that plugins register."""

    #: The format's name, as ``--format`` takes it.
    name: str
    #: The file extensions it writes (``.gif``), lower case.
    extensions: tuple[str, ...]
    #: Opens a recorder on a path.
    open: Callable[[Path, VideoSettings], Recorder]
    #: One line for ``sandmod list``.
    description: str = ""
    #: For a recorder that writes a folder: a glob of its files' names, e.g. "frame_*.png".
    folder: str | None = None
    #: The widest and tallest image the format holds, in pixels.
    max_side: int | None = None
    #: Memory each recorded pixel takes until the output is closed (0: streamed).
    kept_bytes_per_pixel: float = 0.0


class WriteError(OSError):
    """Writing one of a render's outputs failed; ``target`` is the output it was for."""

    def __init__(self, target: Path, cause: OSError):
        super().__init__(cause.errno, cause.strerror or str(cause))
        self.target = Path(target)


@contextlib.contextmanager
def writing(target: Path) -> Iterator[None]:
    """Turn an OSError inside into a :class:`WriteError` naming ``target``."""
    try:
        yield
    except WriteError:
        raise
    except OSError as exc:
        raise WriteError(target, exc) from exc


@contextlib.contextmanager
def atomic_path(target: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success it replaces ``target``.

    The temporary's name holds this process's id, so that what a killed run
    left (``.NAME.PID.*.part``) is removed by the next run on the same output.
    """
    target = Path(target)
    with writing(target):
        target.parent.mkdir(parents=True, exist_ok=True)
        remove_stale(target)
        fd, name = tempfile.mkstemp(prefix=_temp_prefix(target), suffix=".part", dir=target.parent)
        os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        with writing(target):
            os.chmod(tmp, 0o666 & ~_umask())  # as an ordinary new file (mkstemp makes it private)
            os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def atomic_folder(target: Path, files: str) -> Iterator[Path]:
    """Yield a temporary folder beside ``target``; on success it takes ``target``'s place.

    An existing ``target`` is replaced only when every file in it matches the
    glob ``files`` (an earlier render's frames), checked before anything is
    written and again just before it is replaced; otherwise FileExistsError.
    """
    target = Path(target)
    _only_frames(target, files)
    with writing(target):
        target.parent.mkdir(parents=True, exist_ok=True)
        remove_stale(target)
        tmp = Path(tempfile.mkdtemp(prefix=_temp_prefix(target), suffix=".part", dir=target.parent))
    try:
        yield tmp
        _only_frames(target, files)  # nothing else was put there while we ran
        with writing(target):
            os.chmod(tmp, 0o777 & ~_umask())
            if target.exists():
                old = Path(tempfile.mkdtemp(prefix=_temp_prefix(target), suffix=".old", dir=target.parent))
                os.replace(target, old / "frames")
                os.replace(tmp, target)
                shutil.rmtree(old)
            else:
                os.replace(tmp, target)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)


def _only_frames(target: Path, files: str) -> None:
    if target.exists():
        if not target.is_dir() or not all(p.is_file() and fnmatch.fnmatchcase(p.name, files) for p in target.iterdir()):
            raise FileExistsError(f"{target} exists and holds other files than an earlier render's {files}")


def _temp_prefix(target: Path) -> str:
    return f".{target.name}.{os.getpid()}."


def remove_stale(target: Path) -> None:
    """Remove what killed runs left beside ``target``: temporaries whose process is gone."""
    prefix = f".{target.name}."
    for path in Path(target.parent).iterdir():
        name = path.name
        if not (name.startswith(prefix) and name.endswith((".part", ".old"))):
            continue
        pid = name[len(prefix) :].split(".", 1)[0]
        if not pid.isdigit() or _alive(int(pid)):
            continue
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # someone else's: leave it
    return True


def output_bytes(path: Path) -> int:
    """The size of an output: a file, or the files of a folder recorder's folder."""
    path = Path(path)
    return sum(p.stat().st_size for p in path.iterdir()) if path.is_dir() else path.stat().st_size


def palette_image(frame: np.ndarray, palette: bytes):
    """A palette frame as a pillow image in mode ``P``."""
    from PIL import Image

    image = Image.fromarray(np.ascontiguousarray(frame, dtype=np.uint8), mode="P")
    image.putpalette(palette)
    return image


def write_png(path: Path, frame: np.ndarray, palette: bytes) -> None:
    """Write one palette frame as an indexed PNG."""
    palette_image(frame, palette).save(path, format="PNG", compress_level=1)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
