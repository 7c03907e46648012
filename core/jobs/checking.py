"""``sandmod validate``: every problem in every mod, test and world file, in one pass.

Files that fail their schema are reported, and compiled with their broken
elements stood in for, so that what the mistakes would hide is reported too;
the rest are compiled (element references, reaction conflicts, reactions that
never settle), their tests' element names resolved, and the world files loaded.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable

from ..errors import Problem, ProblemsError
from ..formats.limits import DEFAULT_MAX_MEMORY
from ..registry import Registry


@dataclass
class Report:
    """What was checked, and what is wrong."""

    mods: int = 0
    elements: int = 0
    reactions: int = 0
    tests: int = 0
    worlds: int = 0
    problems: list[Problem] = field(default_factory=list)
    warnings: list[Problem] = field(default_factory=list)


def _behind_mistakes(modset) -> list[Problem]:
    """The problems a mod's field mistakes would hide until they are fixed (a reaction naming an
    element of a mod it does not require, say): each such mod compiled with the others, its broken
    parts stood in for (:func:`~sandmod.rules.modset.salvage`); the problems in its other parts."""
    from dataclasses import replace

    from ..rules.compiler import compile_mods
    from ..rules.modset import ModSet

    found: list[Problem] = []
    for salvaged in modset.salvaged:
        mod = salvaged.mod
        try:
            compile_mods(ModSet({**modset.mods, mod.name: mod}).select(None), modset.behaviours)
        except ProblemsError as exc:
            found += [
                replace(p, path=salvaged.path_in_file(p.path))
                for p in exc.problems
                if p.file == mod.source.name and not any(p.path.startswith(f"elements.{name}") for name in salvaged.stood_in)
            ]
    return found


def check(
    registry: Registry,
    folders: Iterable[Path],
    mod_files: Iterable[Path] = (),
    worlds: Iterable[Path] = (),
    world_mod_dirs: Iterable[Path] = (),
    max_memory: int | None = DEFAULT_MAX_MEMORY,
) -> Report:
    """Check the mods in ``folders`` and ``mod_files`` (with the plugins' mods), and the ``worlds``
    (each with the mods beside it and in ``world_mod_dirs``)."""
    from ..rules.compiler import compile_mods
    from ..world.loading import load_world
    from ..rules.modset import discover_mods
    from .modtests import TestRunner

    folders = list(folders)
    report = Report()
    modset, report.problems = discover_mods(registry, folders, mod_files)
    try:
        ruleset = compile_mods(modset.select(None), modset.behaviours)
    except ProblemsError as exc:
        report.problems.extend(exc.problems)
        usable = modset.usable()
        try:  # what does not depend on a broken mod can still be checked
            ruleset = compile_mods(modset.select(usable), modset.behaviours) if usable and len(usable) < len(modset.mods) else None
        except ProblemsError as more:
            report.problems.extend(more.problems)
            ruleset = None
    report.problems += _behind_mistakes(modset)
    if ruleset is not None:
        report.mods, report.elements, report.reactions = len(ruleset.mods), len(ruleset.elements), len(ruleset.reactions)
        report.warnings += ruleset.warnings
        runner = TestRunner(modset)
        for case in runner.cases([m.name for m in ruleset.mods]):
            report.tests += 1
            try:
                runner.check(case)
            except ProblemsError as exc:
                report.problems.extend(exc.problems)
    for world in worlds:
        report.worlds += 1
        try:
            report.warnings += load_world(world, mod_dirs=world_mod_dirs, registry=registry, max_memory=max_memory).warnings
        except ProblemsError as exc:
            report.problems.extend(exc.problems)
    report.problems = list(dict.fromkeys(report.problems))
    return report
