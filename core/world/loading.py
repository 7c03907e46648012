"""From files to a ready world: plugins, mods, ruleset, world.

These are the functions the CLI (and a Python user) calls::

    from sandmod.world.loading import load_world
    loaded = load_world("examples/hourglass.toml")
    for _ in range(100):
        loaded.world.step()
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable, NamedTuple, Sequence

import pluggy

from ..rules.compiler import Ruleset, compile_mods
from ..errors import Problem
from ..formats.limits import DEFAULT_MAX_MEMORY, MemoryBudget
from ..rules.modset import LoadedMod, ModSet, find_mods
from ..registry import Registry, collect, make_plugin_manager
from ..formats.tomlsource import TomlSource
from ..formats.validation import validate
from .world import World
from ..formats.worldspec import WorldFile


def load_registry(pm: pluggy.PluginManager | None = None) -> Registry:
    """What the installed plugins register."""
    return collect(pm or make_plugin_manager())


def load_ruleset(
    mods: Sequence[str] | None = None, mod_dirs: Iterable[Path] = (), registry: Registry | None = None
) -> Ruleset:
    """Compile the named mods (all found when ``None``) from the plugins' folders and ``mod_dirs``
    (``mod_folders(mod_dirs)`` adds ``./mods``, as the command line does)."""
    registry = registry or load_registry()
    modset = find_mods(registry, mod_dirs)
    return compile_mods(modset.select(mods), modset.behaviours)


@dataclass(frozen=True)
class LoadedWorld:
    """A world file, its ruleset, and the world built from it."""

    #: The world file.
    path: Path
    #: The world file, validated.
    spec: WorldFile
    #: The world file as parsed, with the line of each key.
    source: TomlSource
    #: The mods the world asks for, compiled.
    ruleset: Ruleset
    #: The world, its scene painted, at frame 0.
    world: World
    #: What the plugins registered.
    registry: Registry
    #: What the user should know of: other mod versions than the world was made with.
    warnings: list[Problem] = field(default_factory=list)
    #: The memory it was allowed, and promised so far.
    memory: MemoryBudget = field(default_factory=MemoryBudget)

    @property
    def inputs(self) -> list[Path]:
        """The files the world is made from: the world file and its pictures."""
        from ..formats.worldspec import Picture

        shapes = [*self.spec.scene, *(event.paint for event in self.spec.timeline if event.paint is not None)]
        folder = self.source.folder or Path(".")
        return [self.path, *(folder / shape.file for shape in shapes if isinstance(shape, Picture))]


def mod_folders(extra: Iterable[Path] = (), world: Path | None = None) -> list[Path]:
    """The folders mods are read from besides the plugins': a ``mods/`` beside ``world``, ``./mods``,
    then ``extra`` (each folder once)."""
    named = [Path(p) for p in extra]
    found = ([Path(world).parent / "mods"] if world is not None else []) + [Path("mods")]
    unique: dict[Path, Path] = {}
    for folder in [*(f for f in found if f.is_dir()), *named]:  # a folder the user named must exist: find_mods says so
        unique.setdefault(folder.resolve(), folder)
    return list(unique.values())


def world_mod_folders(spec: WorldFile, source: TomlSource, path: Path, mod_dirs: Iterable[Path] = ()) -> list[Path]:
    """:func:`mod_folders` for a world file, with the folders its ``world.mod_folders`` names (each inside
    the world file's folder: a world file never makes sandmod read mods from elsewhere). ProblemsError
    names a folder refused or missing."""
    from ..errors import ProblemsError, display_path
    from ..formats.userfiles import Refused, inside

    folder = source.folder or Path(path).parent
    named, problems = [], []
    for number, written in enumerate(spec.world.mod_folders):
        where = ("world", "mod_folders", number)
        try:
            found = inside(folder, written, "mods folder")
        except Refused as refused:
            problems.append(source.problem(where, str(refused)))
            continue
        if not found.is_dir():
            problems.append(source.problem(where, f"no folder '{written}' in {display_path(folder)}"))
        named.append(found)
    if problems:
        raise ProblemsError(problems)
    return mod_folders([*mod_dirs, *named], path)


def read_world_spec(path: str | Path) -> tuple[WorldFile, TomlSource]:
    """Read and validate a world file (no mods needed)."""
    from ..errors import ProblemsError

    source = TomlSource.read(path)
    if "mod" in source.data and "world" not in source.data:
        hint = "this is a mod ([mod]), not a world ([world]); put it in a mods/ folder beside your world"
        raise ProblemsError([source.problem(("mod",), hint)])
    return validate(WorldFile, source), source


def load_world(
    path: str | Path,
    *,
    mod_dirs: Iterable[Path] = (),
    seed: int | None = None,
    registry: Registry | None = None,
    max_memory: int | None = DEFAULT_MAX_MEMORY,
) -> LoadedWorld:
    """Read a world file, load the mods it asks for and paint its scene.

    Mods are found as the command line finds them: the plugins' (the bundled
    ones), a ``mods/`` folder beside the world file, ``./mods`` and ``mod_dirs``.

    What the world would take is checked against ``max_memory`` bytes (None:
    no limit) before it is allocated; past it, a ProblemsError says how much.
    """
    path = Path(path)
    spec, source = read_world_spec(path)
    return load_world_spec(spec, source, path, mod_dirs=mod_dirs, seed=seed, registry=registry, max_memory=max_memory)


def load_world_spec(
    spec: WorldFile,
    source: TomlSource,
    path: Path,
    *,
    mod_dirs: Iterable[Path] = (),
    seed: int | None = None,
    registry: Registry | None = None,
    max_memory: int | None = DEFAULT_MAX_MEMORY,
    rules: WorldRules | None = None,
) -> LoadedWorld:
    """:func:`load_world` for a world file already read (or made in memory: ``path`` names it,
    and its folder is where mods beside it are looked for); with ``rules``, under those."""
    from .scene import build_world

    registry, modset, ruleset = rules or world_rules(spec, source, path, mod_dirs=mod_dirs, registry=registry)
    memory = MemoryBudget(max_memory)
    world = build_world(spec, ruleset, source, seed, memory, _unloaded_elements(modset, ruleset))
    return LoadedWorld(path, spec, source, ruleset, world, registry, mod_warnings(spec, source, ruleset), memory)


class WorldRules(NamedTuple):
    """The plugins, the mods found, and the ruleset a world file's mods compile to."""

    registry: Registry
    modset: ModSet
    ruleset: Ruleset


def world_rules(
    spec: WorldFile,
    source: TomlSource,
    path: Path,
    *,
    mod_dirs: Iterable[Path] = (),
    registry: Registry | None = None,
    change: Callable[[list[LoadedMod]], list[LoadedMod]] | None = None,
) -> WorldRules:
    """Find the mods as the command line does and compile those the world asks for (``change``
    may alter them first: a sweep's parameters). ProblemsError names what is wrong."""
    registry = registry or load_registry()
    modset: ModSet = find_mods(registry, world_mod_folders(spec, source, path, mod_dirs))
    selected = _select_for_world(modset, spec, source)
    return WorldRules(registry, modset, compile_mods(change(selected) if change else selected, modset.behaviours))


def mod_warnings(spec: WorldFile, source: TomlSource, ruleset: Ruleset) -> list[Problem]:
    """How the loaded mods differ from those the world records in ``world.made_with``."""
    recorded = spec.world.made_with
    if recorded is None:
        return []
    loaded = {m.name: m.spec.mod.version for m in ruleset.mods}
    warnings = []
    for name, version in recorded.items():
        where = ("world", "made_with", name)
        if name not in loaded:
            warnings.append(source.problem(where, f"made with mod {name} {version}, which is not loaded now"))
        elif loaded[name] != version:
            warnings.append(source.problem(where, f"made with mod {name} {version}; loading {name} {loaded[name]}"))
    for name in sorted(set(loaded) - set(recorded)):
        warnings.append(source.problem(("world", "made_with"), f"mod {name} {loaded[name]} is loaded but the world was not made with it"))
    return warnings


def _select_for_world(modset: ModSet, spec: WorldFile, source: TomlSource):
    from ..errors import ProblemsError

    names = spec.world.mods
    if names is not None:
        missing = [
            source.problem(("world", "mods", i), f"mod '{name}' was not found (found: {', '.join(sorted(modset.mods))})")
            for i, name in enumerate(names)
            if name not in modset.mods
        ]
        if missing:
            raise ProblemsError(missing)
    return modset.select(names)


def _unloaded_elements(modset: ModSet, ruleset: Ruleset) -> dict[str, str]:
    """Elements of the mods found but not loaded ('water' and 'water:water'), each to its mod."""
    loaded = {m.name for m in ruleset.mods}
    found: dict[str, str] = {}
    for mod in modset.mods.values():
        if mod.name not in loaded:
            for element in mod.spec.elements:
                found.setdefault(element, mod.name)
                found[f"{mod.name}:{element}"] = mod.name
    return found
