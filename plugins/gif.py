"""Built-in plugin: animated GIF output with one shared palette."""

from __future__ import annotations

import itertools
import struct
from pathlib import Path
from typing import BinaryIO, Iterator, Sequence

import numpy as np

from sandmod.hooks import hookimpl
from sandmod.recording import RecorderSpec, SavedAtClose, VideoSettings, palette_image

#: Browsers slow down GIF frames shorter than 20 ms, and delays are in 10 ms steps.
MIN_DELAY_MS = 20
#: The longest delay one GIF image holds (in 10 ms steps, two bytes): longer runs of one picture take several.
MAX_DELAY_MS = 65_530 * 10


def distinct_colours(palette: bytes) -> bytes:
    """The palette with repeated colours nudged by one unit, so every entry is distinct.

    Pillow matches frame colours to a given palette by colour; repeats make
    that slow and ambiguous. A change of one unit in one channel is invisible.
    """
    seen: set[tuple[int, int, int]] = set()
    out = bytearray(palette)
    for i in range(0, len(out), 3):
        r, g, b = out[i : i + 3]
        for dr, dg, db in itertools.product((0, 1, -1), repeat=3):  # (0, 0, 0) first
            candidate = (min(max(r + dr, 0), 255), min(max(g + dg, 0), 255), min(max(b + db, 0), 255))
            if candidate not in seen:
                break
        else:
            candidate = next((v, v, v) for v in range(256) if (v, v, v) not in seen)
        seen.add(candidate)
        out[i : i + 3] = bytes(candidate)
    return bytes(out)


def gif_delay_ms(fps: float) -> int:
    """The delay GIF stores for ``fps``: whole 10 ms steps, at least MIN_DELAY_MS."""
    return max(MIN_DELAY_MS, int(round(1000 / fps / 10)) * 10)


def changes(frames: Sequence[np.ndarray], delay_ms: int) -> Iterator[tuple[np.ndarray, int, int, int]]:
    """Each picture of ``frames`` as GIF stores it: (the box that changed since the last, its x, its y,
    how long it shows in ms). A frame like the one before it adds its delay to that one's."""
    shown: list | None = None  # [box, x, y, ms] of the picture before, not yet given out
    previous = None
    for frame in frames:
        if previous is None:
            box, x, y = frame, 0, 0
        else:
            changed = frame != previous
            rows = np.flatnonzero(changed.any(axis=1))
            if rows.size == 0 and shown[3] + delay_ms <= MAX_DELAY_MS:
                shown[3] += delay_ms
                continue
            cols = np.flatnonzero(changed.any(axis=0))
            y0, y1, x0, x1 = (rows[0], rows[-1] + 1, cols[0], cols[-1] + 1) if rows.size else (0, 1, 0, 1)
            box, x, y = frame[y0:y1, x0:x1], int(x0), int(y0)
        if shown is not None:
            yield tuple(shown)
        shown = [box, x, y, delay_ms]
        previous = frame
    if shown is not None:
        yield tuple(shown)


def write_gif(out: BinaryIO, frames: Sequence[np.ndarray], palette: bytes, delay_ms: int, loop: int | None) -> None:
    """Write palette-index frames as an animated GIF: one global colour table (``palette``, 768
    bytes), each picture cut to what changed, ``loop`` repeats after the first play (None: none).

    Pillow encodes each picture's pixels (LZW); the file around them is written here, since
    pillow's own GIF writer matches every frame's colours to the palette again, in Python.
    """
    from PIL import GifImagePlugin

    height, width = frames[0].shape
    out.write(b"GIF89a" + struct.pack("<HHBBB", width, height, 0xF7, 0, 0) + palette)  # 0xF7: a global table of 256 colours, 8 bits a channel
    if loop is not None:
        out.write(b"!\xff\x0bNETSCAPE2.0\x03\x01" + struct.pack("<H", loop) + b"\x00")
    for box, x, y, ms in changes(frames, delay_ms):
        image = palette_image(box, palette)
        out.write(b"".join(GifImagePlugin.getdata(image, offset=(x, y), duration=ms, disposal=1)))
    out.write(b";")


class GifRecorder(SavedAtClose):
    """Palette frames as one animated GIF with a single global colour table."""

    def __init__(self, path: Path, settings: VideoSettings):
        super().__init__(path, settings)
        self._palette = distinct_colours(settings.palette)

    def convert(self, frame: np.ndarray) -> np.ndarray:
        return np.array(frame, dtype=np.uint8)  # a copy: the caller may reuse its array

    def save(self, first, rest: list) -> None:
        plays = self.settings.loop
        with open(self.path, "wb") as out:  # GIF counts repeats after the first play; none: play once
            write_gif(out, [first, *rest], self._palette, gif_delay_ms(self.settings.fps), None if plays == 1 else max(plays - 1, 0))


@hookimpl
def register_recorders(register):
    register(RecorderSpec("gif", (".gif",), GifRecorder, "Animated GIF, one shared 256-colour palette."))
