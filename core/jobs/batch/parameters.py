"""A sweep's parameters applied: ``world.X`` and ``render.X`` to a world file's tables,
``elements.NAME.FIELD`` to the element NAME of whichever loaded mod defines it."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any, Iterable

from ...formats.tomlsource import TomlSource
from ...formats.validation import validate

_RULESETS: dict[str, tuple] = {}  # in each process: (registry, modset, ruleset) by mods and values


def world_source(source: TomlSource, parameters: dict[str, Any]) -> TomlSource:
    """The world file's source with the ``world.X`` and ``render.X`` parameters set."""
    data = copy.deepcopy(source.data)
    for name, value in parameters.items():
        table, _, key = name.partition(".")
        if table in ("world", "render"):
            data.setdefault(table, {})[key] = value
    return TomlSource(source.name, source.text, data, source.positions, source.path, source.folder)


def element_values(parameters: dict[str, Any]) -> dict[str, Any]:
    """The parameters that set an element's field."""
    return {name: value for name, value in parameters.items() if name.startswith("elements.")}


def load_run(world_path: str | Path, parameters: dict[str, Any], mod_dirs: Iterable[str], seed: int | None, max_memory: int | None = None):
    """The world file loaded with the parameters applied (a LoadedWorld)."""
    from ...world.loading import load_world_spec

    spec, source, rules = compile_run(world_path, parameters, mod_dirs)
    return load_world_spec(spec, source, Path(world_path), seed=seed, rules=rules, max_memory=max_memory)


def compile_run(world_path: str | Path, parameters: dict[str, Any], mod_dirs: Iterable[str]):
    """(the world file's spec, its source, its WorldRules) with the parameters applied: what a run
    loads, short of building the world."""
    from ...formats.worldspec import WorldFile
    from ...world.loading import world_rules

    path = Path(world_path)
    source = world_source(TomlSource.read(path), parameters)
    spec = validate(WorldFile, source)
    values = element_values(parameters)
    key = json.dumps([list(mod_dirs), spec.world.mods, values], default=str)
    if key not in _RULESETS:  # a process compiles each set of mods and values once
        _RULESETS[key] = world_rules(spec, source, path, mod_dirs=[Path(d) for d in mod_dirs], change=lambda mods: with_values(mods, values))
    return spec, source, _RULESETS[key]


def target(name: str) -> tuple[str, str, list[str]]:
    """``elements.NAME.FIELD[.FIELD]`` split into the owning mod ('' for any), the element and the fields."""
    _, element, *fields = name.split(".")
    owner, _, own = element.rpartition(":")
    return owner, own, fields


def with_values(mods: list, values: dict[str, Any]) -> list:
    """The loaded mods with the parameters that name their elements set (validated as a file's values
    are). ValueError for a parameter whose element no loaded mod defines."""
    from ...formats.modspec import ModFile
    from ...rules.modset import LoadedMod

    changed, used = [], set()
    for mod in mods:
        data = copy.deepcopy(mod.source.data)
        for name, value in values.items():
            owner, element, fields = target(name)
            table = data.get("elements", {}).get(element)
            if table is None or owner not in ("", mod.name):
                continue
            for parent in fields[:-1]:
                table = table.setdefault(parent, {})
            table[fields[-1]] = value
            used.add(name)
        if data == mod.source.data:
            changed.append(mod)
            continue
        source = TomlSource(mod.source.name, mod.source.text, data, mod.source.positions, mod.source.path, mod.source.folder)
        changed.append(LoadedMod(validate(ModFile, source), source, mod.plugin))
    unused = [name for name in values if name not in used]
    if unused:
        raise ValueError(f"{unused[0]}: no element of the world's mods ({', '.join(m.name for m in mods)}) is called that")
    return changed


def owner_of(name: str, mods: list):
    """The loaded mod whose element the parameter ``name`` sets, or None."""
    owner, element, _ = target(name)
    for mod in mods:
        if element in mod.source.data.get("elements", {}) and owner in ("", mod.name):
            return mod
    return None
