"""The plugin manager, and what the plugins registered.

:func:`make_plugin_manager` builds a fresh manager (no import-time state) with
the built-in plugins and those installed under the ``sandmod`` entry-point
group. :func:`collect` calls each registering hook and returns a
:class:`Registry` that remembers which plugin gave what.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Generic, Mapping, TypeVar

import pluggy

from . import hooks
from .errors import Problem, ProblemsError
from .formats.behaviour import NAME, Behaviour
from .formats.recording import RecorderSpec
from .formats.tomlsource import TomlSource

T = TypeVar("T")

#: Built-in plugins, registered by module name.
BUILTIN_PLUGINS = (
    "sandmod.plugins.toml_mods",
    "sandmod.plugins.gif",
    "sandmod.plugins.apng",
    "sandmod.plugins.webp",
    "sandmod.plugins.png_frames",
)
#: Comma-separated plugin names to leave out (built-in or installed).
DISABLE_ENV = "SANDMOD_DISABLE_PLUGINS"
#: A plugin name that may prefix its behaviours' names (``garden`` in ``garden:grow``).
BEHAVIOUR_PLUGIN = re.compile(r"^[a-z][a-z0-9_.-]*$")


@dataclass(frozen=True)
class Registered(Generic[T]):
    """A value and the plugin that registered it."""

    value: T
    plugin: str


@dataclass
class Registry:
    """Everything the plugins registered."""

    mod_dirs: list[Registered[Path]] = field(default_factory=list)
    mod_loaders: dict[str, Registered[hooks.ModLoader]] = field(default_factory=dict)
    mods: list[Registered[TomlSource]] = field(default_factory=list)
    recorders: dict[str, Registered[RecorderSpec]] = field(default_factory=dict)
    metrics: dict[str, Registered[hooks.Metric]] = field(default_factory=dict)
    #: By full name, ``PLUGIN:name``.
    behaviours: dict[str, Registered[Behaviour]] = field(default_factory=dict)

    def recorder_for(self, path: Path) -> RecorderSpec | None:
        """The recorder that writes files with ``path``'s extension (a folder recorder: no extension)."""
        suffix = Path(path).suffix.lower()
        for entry in reversed(self.recorders.values()):  # a later plugin wins
            spec = entry.value
            if suffix in spec.extensions or (not suffix and spec.folder):
                return spec
        return None

    def recorder_choices(self) -> str:
        """The formats and their extensions, for error messages: 'gif (.gif), ...'."""
        return ", ".join(
            f"{name} ({', '.join(e.value.extensions) or 'a folder'})" for name, e in sorted(self.recorders.items())
        )


def make_plugin_manager(*, entry_points: bool = True) -> pluggy.PluginManager:
    """A plugin manager with sandmod's hooks, built-in plugins and installed plugins."""
    import importlib

    pm = pluggy.PluginManager(hooks.PROJECT)
    pm.add_hookspecs(hooks)
    for name in filter(None, (n.strip() for n in os.environ.get(DISABLE_ENV, "").split(","))):
        pm.set_blocked(name)
    for module_name in BUILTIN_PLUGINS:
        if not pm.is_blocked(module_name):
            pm.register(importlib.import_module(module_name), name=module_name)
    if entry_points:
        try:
            pm.load_setuptools_entrypoints(hooks.PROJECT)
        except Exception as exc:  # a broken third-party plugin must not look like our crash
            raise ProblemsError([Problem("plugins", None, "", f"a plugin failed to load: {exc!r}")]) from exc
    return pm


def collect(pm: pluggy.PluginManager) -> Registry:
    """Call every registering hook and gather what the plugins gave; ProblemsError names each
    plugin that implements a hook sandmod does not have (a misspelling) or fails to register."""
    try:
        pm.check_pending()  # a hook marked but misspelled would otherwise never be called
    except pluggy.PluginValidationError as exc:
        known = ", ".join(sorted(name for name in dir(hooks) if name.startswith("register_")))
        raise ProblemsError([Problem(pm.get_name(exc.plugin) or "plugins", None, "", f"{exc} (sandmod's hooks: {known})")]) from None
    registry = Registry()
    problems: list[Problem] = []

    def each(hook_name: str, make_register: Callable[[str], Callable[..., None]]) -> None:
        caller = getattr(pm.hook, hook_name)
        for impl in caller.get_hookimpls():  # in registration order: built-ins first
            try:
                impl.function(register=make_register(impl.plugin_name))
            except ProblemsError as exc:
                problems.extend(exc.problems)
            except Exception as exc:  # a plugin's bug is its problem, named, not our traceback
                problems.append(Problem(impl.plugin_name, None, hook_name, f"failed: {exc!r}"))

    def mod_dir(plugin: str) -> Callable[[Path], None]:
        def register(path: Path) -> None:
            path = Path(path)
            if not path.is_dir():
                problems.append(Problem(plugin, None, "register_mod_dirs", f"{path} is not a directory"))
                return
            registry.mod_dirs.append(Registered(path, plugin))

        return register

    def mod_loader(plugin: str) -> Callable[[str, hooks.ModLoader], None]:
        def register(suffix: str, load: hooks.ModLoader) -> None:
            if not (isinstance(suffix, str) and suffix.startswith(".") and callable(load)):
                problems.append(Problem(plugin, None, "register_mod_loaders", f"register(suffix, load) needs '.ext' and a function, got {suffix!r}, {load!r}"))
                return
            registry.mod_loaders[suffix.lower()] = Registered(load, plugin)

        return register

    def mod(plugin: str) -> Callable[[Mapping[str, Any], str], None]:
        def register(data: Mapping[str, Any], origin: str) -> None:
            if not isinstance(data, Mapping):
                problems.append(Problem(plugin, None, "register_mods", f"register(data, origin) needs a mapping, got {data!r}"))
                return
            registry.mods.append(Registered(TomlSource(origin, "", dict(data)), plugin))

        return register

    def recorder(plugin: str) -> Callable[[RecorderSpec], None]:
        def register(spec: RecorderSpec) -> None:
            if not isinstance(spec, RecorderSpec):
                problems.append(Problem(plugin, None, "register_recorders", f"register() needs a RecorderSpec, got {spec!r}"))
                return
            registry.recorders[spec.name] = Registered(spec, plugin)

        return register

    def metric(plugin: str) -> Callable[[str, hooks.Metric], None]:
        def register(name: str, measure: hooks.Metric) -> None:
            if not (isinstance(name, str) and name and callable(measure)):
                problems.append(Problem(plugin, None, "register_metrics", f"register(name, measure) needs a name and a function, got {name!r}, {measure!r}"))
                return
            registry.metrics[name] = Registered(measure, plugin)

        return register

    def behaviour(plugin: str) -> Callable[[str, Behaviour], None]:
        def register(name: str, function: Behaviour) -> None:
            if callable(function) and not isinstance(function, Behaviour):
                function = Behaviour(function)  # a bare function: no arguments
            full = f"{plugin}:{name}"
            if not (isinstance(name, str) and NAME.match(name) and isinstance(function, Behaviour)):
                message = f"register(name, behaviour) needs a lower-case name and a function, got {name!r}, {function!r}"
            elif not BEHAVIOUR_PLUGIN.match(plugin):
                message = f"a plugin named {plugin!r} cannot name behaviours (its name must be lower-case letters, digits, '_', '-' or '.')"
            elif full in registry.behaviours:
                message = f"'{full}' is registered twice"
            else:
                registry.behaviours[full] = Registered(function, plugin)
                return
            problems.append(Problem(plugin, None, "register_behaviours", message))

        return register

    each("register_mod_dirs", mod_dir)
    each("register_mod_loaders", mod_loader)
    each("register_mods", mod)
    each("register_recorders", recorder)
    each("register_metrics", metric)
    each("register_behaviours", behaviour)
    if problems:
        raise ProblemsError(problems)
    return registry
