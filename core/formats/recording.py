"""Output formats: what a recorder is, and writing its output atomically.

A recorder receives finished frames (colour indices into the settings'
``colours``, already cropped and scaled) and writes them to a path: a file,
or for a recorder that writes a folder of images, a folder. Formats with
palettes fit the frames' colours into 256 with :func:`fit_palette`. sandmod
hands it a temporary path beside the real output and renames it into place
only when the recorder closes cleanly, so a failed or interrupted render
never leaves a half-written output.
"""

from __future__ import annotations

import contextlib
import fnmatch
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Iterator, Protocol

import numpy as np


@dataclass(frozen=True)
class VideoSettings:
    """What a recorder needs to know about the frames it will get."""

    #: Frame width in pixels.
    width: int
    #: Frame height in pixels.
    height: int
    #: Every colour a frame may hold, uint8 (colours, 3) RGB: a frame's values are rows of it.
    colours: np.ndarray
    #: Frames a second.
    fps: float
    #: Times the animation plays in all; 0 = forever.
    loop: int = 0

    def rgb(self, frame: np.ndarray) -> np.ndarray:
        """A frame as a (height, width, 3) uint8 RGB array."""
        return self.colours[frame]

    @property
    def frame_ms(self) -> int:
        """How long each image shows, in whole milliseconds."""
        return max(1, round(1000 / self.fps))


class Recorder(Protocol):
    """Writes frames to one output."""

    def add_frame(self, frame: np.ndarray) -> None:
        """Add one frame: a (height, width) uint16 array of colour indices (rows of ``settings.colours``)."""

    def close(self) -> None:
        """Finish the file. Called once, after the last frame."""


class SavedAtClose:
    """A recorder for formats written in one go: it keeps each frame (a copy, by default) and saves all on close.

    Subclasses say what is kept of a frame (:meth:`convert`) and how it is
    all saved (:meth:`save`).
    """

    #: The file to write.
    path: Path
    #: The frames' size, colours and speed.
    settings: VideoSettings

    def __init__(self, path: Path, settings: VideoSettings):
        self.path = path
        self.settings = settings
        self._images: list = []

    def convert(self, frame: np.ndarray):
        """What is kept of a frame (by default a copy of its colour indices)."""
        return np.array(frame)

    def save(self, first, rest: list) -> None:
        """Write what was kept of the frames to ``self.path``."""
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


#: The most colours a palette image holds.
PALETTE_SIZE = 256


@dataclass(frozen=True)
class Palette:
    """Frames' colours as at most 256, for formats with palettes: made by :func:`fit_palette`."""

    #: uint8 (entries, 3) RGB, at most PALETTE_SIZE entries.
    rgb: np.ndarray
    #: uint8 per colour index: its entry (for the colours of the frames it was made for).
    lookup: np.ndarray
    #: bool per colour index: held as it is (every colour of the frames, where :attr:`exact`).
    kept: np.ndarray
    #: The frames held at most PALETTE_SIZE colours: each shows as it is.
    exact: bool

    def indices(self, frame: np.ndarray) -> np.ndarray:
        """A frame's colour indices as entries of the palette, uint8."""
        return np.take(self.lookup, frame)

    def image(self, frame: np.ndarray):
        """A frame as a pillow image in mode ``P``."""
        from PIL import Image

        image = Image.fromarray(self.indices(frame), mode="P")
        image.putpalette(self.rgb.tobytes())
        return image


def fit_palette(frames: Iterable[np.ndarray], colours: np.ndarray) -> Palette:
    """The colours ``frames`` hold as a palette: all of them, exactly, when they are at most
    PALETTE_SIZE (found by counting the indices, not by comparing colours). Beyond, a quantized one
    (``exact`` False): the PALETTE_SIZE most common colours as they are, every other as the nearest
    of them; a format that must be lossless writes RGB instead."""
    counts = sum(np.bincount(frame.ravel(), minlength=len(colours)) for frame in frames)
    used = np.flatnonzero(counts)
    kept = used if len(used) <= PALETTE_SIZE else np.sort(used[np.argsort(-counts[used], kind="stable")[:PALETTE_SIZE]])
    held = np.zeros(len(colours), bool)
    held[kept] = True
    lookup = np.zeros(len(colours), np.uint8)
    lookup[kept] = np.arange(len(kept))
    others = used[~held[used]]
    if len(others):
        lookup[others] = _nearest(colours[others], colours[kept])
    return Palette(colours[kept], lookup, held, not len(others))


def _nearest(rgb: np.ndarray, table: np.ndarray, rows: int = 1024) -> np.ndarray:
    """For each colour of ``rgb``, the entry of ``table`` nearest to it (squared distance, the first of equals)."""
    table = table.astype(np.int32)[None]
    parts = np.split(rgb.astype(np.int32), list(range(rows, len(rgb), rows)))
    return np.concatenate([((part[:, None, :] - table) ** 2).sum(axis=2).argmin(axis=1) for part in parts])


def write_png(path: Path, frame: np.ndarray, colours: np.ndarray) -> None:
    """Write one frame (colour indices) as a PNG: indexed when it holds at most PALETTE_SIZE colours, else RGB."""
    from PIL import Image

    palette = fit_palette([frame], colours)
    image = palette.image(frame) if palette.exact else Image.fromarray(colours[frame], mode="RGB")
    image.save(path, format="PNG", compress_level=1)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
