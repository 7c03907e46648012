"""Built-in plugin: animated GIF output with one shared palette."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sandmod.hooks import hookimpl
from sandmod.recording import RecorderSpec, VideoSettings

#: Browsers slow down GIF frames shorter than 20 ms, and delays are in 10 ms steps.
MIN_DELAY_MS = 20


class GifRecorder:
    """Collects palette frames and writes them as one animated GIF."""

    def __init__(self, path: Path, settings: VideoSettings):
        from PIL import Image

        self._image = Image
        self._path = path
        self._settings = settings
        self._frames: list = []

    def add_frame(self, frame: np.ndarray) -> None:
        image = self._image.fromarray(np.ascontiguousarray(frame, dtype=np.uint8), mode="P")
        image.putpalette(self._settings.palette)
        self._frames.append(image)

    def close(self) -> None:
        if not self._frames:
            raise ValueError("no frames to write")
        delay = max(MIN_DELAY_MS, int(round(1000 / self._settings.fps / 10)) * 10)
        first, *rest = self._frames
        first.save(
            self._path,
            format="GIF",
            save_all=True,
            append_images=rest,
            duration=delay,
            loop=self._settings.loop,
            palette=self._settings.palette,  # one global colour table, no table per frame
            optimize=False,
            disposal=1,
        )
        self._frames.clear()


@hookimpl
def register_recorders(register):
    register(RecorderSpec("gif", (".gif",), GifRecorder, "Animated GIF, one shared 256-colour palette."))
