"""What a plugin author imports: the hook marker and the types the hooks pass.

::

    from sandmod.api import RecorderSpec, hookimpl

    @hookimpl
    def register_recorders(register):
        register(RecorderSpec("count", (".txt",), CountRecorder, "How many frames, as text."))

Everything here is stable; the modules it comes from are not.
"""

from __future__ import annotations

from .errors import Problem, ProblemsError
from .hooks import Metric, ModLoader, hookimpl
from .formats.modspec import Explosion
from .formats.recording import PALETTE_SIZE, Palette, Recorder, RecorderSpec, SavedAtClose, VideoSettings, fit_palette, write_png
from .formats.tomlsource import Loc, TomlSource
from .world.world import State

__all__ = [
    "Explosion",
    "PALETTE_SIZE",
    "Palette",
    "Loc",
    "Metric",
    "ModLoader",
    "Problem",
    "ProblemsError",
    "Recorder",
    "RecorderSpec",
    "SavedAtClose",
    "State",
    "TomlSource",
    "VideoSettings",
    "fit_palette",
    "hookimpl",
    "write_png",
]
