"""Built-in plugin: animated GIF output with one shared palette."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np

from sandmod.hooks import hookimpl
from sandmod.recording import RecorderSpec, SavedAtClose, VideoSettings, palette_image

#: Browsers slow down GIF frames shorter than 20 ms, and delays are in 10 ms steps.
MIN_DELAY_MS = 20


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


class GifRecorder(SavedAtClose):
    """Palette frames as one animated GIF with a single global colour table."""

    def __init__(self, path: Path, settings: VideoSettings):
        super().__init__(path, settings)
        self._palette = distinct_colours(settings.palette)

    def convert(self, frame: np.ndarray):
        return palette_image(frame, self._palette)

    def save(self, first, rest: list) -> None:
        plays = self.settings.loop
        looping = {} if plays == 1 else {"loop": max(plays - 1, 0)}  # GIF counts repeats; none: play once
        first.save(
            self.path,
            format="GIF",
            save_all=True,
            append_images=rest,
            duration=gif_delay_ms(self.settings.fps),
            palette=self._palette,  # one global colour table, no table per frame
            optimize=False,
            disposal=1,
            **looping,
        )


@hookimpl
def register_recorders(register):
    register(RecorderSpec("gif", (".gif",), GifRecorder, "Animated GIF, one shared 256-colour palette."))
