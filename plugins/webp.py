"""Built-in plugin: animated WebP, lossless RGB."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sandmod.api import RecorderSpec, SavedAtClose, VideoSettings, hookimpl


class WebpRecorder(SavedAtClose):
    """Frames as one lossless animated WebP."""

    def __init__(self, path: Path, settings: VideoSettings):
        from PIL import features

        if not features.check("webp"):
            raise RuntimeError("this pillow was built without WebP support; pick another format")
        super().__init__(path, settings)

    def convert(self, frame: np.ndarray):
        from PIL import Image

        return Image.fromarray(self.settings.rgb(frame), mode="RGB")

    def save(self, first, rest: list) -> None:
        first.save(
            self.path,
            format="WEBP",
            save_all=True,
            append_images=rest,
            duration=self.settings.frame_ms,
            loop=self.settings.loop,  # WebP counts plays; 0 = forever
            lossless=True,
            quality=0,  # with lossless: effort, not fidelity (0 = fastest)
            method=0,
            kmin=0,  # no key frames after the first: a third faster and a quarter smaller here
            kmax=0,
        )


@hookimpl
def register_recorders(register):
    # Until it closes: each frame as a pillow RGB image (4 bytes a pixel), then the encoder's: 4.85 measured.
    register(
        RecorderSpec(
            "webp", (".webp",), WebpRecorder, "Animated WebP: lossless, small, any delay.", max_side=16383, kept_bytes_per_pixel=5
        )
    )
