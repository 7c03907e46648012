"""Built-in plugin: animated WebP, lossless RGB."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sandmod.hooks import hookimpl
from sandmod.recording import RecorderSpec, VideoSettings


class WebpRecorder:
    """Collects frames and writes them as one lossless animated WebP."""

    def __init__(self, path: Path, settings: VideoSettings):
        from PIL import features

        if not features.check("webp"):
            raise RuntimeError("this pillow was built without WebP support; pick another format")
        self._path = path
        self._settings = settings
        self._frames: list = []

    def add_frame(self, frame: np.ndarray) -> None:
        from PIL import Image

        self._frames.append(Image.fromarray(self._settings.rgb(frame), mode="RGB"))

    def close(self) -> None:
        if not self._frames:
            raise ValueError("no frames to write")
        first, *rest = self._frames
        first.save(
            self._path,
            format="WEBP",
            save_all=True,
            append_images=rest,
            duration=self._settings.frame_ms,
            loop=self._settings.loop,  # WebP counts plays; 0 = forever
            lossless=True,
            quality=0,  # with lossless: effort, not fidelity (0 = fastest)
            method=0,
        )
        self._frames.clear()


@hookimpl
def register_recorders(register):
    register(RecorderSpec("webp", (".webp",), WebpRecorder, "Animated WebP: lossless, small, any delay."))
