"""Built-in plugin: animated GIF output, written as the frames come: a global colour table of the
first image's colours (then as many others of the settings' colours as fit, in order), and a local
table for any picture with a colour not in it (exact where the picture holds at most 256 colours,
the nearest of its 256 most common beyond)."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

from sandmod.api import PALETTE_SIZE, RecorderSpec, VideoSettings, fit_palette, hookimpl


#: Browsers slow down GIF frames shorter than 20 ms, and delays are in 10 ms steps.
MIN_DELAY_MS = 20
#: GIF stores its width and height in two bytes.
MAX_SIDE = 65535
#: The longest delay one GIF image holds (in 10 ms steps, two bytes): longer runs of one picture take several.
MAX_DELAY_MS = 65_530 * 10


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


def colour_table(rgb: np.ndarray) -> tuple[int, bytes]:
    """A GIF colour table of ``rgb`` (uint8 (entries, 3), at most 256): its size field (2 ** (size + 1)
    entries) and its bytes, padded with black."""
    size = max(0, (len(rgb) - 1).bit_length() - 1)
    return size, rgb.tobytes().ljust(3 * 2 ** (size + 1), b"\0")


def gif_header(width: int, height: int, rgb: np.ndarray, loop: int | None) -> bytes:
    """The GIF's screen, its global colour table (``rgb``) and, unless ``loop`` is None, how often it
    repeats after the first play."""
    size, table = colour_table(rgb)
    header = b"GIF89a" + struct.pack("<HHBBB", width, height, 0xF0 | size, 0, 0) + table  # 0xF0: a global table, 8 bits a channel
    if loop is not None:
        header += b"!\xff\x0bNETSCAPE2.0\x03\x01" + struct.pack("<H", loop) + b"\x00"
    return header


def picture_entries(box: np.ndarray, in_global: np.ndarray, colours: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """A picture's pixels as colour table entries (uint8), and its local table (uint8 (entries, 3);
    None: the global one holds all its colours). ``in_global``: each colour index's global entry,
    PALETTE_SIZE for those it lacks."""
    entries = np.take(in_global, box)  # faster than in_global[box]
    if entries.max() < PALETTE_SIZE:
        return entries.astype(np.uint8), None
    local = fit_palette([box], colours)
    return local.indices(box), local.rgb


def gif_picture(entries: np.ndarray, x: int, y: int, ms: int, local: np.ndarray | None) -> bytes:
    """One picture at (x, y) (colour table entries), shown ``ms`` milliseconds, with its ``local``
    colour table if any; pillow encodes its pixels (LZW). The file around them is written here,
    since pillow's own GIF writer keeps every frame until the end and matches each one's colours
    to the palette again, in Python."""
    from PIL import GifImagePlugin, Image

    image = Image.fromarray(entries, mode="P")
    if local is not None:
        image.putpalette(local.tobytes())
    return b"".join(GifImagePlugin.getdata(image, offset=(x, y), duration=ms, disposal=1, include_color_table=local is not None))


class GifRecorder:
    """Frames as one animated GIF, written as they come (see the module's docstring)."""

    def __init__(self, path: Path, settings: VideoSettings):
        self._settings = settings
        self._pictures = Changes(gif_delay_ms(settings.fps))
        self._file = open(path, "wb")
        self._in_global: np.ndarray | None = None  # per colour index: its global table entry, PALETTE_SIZE: none
        self.pictures = 0  # pictures written: images like the one before are merged into it
        self.local_tables = 0  # of them, those with a colour table of their own

    def add_frame(self, frame: np.ndarray) -> None:
        frame = np.array(frame, dtype=np.uint16)  # a copy: the caller may reuse its array
        if self._in_global is None:
            self._start(frame)
        self._write(self._pictures.add(frame))

    def close(self) -> None:
        self._write(self._pictures.finish())
        if not self.pictures:
            raise ValueError("no frames to write")
        self._file.write(b";")
        self._file.close()

    def _start(self, first: np.ndarray) -> None:
        """The header, with the global table: the first image's colours, then others while there is room."""
        settings, palette = self._settings, fit_palette([first], self._settings.colours)
        spare = np.flatnonzero(~palette.kept)[: PALETTE_SIZE - len(palette.rgb)]
        self._in_global = np.where(palette.kept, palette.lookup.astype(np.uint16), PALETTE_SIZE)
        self._in_global[spare] = np.arange(len(palette.rgb), len(palette.rgb) + len(spare))
        table = np.concatenate([palette.rgb, settings.colours[spare]])
        plays = settings.loop  # GIF counts repeats after the first play; none: play once
        self._file.write(gif_header(settings.width, settings.height, table, None if plays == 1 else max(plays - 1, 0)))

    def _write(self, pictures) -> None:
        for box, x, y, ms in pictures:
            entries, local = picture_entries(box, self._in_global, self._settings.colours)
            self._file.write(gif_picture(entries, x, y, ms, local))
            self.pictures += 1
            self.local_tables += local is not None


@hookimpl
def register_recorders(register):
    register(
        RecorderSpec(
            "gif", (".gif",), GifRecorder, "Animated GIF: 256 colours a picture (the nearest of them beyond), streamed.", max_side=MAX_SIDE
        )
    )
