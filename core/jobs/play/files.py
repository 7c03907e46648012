"""What ``sandmod play`` writes (sessions, snapshots, screenshots, captures): each whole or not at all,
in the first of its folders that can be written, and a capture in the background so that the window
never freezes."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
from PIL import Image

from ...formats.recording import VideoSettings, atomic_path
from ...world.world import enlarge


def folders(first: Path | None) -> list[Path]:
    """Where play writes, in order of preference: ``first`` (the world's folder), the current one, the home one."""
    places = [first] if first is not None else []
    places += [Path.cwd(), Path.home()]
    unique: list[Path] = []
    for place in places:
        if place.resolve() not in [u.resolve() for u in unique]:
            unique.append(place)
    return unique


def write_somewhere(name: str, places: Sequence[Path], write: Callable[[Path], None]) -> Path:
    """``write(path)`` for ``name`` in the first of ``places`` where it works; the path written. The first
    place's OSError if none works."""
    first: OSError | None = None
    for place in places:
        try:
            write(place / name)
            return place / name
        except OSError as error:
            first = first or error
    assert first is not None, "no place to write to"
    raise first


def save_png(rgb: np.ndarray, path: Path) -> None:
    """An RGB image (height, width, 3) as a PNG file, whole or not at all."""
    with atomic_path(path) as temporary:
        Image.fromarray(rgb, "RGB").save(temporary, format="PNG")


class Capture:
    """A GIF of frames (colour indices) written on a thread of its own; :meth:`result` says how it went."""

    def __init__(self, frames: list[np.ndarray], scale: int, colours: np.ndarray, fps: float, name: str, places: Sequence[Path]):
        self.outcome: str | None = None
        self._thread = threading.Thread(target=self._write, args=(frames, scale, colours, fps, name, places), daemon=False)
        self._thread.start()

    def _write(self, frames, scale, colours, fps, name, places) -> None:
        from ...world.loading import load_registry

        try:
            spec = load_registry().recorders["gif"].value
            height, width = frames[0].shape
            settings = VideoSettings(width * scale, height * scale, colours, fps)

            def write(path: Path) -> None:
                with atomic_path(path) as temporary:
                    recorder = spec.open(temporary, settings)
                    for frame in frames:
                        recorder.add_frame(enlarge(frame, scale))
                    recorder.close()

            path = write_somewhere(name, places, write)
            self.outcome = f"saved {path}: {len(frames)} images"
        except (OSError, ValueError) as error:
            self.outcome = f"could not save {name}: {getattr(error, 'strerror', None) or error}"

    def result(self, wait: bool = False) -> str | None:
        """What came of it (None: still writing; ``wait`` for it to end)."""
        if wait:
            self._thread.join()
        return self.outcome if not self._thread.is_alive() else None
