"""Built-in plugin: a folder of numbered PNG images, one per frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sandmod.api import RecorderSpec, VideoSettings, hookimpl, write_png


#: The name of image number i (from 0) in the folder.
NAME = "frame_{:05d}.png"


class PngFramesRecorder:
    """Writes each frame as it comes as a PNG (indexed when it holds at most 256 colours, else RGB):
    frame_00000.png, frame_00001.png, ..."""

    def __init__(self, folder: Path, settings: VideoSettings):
        self._folder = folder
        self._settings = settings
        self._count = 0

    def add_frame(self, frame: np.ndarray) -> None:
        write_png(self._folder / NAME.format(self._count), frame, self._settings.colours)
        self._count += 1

    def close(self) -> None:
        if not self._count:
            raise ValueError("no frames to write")


@hookimpl
def register_recorders(register):
    register(
        RecorderSpec(
            "png-frames", (), PngFramesRecorder, "A folder of PNGs, frame_00000.png on (outputs without an extension).", folder="frame_*.png"
        )
    )
