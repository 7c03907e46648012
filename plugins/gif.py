"""Built-in plugin: animated GIF output with one shared palette."""

from __future__ import annotations

import itertools
import struct
from pathlib import Path
from typing import BinaryIO, Iterable, Iterator, Sequence

import numpy as np

from sandmod.api import RecorderSpec, VideoSettings, hookimpl, palette_image


#: Browsers slow down GIF frames shorter than 20 ms, and delays are in 10 ms steps.
MIN_DELAY_MS = 20
#: GIF stores its width and height in two bytes.
MAX_SIDE = 65535
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


class Changes:
    """Frames in, pictures out as GIF stores them: (the box that changed since the last, its x, its y,
    how long it shows in ms). A frame like the one before it adds its delay to that one's, so a
    picture is given out only when the next differs (or at :meth:`finish`)."""

    def __init__(self, delay_ms: int):
        self.delay_ms = delay_ms
        self._shown: list | None = None  # [box, x, y, ms] of the picture before, not yet given out
        self._previous: np.ndarray | None = None

    def add(self, frame: np.ndarray) -> Iterator[tuple[np.ndarray, int, int, int]]:
        """The pictures finished by ``frame`` (none or one)."""
        if self._previous is None:
            box, x, y = frame, 0, 0
        else:
            changed = frame != self._previous
            rows = np.flatnonzero(changed.any(axis=1))
            if rows.size == 0 and self._shown[3] + self.delay_ms <= MAX_DELAY_MS:
                self._shown[3] += self.delay_ms
                return
            cols = np.flatnonzero(changed.any(axis=0))
            y0, y1, x0, x1 = (rows[0], rows[-1] + 1, cols[0], cols[-1] + 1) if rows.size else (0, 1, 0, 1)
            box, x, y = frame[y0:y1, x0:x1], int(x0), int(y0)
        if self._shown is not None:
            yield tuple(self._shown)
        self._shown = [box, x, y, self.delay_ms]
        self._previous = frame

    def finish(self) -> Iterator[tuple[np.ndarray, int, int, int]]:
        """The last picture."""
        if self._shown is not None:
            yield tuple(self._shown)
        self._shown = None


def changes(frames: Iterable[np.ndarray], delay_ms: int) -> Iterator[tuple[np.ndarray, int, int, int]]:
    """Each picture of ``frames`` as GIF stores it (see :class:`Changes`)."""
    pictures = Changes(delay_ms)
    for frame in frames:
        yield from pictures.add(frame)
    yield from pictures.finish()


def gif_header(width: int, height: int, palette: bytes, loop: int | None) -> bytes:
    """The GIF's screen, its global colour table (``palette``, 768 bytes) and, unless ``loop`` is
    None, how often it repeats after the first play."""
    header = b"GIF89a" + struct.pack("<HHBBB", width, height, 0xF7, 0, 0) + palette  # 0xF7: 256 colours, 8 bits a channel
    if loop is not None:
        header += b"!\xff\x0bNETSCAPE2.0\x03\x01" + struct.pack("<H", loop) + b"\x00"
    return header


def gif_picture(box: np.ndarray, x: int, y: int, ms: int, palette: bytes) -> bytes:
    """One picture at (x, y), shown ``ms`` milliseconds; pillow encodes its pixels (LZW). The file
    around them is written here, since pillow's own GIF writer keeps every frame until the end and
    matches each one's colours to the palette again, in Python."""
    from PIL import GifImagePlugin

    return b"".join(GifImagePlugin.getdata(palette_image(box, palette), offset=(x, y), duration=ms, disposal=1))


def write_gif(out: BinaryIO, frames: Sequence[np.ndarray], palette: bytes, delay_ms: int, loop: int | None) -> None:
    """Write palette-index frames as an animated GIF: each picture cut to what changed, ``loop``
    repeats after the first play (None: none)."""
    height, width = frames[0].shape
    out.write(gif_header(width, height, palette, loop))
    for box, x, y, ms in changes(frames, delay_ms):
        out.write(gif_picture(box, x, y, ms, palette))
    out.write(b";")


class GifRecorder:
    """Palette frames as one animated GIF with a single global colour table, written as they come."""

    def __init__(self, path: Path, settings: VideoSettings):
        self._palette = distinct_colours(settings.palette)
        self._pictures = Changes(gif_delay_ms(settings.fps))
        plays = settings.loop  # GIF counts repeats after the first play; none: play once
        self._file = open(path, "wb")
        self._file.write(gif_header(settings.width, settings.height, self._palette, None if plays == 1 else max(plays - 1, 0)))
        self.pictures = 0  # pictures written: images like the one before are merged into it

    def add_frame(self, frame: np.ndarray) -> None:
        self._write(self._pictures.add(np.array(frame, dtype=np.uint8)))  # a copy: the caller may reuse its array

    def close(self) -> None:
        self._write(self._pictures.finish())
        if not self.pictures:
            raise ValueError("no frames to write")
        self._file.write(b";")
        self._file.close()

    def _write(self, pictures) -> None:
        for box, x, y, ms in pictures:
            self._file.write(gif_picture(box, x, y, ms, self._palette))
            self.pictures += 1


@hookimpl
def register_recorders(register):
    register(RecorderSpec("gif", (".gif",), GifRecorder, "Animated GIF, one shared 256-colour palette.", max_side=MAX_SIDE))
