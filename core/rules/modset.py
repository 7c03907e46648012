"""Find, read and validate mods, then pick the ones a world needs in load order.

Mods come from folders (the bundled ``mods/``, folders that plugins register,
a ``mods/`` beside the world file, ``--mods DIR``) and from plugins directly.
Every file is read and validated before anything is reported, so one run
lists every problem in every file.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping, Sequence

from ..errors import Problem, ProblemsError, display_path
from pydantic import ValidationError

from ..formats.modspec import ModFile, ModInfo, version_matches
from ..formats.behaviour import Behaviour
from ..registry import Registered, Registry
from ..formats.tomlsource import TomlSource
from ..formats.validation import validate

#: The mod every world loads: it defines ``empty`` and ``stone``.
BASE_MOD = "base"


@dataclass(frozen=True)
class LoadedMod:
    """A validated mod and where it came from."""

    spec: ModFile
    source: TomlSource
    plugin: str

    @property
    def name(self) -> str:
        return self.spec.mod.name

    @property
    def requires(self) -> list[str]:
        """The mods this one needs loaded first (``base`` is always among them)."""
        own = self.spec.mod.required_names
        return own if self.name == BASE_MOD or BASE_MOD in own else [BASE_MOD, *own]


@dataclass(frozen=True)
class ModSet:
    """Every mod that was found, by name."""

    mods: dict[str, LoadedMod]
    broken: frozenset[str] = frozenset()  # names of mods that were found but have mistakes
    salvaged: tuple["Salvaged", ...] = ()  # those, their broken parts stood in for (see salvage): for checking only
    behaviours: Mapping[str, Registered[Behaviour]] = field(default_factory=dict)  # the plugins', by full name

    def usable(self) -> list[str]:
        """The mods whose requirements, all the way down, were found without mistakes."""
        ok: dict[str, bool] = {}

        def check(name: str, seen: tuple[str, ...]) -> bool:
            if name not in ok:
                mod = self.mods.get(name)
                ok[name] = mod is not None and all(r in seen or check(r, seen + (r,)) for r in mod.requires)
            return ok[name]

        return [name for name in self.mods if check(name, (name,))]

    def select(self, names: Sequence[str] | None = None) -> list[LoadedMod]:
        """The named mods (all when ``None``), what they require, and ``base``, in load order."""
        wanted = list(self.mods) if names is None else [BASE_MOD, *names]
        problems: list[Problem] = []
        chosen: dict[str, LoadedMod] = {}
        stack = [n for n in wanted if n in self.mods]
        while stack:
            mod = self.mods[stack.pop()]
            if mod.name in chosen:
                continue
            chosen[mod.name] = mod
            problems += requirement_problems(mod.spec.mod, mod.source, self.mods, self.broken)
            stack += [need for need, _ in mod.spec.mod.requirements() if need in self.mods]
        if BASE_MOD not in self.mods:
            problems.append(Problem("mods", None, "", f"the '{BASE_MOD}' mod (empty, stone) was not found"))
        if problems:
            raise ProblemsError(problems)
        return _load_order(chosen)


def requirement_problems(info: ModInfo, source: TomlSource, mods: dict[str, LoadedMod], broken: Iterable[str]) -> list[Problem]:
    """What is wrong with the mods a mod's header requires: not found, with mistakes, another version."""
    problems = []
    for i, (need, conditions) in enumerate(info.requirements()):
        found = mods.get(need)
        if found is not None and not version_matches(found.spec.mod.version, conditions):
            message = f"requires mod '{info.requires[i].strip()}', but {found.source.name} is version {found.spec.mod.version}"
        elif found is not None:
            continue
        elif need in broken:
            message = f"requires mod '{need}', which has mistakes"
        else:
            message = f"requires mod '{need}', which was not found"
        problems.append(source.problem(("mod", "requires", i), message))
    return problems


def _load_order(mods: dict[str, LoadedMod]) -> list[LoadedMod]:
    """Dependencies first; among mods free to go, alphabetical. Cycles are errors."""
    order: list[LoadedMod] = []
    done: set[str] = set()
    remaining = dict(sorted(mods.items()))
    while remaining:
        ready = [name for name, mod in remaining.items() if all(r in done for r in mod.requires)]
        if not ready:
            cycle = _find_cycle(remaining)
            first = remaining[cycle[0]]
            raise ProblemsError(
                [first.source.problem(("mod", "requires"), "dependency cycle: " + " -> ".join(cycle))]
            )
        name = ready[0]
        order.append(remaining.pop(name))
        done.add(name)
    return order


def _find_cycle(mods: dict[str, LoadedMod]) -> list[str]:
    start = next(iter(mods))
    path = [start]
    while True:
        following = next(r for r in mods[path[-1]].requires if r in mods)
        if following in path:
            return path[path.index(following) :] + [following]
        path.append(following)


def is_world(data: dict) -> bool:
    """Whether a file's tables are a world's ([world], no [mod]): a world beside mods is not one of them."""
    return "world" in data and "mod" not in data


def is_sweep(data: dict) -> bool:
    """Whether a file's tables are a sweep's ([sweep], no [mod]), for ``sandmod batch``: not a mod either."""
    return "sweep" in data and "mod" not in data


def find_mods(registry: Registry, extra_dirs: Iterable[Path] = (), extra_files: Iterable[Path] = ()) -> ModSet:
    """Read and validate every mod the registry, ``extra_dirs`` and ``extra_files`` provide.

    Raises :class:`ProblemsError` naming every mistake in every file.
    """
    modset, problems = discover_mods(registry, extra_dirs, extra_files)
    if problems:
        raise ProblemsError(problems)
    return modset


def discover_mods(
    registry: Registry, extra_dirs: Iterable[Path] = (), extra_files: Iterable[Path] = ()
) -> tuple[ModSet, list[Problem]]:
    """:func:`find_mods` that keeps going: the mods that are valid, and the problems of the rest."""
    problems: list[Problem] = []
    loaded: list[LoadedMod] = []

    broken: set[str] = set()
    headers: list[tuple[ModInfo, TomlSource]] = []  # of mods with mistakes elsewhere: their requires are checked too

    salvaged: list[Salvaged] = []

    def add(source: TomlSource, plugin: str) -> None:
        try:
            loaded.append(LoadedMod(validate(ModFile, source), source, plugin))
        except ProblemsError as exc:
            problems.extend(exc.problems)
            info = source.data.get("mod")
            if isinstance(info, dict) and isinstance(info.get("name"), str):
                broken.add(info["name"])
                with contextlib.suppress(ValidationError):
                    headers.append((ModInfo.model_validate(info), source))
                whole = salvage(source, plugin)
                if whole is not None:
                    salvaged.append(whole)

    folders = [(entry.value, entry.plugin) for entry in registry.mod_dirs]
    for folder in extra_dirs:
        if Path(folder).is_dir():
            folders.append((Path(folder), "user"))
        else:
            problems.append(Problem(display_path(folder), None, "", "mods folder does not exist"))
    files = [(path, plugin) for folder, plugin in folders for path in sorted(Path(folder).iterdir())]
    files += [(Path(path), "user") for path in extra_files]
    seen: set[Path] = set()
    copies: set[tuple[str, bytes]] = set()  # (name, digest): a copy of a file read is the same mod, not a rival
    for path, plugin in files:
        loader = registry.mod_loaders.get(path.suffix.lower())
        if loader is None or not path.is_file() or path.resolve() in seen:
            continue
        seen.add(path.resolve())
        copy = (path.name, hashlib.sha256(path.read_bytes()).digest())
        if copy in copies:
            continue  # e.g. a checkout's mods/ beside the same files installed (not editable) as the bundled mods
        copies.add(copy)
        try:
            source = loader.value(path)
        except ProblemsError as exc:
            problems.extend(exc.problems)
            continue
        except Exception as exc:  # the loader's bug: named with its plugin, not a traceback
            problems.append(Problem(display_path(path), None, "", f"the {loader.plugin} plugin's loader failed: {exc!r}"))
            continue
        if not (is_world(source.data) or is_sweep(source.data)):
            add(source, plugin)
    for entry in registry.mods:
        add(entry.value, entry.plugin)

    by_name: dict[str, LoadedMod] = {}
    for mod in loaded:
        other = by_name.get(mod.name)
        if other is not None:
            problems.append(
                mod.source.problem(("mod", "name"), f"mod '{mod.name}' is also defined by {other.source.name}")
            )
            continue
        by_name[mod.name] = mod
    broken -= set(by_name)
    for info, source in headers:
        problems += requirement_problems(info, source, by_name, broken)
    salvaged_broken = tuple(m for m in salvaged if m.mod.name in broken)
    return ModSet(by_name, frozenset(broken), salvaged_broken, dict(registry.behaviours)), problems


#: What stands in for an element with mistakes while the rest of its mod is checked.
STAND_IN = {"archetype": "static", "color": "#000000", "description": "stands in for an element with mistakes"}


@dataclass(frozen=True)
class Salvaged:
    """A mod with mistakes made whole by :func:`salvage`, and where its kept reactions and tests were."""

    mod: LoadedMod
    stood_in: tuple[str, ...]  # the elements stood in for
    was: dict[tuple[str, int], int]  # (table, index now) -> index in the file

    def path_in_file(self, path: str) -> str:
        """A problem's field path as the file numbers its reactions and tests."""
        table, _, rest = path.partition(".")
        number, dot, tail = rest.partition(".")
        if number.isdigit() and (table, int(number)) in self.was:
            return f"{table}.{self.was[(table, int(number))]}{dot}{tail}"
        return path


def salvage(source: TomlSource, plugin: str) -> Salvaged | None:
    """A mod with mistakes, for checking what they do not hide (a reaction naming another mod's
    element, say): each element with a mistake replaced by a stand-in of the same name, each
    reaction or test with one left out. None when its header has a mistake too."""
    data = source.data
    try:
        ModFile.model_validate(data)
        return None
    except ValidationError as exc:
        errors = [tuple(e["loc"]) for e in exc.errors()]
    data = copy.deepcopy(data)
    dropped: dict[str, set[int]] = {"reactions": set(), "tests": set()}
    stood_in: set[str] = set()
    for loc in errors:
        if len(loc) > 1 and loc[0] == "elements" and isinstance(loc[1], str) and isinstance(data.get("elements"), dict):
            data["elements"][loc[1]] = dict(STAND_IN)
            stood_in.add(loc[1])
        elif len(loc) > 1 and loc[0] in dropped and isinstance(loc[1], int):
            dropped[loc[0]].add(loc[1])
        else:
            return None  # the header, or the shape of the file itself
    positions, was = dict(source.positions), {}
    for table, numbers in dropped.items():
        if isinstance(data.get(table), list) and numbers:
            kept = [number for number in range(len(data[table])) if number not in numbers]
            data[table] = [data[table][number] for number in kept]
            was.update({(table, new): old for new, old in enumerate(kept)})
            positions = {k: v for k, v in positions.items() if not (len(k) > 1 and k[0] == table)}
            positions.update({(table, new, *k[2:]): v for new, old in enumerate(kept) for k, v in source.positions.items() if k[:2] == (table, old)})
    try:
        spec = ModFile.model_validate(data)
    except ValidationError:
        return None
    mod = LoadedMod(spec, TomlSource(source.name, source.text, data, positions, source.path, source.folder), plugin)
    return Salvaged(mod, tuple(sorted(stood_in)), was)
