"""What a plugin author imports: the hook marker and the types the hooks pass.

::

    from sandmod.api import RecorderSpec, hookimpl

    @hookimpl
    def register_recorders(register):
        register(RecorderSpec("count", (".txt",), CountRecorder, "How many frames, as text."))

A plugin's per-cell behaviour (see ``register_behaviours``) is written with
:func:`behaviour` and the helpers ``here``, ``look``, ``put``, ``swap``,
``temperature``, ``random``, ``chance``, ``arg`` and ``frame``::

    from sandmod.api import arg, behaviour, chance, hookimpl, look, put

    @behaviour(args=("into", "chance"))
    def grow(v):
        if look(v, 0, -1) == 0 and chance(v, arg(v, 1)):
            put(v, 0, -1, int(arg(v, 0)))

Everything here is stable; the modules it comes from are not.
"""

from __future__ import annotations

from .errors import Problem, ProblemsError
from .hooks import Metric, ModLoader, hookimpl
from .formats.behaviour import REACH, Behaviour, View, arg, behaviour, chance, frame, helper, here, look, put, random, swap, temperature
from .formats.modspec import Explosion
from .formats.recording import PALETTE_SIZE, Palette, Recorder, RecorderSpec, SavedAtClose, VideoSettings, fit_palette, write_png
from .formats.tomlsource import Loc, TomlSource
from .world.world import State

__all__ = [
    "REACH",
    "Behaviour",
    "View",
    "arg",
    "behaviour",
    "chance",
    "frame",
    "helper",
    "here",
    "look",
    "put",
    "random",
    "swap",
    "temperature",
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
