"""Run the interaction tests that mods carry as data (``[[tests]]`` in a mod file).

A test loads its own mod with what that mod requires (and ``base``), paints
its scene, runs the kernel for its frames and checks its expectations. The
same code serves ``sandmod test`` and the pytest plugin::

    runner = TestRunner(find_mods(load_registry(), [Path("mods")]))
    for case in runner.cases():
        outcome = runner.run(case)
        print(case.id, "ok" if outcome.passed else outcome.report())
"""

from __future__ import annotations

import string
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ..rules.compiler import Ruleset, compile_mods
from ..errors import Problem, ProblemsError
from ..rules.modset import LoadedMod, ModSet
from ..formats.modspec import ModTest, Placed


@dataclass(frozen=True)
class TestCase:
    """One test of one mod."""

    __test__ = False  # not a pytest class
    mod: LoadedMod
    number: int  # its place in the mod's [[tests]]
    spec: ModTest

    @property
    def id(self) -> str:
        """``mod:test``, how the test is named everywhere."""
        return f"{self.mod.name}:{self.spec.name}"

    @property
    def loc(self) -> tuple:
        return ("tests", self.number)

    @property
    def file(self) -> str:
        return self.mod.source.name

    @property
    def line(self) -> int | None:
        return self.mod.source.line_of(self.loc)

    def problem(self, field: tuple, message: str) -> Problem:
        return self.mod.source.problem(self.loc + field, message)


@dataclass
class Outcome:
    """What a test found: ``failures`` is empty when it passed."""

    case: TestCase
    failures: list[str] = field(default_factory=list)
    scene: list[str] = field(default_factory=list)
    expected: list[str] | None = None
    actual: list[str] = field(default_factory=list)
    key: dict[str, str] = field(default_factory=dict)  # character -> element id, for every character shown

    @property
    def passed(self) -> bool:
        return not self.failures

    def report(self) -> str:
        """The failure as a mod author reads it: where, the grids side by side, what is wrong."""
        case, spec = self.case, self.case.spec
        where = case.file if case.line is None else f"{case.file}:{case.line}"
        lines = [f"{where}: tests.{case.number} ({case.id}): after {spec.frames} frame{'' if spec.frames == 1 else 's'}, seed {spec.seed}"]
        columns = [("scene", self.scene)] + ([("expected", self.expected)] if self.expected is not None else []) + [("actual", self.actual)]
        widths = [max(len(title), len(rows[0]) if rows else 0) for title, rows in columns]
        lines.append("  " + "   ".join(title.ljust(w) for (title, _), w in zip(columns, widths)).rstrip())
        for y in range(len(self.actual)):
            row = "   ".join(rows[y].ljust(w) for (_, rows), w in zip(columns, widths)).rstrip()
            if self.expected is not None and not _row_matches(self.expected[y], self.actual[y], spec.wildcard):
                row += "  <"
            lines.append("  " + row)
        lines += [f"  {failure}" for failure in self.failures]
        lines.append("  key: " + ", ".join(f"{char} {element}" for char, element in self.key.items()))
        return "\n".join(lines)


def _row_matches(expected: str, actual: str, wildcard: str) -> bool:
    return all(e == wildcard or e == a for e, a in zip(expected, actual))


class TestRunner:
    """Runs the tests of the mods in a :class:`ModSet`, compiling each mod's ruleset once."""

    __test__ = False  # not a pytest class

    def __init__(self, modset: ModSet):
        self.modset = modset
        self._rulesets: dict[str, Ruleset] = {}

    def cases(self, mods: Sequence[str] | None = None) -> list[TestCase]:
        """The tests of the named mods (of every mod when ``None``), in mod then file order."""
        names = sorted(self.modset.mods) if mods is None else list(mods)
        missing = [n for n in names if n not in self.modset.mods]
        if missing:
            found = ", ".join(sorted(self.modset.mods))
            raise ProblemsError([Problem("mods", None, "", f"mod '{n}' was not found (found: {found})") for n in missing])
        return [TestCase(self.modset.mods[n], i, t) for n in names for i, t in enumerate(self.modset.mods[n].spec.tests)]

    def ruleset(self, case: TestCase) -> Ruleset:
        """The test's mod, the mods it asks for, what they require and ``base``, compiled."""
        names = tuple(dict.fromkeys([case.mod.name, *case.spec.mods]))
        if names not in self._rulesets:
            try:
                self._rulesets[names] = compile_mods(self.modset.select(names), self.modset.behaviours)
            except ProblemsError as exc:
                missing = [n for n in case.spec.mods if n not in self.modset.mods]
                if not missing:
                    raise
                raise ProblemsError(
                    [case.problem(("mods", case.spec.mods.index(n)), f"mod '{n}' was not found") for n in missing]
                ) from exc
        return self._rulesets[names]

    def check(self, case: TestCase) -> "_Resolved":
        """Resolve every element the test names; ProblemsError for unknown or ambiguous ones."""
        ruleset = self.ruleset(case)
        problems: list[Problem] = []
        near = [*case.mod.requires, *case.spec.mods]

        def index(ref: str, *field) -> int:
            try:
                return ruleset.index(ref, case.mod.name, near)
            except KeyError as exc:
                problems.append(case.problem(field, exc.args[0]))
                return -1

        spec = case.spec
        legend: dict[str, tuple[int, float | None]] = {}
        for char, entry in spec.full_legend().items():
            if isinstance(entry, Placed):
                legend[char] = (index(entry.element, "legend", char, "element"), entry.temperature)
            else:
                legend[char] = (index(entry, "legend", char) if char in spec.legend else 0, None)
        resolved = _Resolved(
            ruleset,
            legend,
            {index(ref, "count", ref): (ref, count) for ref, count in spec.count.items()},
            [(index(ref, "present", i), ref) for i, ref in enumerate(spec.present)],
            [(index(ref, "absent", i), ref) for i, ref in enumerate(spec.absent)],
            [(index(ref, "temperature", ref), ref, b) for ref, b in spec.temperature.items()],
        )
        if problems:
            raise ProblemsError(problems)
        return resolved

    def run(self, case: TestCase) -> Outcome:
        """Run one test; ProblemsError if it names elements that are not loaded."""
        from ..world.world import World

        spec, r = case.spec, self.check(case)
        rows = spec.rows("scene")
        chars = np.array([list(row) for row in rows])
        world = World(r.ruleset, chars.shape[1], chars.shape[0], spec.seed)
        for char, (element, temperature) in r.legend.items():
            mask = chars == char
            if mask.any():
                world.paint(mask, element)
                if temperature is not None:
                    world.set_temperature(mask, temperature)
        for _ in range(spec.frames):
            world.step()
        return self._judge(case, r, world, rows)

    def _judge(self, case: TestCase, r: "_Resolved", world, scene: list[str]) -> Outcome:
        spec = case.spec
        shown = world.shown()
        names = [e.id for e in r.ruleset.elements]
        char_of = _characters(r.legend, np.unique(shown), r.ruleset, spec.wildcard)
        outcome = Outcome(case, scene=scene, actual=["".join(char_of[int(e)] for e in row) for row in shown])
        outcome.key = {c: names[e] for e, c in sorted(char_of.items(), key=lambda item: item[1] != ".")}
        numbers = np.bincount(shown.ravel(), minlength=len(names))
        if spec.expect is not None:
            outcome.expected = spec.rows("expect")
            wrong = [
                (x, y)
                for y, (want, got) in enumerate(zip(outcome.expected, outcome.actual))
                for x, (e, a) in enumerate(zip(want, got))
                if e != spec.wildcard and e != a
            ]
            if wrong:
                x, y = wrong[0]
                outcome.failures.append(
                    f"{len(wrong)} cell{'s' * (len(wrong) > 1)} differ{'s' * (len(wrong) == 1)} from expect, "
                    f"the first at row {y + 1}, column {x + 1}"
                )
        for element, (ref, count) in r.count.items():
            got = int(numbers[element])
            low, high = (count, count) if isinstance(count, int) else count
            if not low <= got <= high:
                wanted = str(low) if low == high else f"{low} to {high}"
                outcome.failures.append(f"count of {ref}: expected {wanted}, got {got}")
        for element, ref in r.present:
            if numbers[element] == 0:
                outcome.failures.append(f"{ref} should be present, but there is none")
        for element, ref in r.absent:
            if numbers[element]:
                outcome.failures.append(f"{ref} should be absent, but there are {int(numbers[element])} cells")
        if r.temperature:
            celsius = world.temperature()
            for element, ref, bounds in r.temperature:
                found = celsius[shown == element]
                if found.size == 0:
                    outcome.failures.append(f"temperature of {ref}: there is no {ref} to measure")
                    continue
                low, high = float(found.min()), float(found.max())
                if bounds.min is not None and low < bounds.min:
                    outcome.failures.append(f"temperature of {ref}: expected at least {bounds.min:g}, the coldest cell is {low:.1f}")
                if bounds.max is not None and high > bounds.max:
                    outcome.failures.append(f"temperature of {ref}: expected at most {bounds.max:g}, the hottest cell is {high:.1f}")
        return outcome


@dataclass(frozen=True)
class _Resolved:
    """A test's element names as numeric ids of its ruleset."""

    ruleset: Ruleset
    legend: dict[str, tuple[int, float | None]]  # character -> (element, temperature or None)
    count: dict[int, tuple[str, object]]
    present: list[tuple[int, str]]
    absent: list[tuple[int, str]]
    temperature: list[tuple[int, str, object]]


_SPARE = string.ascii_letters + string.digits + "@$%&*+=~^"


def _characters(legend: dict[str, tuple[int, float | None]], shown: np.ndarray, ruleset: Ruleset, wildcard: str) -> dict[int, str]:
    """A character for every element shown: the legend's, else the first free letter of its name."""
    char_of: dict[int, str] = {}
    for char, (element, temperature) in sorted(legend.items(), key=lambda item: item[1][1] is not None):
        char_of.setdefault(element, char)  # plain entries first: 'H' = hot sand shows as the sand's 'S'
    used = set(legend) | {wildcard}
    for element in (int(e) for e in shown):
        if element in char_of:
            continue
        name = ruleset.elements[element].name
        free = [c for c in (name[:1].upper(), name[:1].lower(), *_SPARE) if c not in used]
        char_of[element] = free[0]
        used.add(free[0])
    return char_of
