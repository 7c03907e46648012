"""The plugin API: every hook sandmod calls, typed and documented.

A plugin is a module or object with functions named after these hooks and
marked with :data:`hookimpl`. Third-party plugins are found through the
``sandmod`` entry-point group::

    [project.entry-points.sandmod]
    my_plugin = "my_package.plugin"

Every hook receives a ``register`` callback. Call it once per thing you
provide; sandmod checks the value at once and remembers which plugin gave it
(shown by ``sandmod list``). Hooks return nothing.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping

import pluggy

if TYPE_CHECKING:
    from .formats.behaviour import Behaviour
    from .formats.recording import RecorderSpec
    from .formats.tomlsource import TomlSource
    # World (sandmod.World, which Metric names) is in a part above this one: named, not imported.

PROJECT = "sandmod"

hookspec = pluggy.HookspecMarker(PROJECT)
#: Mark a plugin's hook implementations with this.
hookimpl = pluggy.HookimplMarker(PROJECT)

#: Reads one mod file into its data and key positions.
ModLoader = Callable[[Path], "TomlSource"]


@hookspec
def register_mod_dirs(register: Callable[[Path], None]) -> None:
    """Add folders to search for mod files.

    ``register(path)`` takes an existing directory. Every file in it whose
    suffix has a loader (see :func:`register_mod_loaders`) is a mod.
    """


@hookspec
def register_mod_loaders(register: Callable[[str, ModLoader], None]) -> None:
    """Teach sandmod to read mod files of another format.

    ``register(suffix, load)``: ``suffix`` like ``".toml"``; ``load(path)``
    returns a :class:`sandmod.api.TomlSource` (the parsed data and the line
    of each key) or raises :class:`sandmod.api.ProblemsError`.
    """


@hookspec
def register_mods(register: Callable[[Mapping[str, Any], str], None]) -> None:
    """Add mods built in Python rather than read from a file.

    ``register(data, origin)``: ``data`` has the same shape as a mod file
    (``{"mod": {...}, "elements": {...}, "reactions": [...]}``) and is
    validated like one; ``origin`` names it in error messages.
    """


@hookspec
def register_recorders(register: Callable[["RecorderSpec"], None]) -> None:
    """Add output formats for ``sandmod render``.

    ``register(spec)`` takes a :class:`sandmod.api.RecorderSpec`:
    a name, the file extensions it writes, and a function that opens a
    recorder on a path.
    """


#: Measures a world: a number, or a mapping of names to numbers (each becomes a column ``name.key``).
Metric = Callable[["World"], "float | Mapping[str, float]"]


@hookspec
def register_metrics(register: Callable[[str, Metric], None]) -> None:
    """Add metrics that ``sandmod batch`` takes of each run, at the sweep's ``[metrics] frames``.

    ``register(name, measure)``: ``measure(world)`` gets the
    world (a :class:`sandmod.World`) and returns a number, or a mapping of
    names to numbers; the results table gets a column ``name@FRAME`` (or
    ``name.key@FRAME``) for it. Example, the height of the tallest heap::

        @hookimpl
        def register_metrics(register):
            register("top", lambda world: float((world.cells != 0).any(axis=1).argmax()))
    """


@hookspec
def register_behaviours(register: Callable[[str, "Behaviour"], None]) -> None:
    """Add compiled per-cell behaviours, for what data cannot say (a vine that branches, an ant).

    ``register(name, behaviour)``: ``name`` a lower-case identifier; elements name it
    ``PLUGIN:name``, after the plugin's name (its entry point's: ``garden:grow``).
    ``behaviour`` is a function of one :class:`sandmod.api.View` made into a
    :class:`sandmod.api.Behaviour` by ``@sandmod.api.behaviour(args=(...))`` (a bare function
    takes no arguments). sandmod compiles it with numba, on its own, the first time a world
    whose elements name it steps, and calls it once a frame for each of their cells, after the
    kernel's step, through the helpers of :mod:`sandmod.api` (``look``, ``put``, ``chance``...)::

        @behaviour(args=("into", "chance"))
        def grow(v):
            if look(v, 0, -1) == 0 and chance(v, arg(v, 1)):
                put(v, 0, -1, int(arg(v, 0)))

        @hookimpl
        def register_behaviours(register):
            register("grow", grow)
    """
