"""Output formats: what a recorder is, and writing its file atomically.

A recorder receives finished frames (palette indices, already scaled) and
writes them to a path. sandmod hands it a temporary path beside the real
output and renames it into place only when the recorder closes cleanly, so a
failed or interrupted render never leaves a half-written file.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator, Protocol

import numpy as np


@dataclass(frozen=True)
class VideoSettings:
    """What a recorder needs to know about the frames it will get."""

    width: int
    height: int
    palette: bytes  # 768 bytes: 256 RGB triples
    fps: float
    loop: int = 0  # 0 = forever


class Recorder(Protocol):
    """Writes frames to one output."""

    def add_frame(self, frame: np.ndarray) -> None:
        """Add one frame: a (height, width) uint8 array of palette indices."""

    def close(self) -> None:
        """Finish the file. Called once, after the last frame."""


@dataclass(frozen=True)
class RecorderSpec:
    """An output format that plugins register."""

    name: str
    extensions: tuple[str, ...]
    open: Callable[[Path, VideoSettings], Recorder]
    description: str = ""


@contextlib.contextmanager
def atomic_path(target: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success it replaces ``target``."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # as an ordinary new file (mkstemp makes it private)
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
