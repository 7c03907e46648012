"""An example sandmod plugin: a folder of mods, and a recorder that writes text."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sandmod.api import RecorderSpec, VideoSettings, hookimpl

#: Darkest to brightest.
RAMP = " .:-=+*#%@"


class AsciiRecorder:
    """Writes each frame as rows of characters, by the brightness of each pixel's colour."""

    def __init__(self, path: Path, settings: VideoSettings):
        rgb = settings.colours.astype(float)
        brightness = rgb @ np.array([0.299, 0.587, 0.114]) / 255.0
        self._chars = np.array(list(RAMP))[np.minimum((brightness * len(RAMP)).astype(int), len(RAMP) - 1)]
        self._file = open(path, "w", encoding="utf-8")

    def add_frame(self, frame: np.ndarray) -> None:
        rows = self._chars[frame]
        self._file.write("\n".join("".join(row) for row in rows) + "\n\n")

    def close(self) -> None:
        self._file.close()


@hookimpl
def register_mod_dirs(register):
    register(Path(__file__).parent / "mods")


@hookimpl
def register_recorders(register):
    register(RecorderSpec("ascii", (".txt",), AsciiRecorder, "Text: one character per pixel, by brightness."))
