"""Built-in plugin: animated PNG (APNG), lossless, with the shared palette."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sandmod.hooks import hookimpl
from sandmod.recording import RecorderSpec, VideoSettings, palette_image


class ApngRecorder:
    """Collects palette frames and writes them as one indexed animated PNG."""

    def __init__(self, path: Path, settings: VideoSettings):
        self._path = path
        self._settings = settings
        self._frames: list = []

    def add_frame(self, frame: np.ndarray) -> None:
        self._frames.append(palette_image(frame, self._settings.palette))

    def close(self) -> None:
        if not self._frames:
            raise ValueError("no frames to write")
        first, *rest = self._frames
        first.save(
            self._path,
            format="PNG",
            save_all=True,
            append_images=rest,
            duration=self._settings.frame_ms,
            loop=self._settings.loop,  # APNG counts plays; 0 = forever
            default_image=False,
            compress_level=3,
        )
        self._frames.clear()


@hookimpl
def register_recorders(register):
    register(RecorderSpec("apng", (".apng", ".png"), ApngRecorder, "Animated PNG: lossless, the shared palette, any delay."))
