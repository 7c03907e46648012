"""A sweep file read, checked and planned into runs, before any runs.

Every mistake is found here, each a problem naming the line of the sweep file (or of the world or
mod it names): an unknown metric or format, a frame past a world's last, a parameter that would not
take effect or whose value its field refuses, an output too large for its format or for the memory
allowed. Checking is quick: each world is loaded once for each combination of its own parameters,
and element values are checked against the element's model, one combination at a time.
"""

from __future__ import annotations

import copy
import difflib
import glob
import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

from pydantic import TypeAdapter, ValidationError

from ... import __version__
from ...errors import Problem, ProblemsError, display_path
from ...formats.limits import DEFAULT_MAX_MEMORY, size_text
from ...formats.sweepspec import MAX_RUNS, SweepFile
from ...formats.tomlsource import TomlSource
from ...formats.userfiles import Refused, inside
from ...formats.validation import validate
from .metrics import BUILT_IN
from .parameters import compile_run, load_run, owner_of, target, with_values
from .run import Run, recording


@dataclass
class Sweep:
    """A sweep file read and checked, with its runs planned."""

    path: Path
    spec: SweepFile
    runs: list[Run] = field(default_factory=list)
    memory_per_run: int = 0  # the most any run is estimated to take, in bytes


def read_sweep(path: Path, out: Path, mod_dirs: Iterable[Path] = (), *, jobs: int = 1, max_memory: int | None = DEFAULT_MAX_MEMORY) -> Sweep:
    """Read ``path`` and plan its runs into ``out``. ProblemsError names every mistake found, in the
    file or in a world or mod it names. ``jobs`` runs at a time must fit in ``max_memory`` bytes."""
    from ...world.loading import load_registry

    source = TomlSource.read(path)
    spec = validate(SweepFile, source)
    registry = load_registry()
    problems = [*_metric_problems(spec, source, registry), *_format_problems(spec, source, registry), *_effect_problems(spec, source)]
    worlds = _worlds(spec, source, source.folder or Path("."))
    seeds = spec.sweep.seed_list()
    count = len(worlds) * math.prod(len(values) for values in spec.parameters.values()) * len(seeds)
    if count > MAX_RUNS:
        problems.append(source.problem(("sweep",), f"{count} runs: at most {MAX_RUNS} in one sweep"))
    if problems:
        raise ProblemsError(problems)
    sweep = Sweep(Path(path), spec)
    for name, world_path in worlds:
        planner = _WorldPlanner(spec, source, name, world_path, mod_dirs, Path(out).absolute(), max_memory)
        problems += planner.check()
        if not problems:
            sweep.runs += planner.runs(seeds)
            sweep.memory_per_run = max(sweep.memory_per_run, planner.memory)
    if not problems:
        problems += _memory_problems(sweep, source, jobs, max_memory)
    if problems:
        raise ProblemsError(problems)
    return sweep


def _metric_problems(spec: SweepFile, source: TomlSource, registry) -> list[Problem]:
    known = [*BUILT_IN, *sorted(registry.metrics)]
    return [
        source.problem(("metrics", "names", number), f"unknown metric {name!r}{_did_you_mean(name, known)} (known: {', '.join(known)})")
        for number, name in enumerate(spec.metrics.names or [])
        if name not in known
    ]


def _format_problems(spec: SweepFile, source: TomlSource, registry) -> list[Problem]:
    name = spec.record.format
    if name == "none" or name in registry.recorders:
        return []
    known = [*sorted(registry.recorders), "none"]
    return [source.problem(("record", "format"), f"unknown format {name!r}{_did_you_mean(name, known)} (known: {', '.join(known)})")]


def _did_you_mean(name: str, known: list[str]) -> str:
    close = difflib.get_close_matches(name.split(".")[0] if "." in name else name, known, n=1, cutoff=0.5)
    return f" (did you mean {close[0]!r}?)" if close else ""


#: render.X parameters that take effect only when [record] leaves them to the world.
_RECORD_OVERRIDES = {"render.every": "every", "render.scale": "scale"}
#: render.X parameters a batch run reads at all (the others are render's command line defaults).
_RENDER_READ = {"render.frames", "render.every", "render.scale", "render.fps", "render.loop"}


def _effect_problems(spec: SweepFile, source: TomlSource) -> list[Problem]:
    """Parameters that would label rows with values that change nothing."""
    problems = []
    for name in spec.parameters:
        why = None
        if name == "world.seed":
            why = "the seeds of [sweep] set each run's seed: list them there"
        elif name == "render.frames" and spec.sweep.frames is not None:
            why = "[sweep] frames sets every run's frames"
        elif name.startswith("render.") and name not in _RENDER_READ:
            why = "a batch run does not use it (it records with [record])"
        elif name.startswith("render.") and name != "render.frames" and spec.record.format == "none":
            why = "nothing is recorded ([record] format is 'none')"
        elif name in _RECORD_OVERRIDES and getattr(spec.record, _RECORD_OVERRIDES[name]) is not None:
            why = f"[record] {_RECORD_OVERRIDES[name]} sets it for every run"
        if why:
            problems.append(source.problem(("parameters", name), f"{name} would not take effect: {why}"))
    return problems


def _worlds(spec: SweepFile, source: TomlSource, folder: Path) -> list[tuple[str, Path]]:
    """The world files the sweep names, globs expanded, each once, confined to the sweep's folder
    (a link out of it is refused, as is a glob's match through one)."""
    found: dict[str, Path] = {}
    for number, pattern in enumerate(spec.sweep.worlds):
        where = ("sweep", "worlds", number)
        try:
            inside(folder, pattern.replace("*", "x").replace("?", "x").replace("[", "x"), "world")  # no absolute path, no '..'
        except Refused as exc:
            raise ProblemsError([source.problem(where, str(exc))]) from None
        pattern_like = any(c in pattern for c in "*?[")
        matches = sorted(glob.glob(glob.escape(str(folder)) + "/" + pattern)) if pattern_like else [str(folder / pattern)]
        if pattern_like:  # a glob's matches that are not worlds (the sweep itself, say) are not meant
            matches = [m for m in matches if Path(m).is_file() and _is_world(Path(m))]
        if not matches or not all(Path(m).is_file() for m in matches):
            raise ProblemsError([source.problem(where, f"no world file {pattern!r} in {display_path(folder)}")])
        for match in matches:
            name = str(Path(match).relative_to(folder))
            try:
                inside(folder, name, "world")
            except Refused as exc:
                raise ProblemsError([source.problem(where, f"{name}: {exc}")]) from None
            found.setdefault(name, Path(match))
    return list(found.items())


def _is_world(path: Path) -> bool:
    """Whether ``path`` reads as TOML with a [world] table (a file that does not read is one: its
    problems are then reported when it is loaded)."""
    from ...rules.modset import is_world

    try:
        return is_world(TomlSource.read(path).data)
    except ProblemsError:
        return True


class _WorldPlanner:
    """The runs of one world of a sweep, and what is wrong with them."""

    def __init__(self, spec: SweepFile, source: TomlSource, name: str, path: Path, mod_dirs: Iterable[Path], out: Path,
                 max_memory: int | None) -> None:
        from ...world.loading import mod_folders

        self.spec, self.source, self.name, self.path, self.out = spec, source, name, path, out
        self.max_memory = max_memory
        self.mod_dirs = tuple(str(d) for d in mod_folders(mod_dirs, path))
        grid = sorted(spec.parameters.items())
        self.world_grid = [(k, v) for k, v in grid if not k.startswith("elements.")]
        self.element_grid = [(k, v) for k, v in grid if k.startswith("elements.")]
        self.frames: dict[str, int] = {}  # by the world parameters' combination
        self.memory = 0

    def check(self) -> list[Problem]:
        """Load the world under each combination of its own parameters, check the element values,
        the frames and what recording needs. The problems found."""
        problems: list[Problem] = []
        for combo in itertools.product(*(values for _, values in self.world_grid)):
            parameters = dict(zip((k for k, _ in self.world_grid), combo))
            problems += self._check_world(parameters)
            if problems:
                return problems
        return self._check_elements()

    def _check_world(self, parameters: dict[str, Any]) -> list[Problem]:
        try:
            loaded = load_run(self.path, parameters, self.mod_dirs, None, max_memory=self.max_memory)
        except (ProblemsError, ValueError) as error:
            return self._blame(parameters, error)
        self.mods, self.text = list(loaded.ruleset.mods), loaded.source.text  # not the world: one at a time in memory
        problems = self._typed(parameters, lambda name: _field(loaded.spec, name.split(".")))
        frames = self.spec.sweep.frames or loaded.spec.render.frames
        self.frames[_key(parameters)] = frames
        problems += self._frame_problems(frames, parameters)
        problems += self._record_problems(loaded, frames, parameters)
        return problems

    def _blame(self, parameters: dict[str, Any], error: Exception) -> list[Problem]:
        """A world that does not load (under ``parameters``): the world's own problems, or the
        sweep's parameters' when they are the cause."""
        found = error.problems if isinstance(error, ProblemsError) else [str(error)]
        if not parameters and isinstance(error, ProblemsError):
            return list(found)
        where = ("parameters", next(iter(parameters))) if parameters else ("parameters",)
        values = ", ".join(f"{k} = {v!r}" for k, v in parameters.items())
        return [self.source.problem(where, f"{values}: {p}" if values else f"{p}") for p in found]

    def _frame_problems(self, frames: int, parameters: dict[str, Any]) -> list[Problem]:
        under = f" (with {', '.join(f'{k} = {v!r}' for k, v in parameters.items())})" if parameters else ""
        return [
            self.source.problem((table, field_name, number), f"frame {frame} is past the last frame of {self.name}, {frames}{under}")
            for table, field_name, frames_listed in (("metrics", "frames", self.spec.metrics.frames), ("record", "snapshots", self.spec.record.snapshots))
            for number, frame in enumerate(frames_listed)
            if frame > frames
        ]

    def _record_problems(self, loaded, frames: int, parameters: dict[str, Any]) -> list[Problem]:
        """Images too wide for the format; and the memory a run takes (the world, and the images a
        format keeps until it closes), for the check against --max-memory."""
        from ..render import Framing, kept_bytes, side_problem

        recorder, every, scale = recording(loaded, self.spec.record.model_dump())
        estimate = loaded.memory.used
        if recorder is not None:
            framing = Framing(scale)
            refused = side_problem(recorder, loaded.world, framing)
            if refused:
                return [self.source.problem(("record", "format"), f"{self.name}: {refused}")]
            estimate += kept_bytes(recorder, loaded.world, framing, frames, every)[1]
        self.memory = max(self.memory, estimate)
        return []

    def _typed(self, parameters: dict[str, Any], read) -> list[Problem]:
        """A true or false given where the field is not one (it would be read as 1 or 0)."""
        problems = []
        for name, value in parameters.items():
            if isinstance(value, bool) and not isinstance(read(name), bool):
                problems.append(self.source.problem(("parameters", name), f"{str(value).lower()} is not a value for {name} (a {type(read(name)).__name__})"))
        return problems

    def _check_elements(self) -> list[Problem]:
        """Each combination of each element's parameters against the element's model (a slow,
        whole-mod validation only to word a refusal), and each value that names something compiled."""
        mods = self.mods
        problems, groups = [], {}
        for name, values in self.element_grid:
            mod = owner_of(name, mods)
            if mod is None:
                names = ", ".join(m.name for m in mods)
                problems.append(self.source.problem(("parameters", name), f"{name}: no element of the world's mods ({names}) is called that"))
                continue
            groups.setdefault((mod.name, target(name)[1]), (mod, []))[1].append((name, values))
        for (mod_name, element), (mod, grid) in groups.items():
            problems += self._check_group(mod, element, grid)
        if not problems and self.element_grid:
            problems += self._compile_named()
        return problems

    def _check_group(self, mod, element: str, grid: list[tuple[str, list]]) -> list[Problem]:
        from ...formats.modspec import Element

        adapter = TypeAdapter(Element)
        base = mod.source.data["elements"][element]
        for combo in itertools.product(*(values for _, values in grid)):
            table = copy.deepcopy(base)
            for (name, _), value in zip(grid, combo):
                _set(table, target(name)[2], value)
            try:
                model = adapter.validate_python(table)
            except ValidationError:
                return self._worded(mod, dict(zip((n for n, _ in grid), combo)))
            values = dict(zip((n for n, _ in grid), combo))
            typed = self._typed(values, lambda name: _field(model, target(name)[2]))
            if typed:
                return typed
        return []

    def _worded(self, mod, values: dict[str, Any]) -> list[Problem]:
        """The problems a whole-mod validation finds with ``values``, at the sweep's lines."""
        try:
            with_values([mod], values)
        except ProblemsError as error:
            others = len(values) > 1
            return [
                self.source.problem(("parameters", name), p.message + (
                    f" (with {', '.join(f'{k} = {v!r}' for k, v in values.items() if k != name)})" if others else ""))
                for p in error.problems
                for name in [next((n for n in values if p.path.endswith(".".join(target(n)[2]))), next(iter(values)))]
            ]
        return [self.source.problem(("parameters", next(iter(values))), f"{values} is refused by {mod.name}'s element")]

    def _compile_named(self) -> list[Problem]:
        """Compile the mods with the first combination, and with each text value (an element a
        field names, say), which only the compiler can check; numbers are checked by the model above."""
        first = {name: values[0] for name, values in self.element_grid}
        tries = [first] + [{**first, name: value} for name, values in self.element_grid for value in values[1:] if isinstance(value, str)]
        for values in tries:
            try:
                compile_run(self.path, values, self.mod_dirs)
            except (ProblemsError, ValueError) as error:
                return self._blame(values, error)
        return []

    def runs(self, seeds: list[int]) -> list[Run]:
        """Every run of this world: each combination of the parameters, with each seed."""
        grid = sorted(self.spec.parameters.items())
        record, metrics = self.spec.record.model_dump(), self.spec.metrics.model_dump()
        fixed = json.dumps([self.name, hashlib.sha256(self.text.encode()).hexdigest(), _mods_fingerprint(self.mods),
                            self.spec.record.model_dump_json(), self.spec.metrics.model_dump_json(), __version__])
        runs = []
        for combo in itertools.product(*(values for _, values in grid)):
            parameters = dict(zip((k for k, _ in grid), combo))
            frames = self.frames[_key({k: v for k, v in parameters.items() if not k.startswith("elements.")})]
            for seed in seeds:
                key = json.dumps([fixed, parameters, seed, frames], sort_keys=True)
                run_id = hashlib.sha256(key.encode()).hexdigest()[:16]
                runs.append(Run(run_id, self.name, str(self.path), seed, frames, parameters, record, metrics, self.mod_dirs, str(self.out)))
        return runs


def _key(parameters: dict[str, Any]) -> str:
    return json.dumps(parameters, sort_keys=True)


def _set(table: dict, fields: list[str], value: Any) -> None:
    for parent in fields[:-1]:
        table = table.setdefault(parent, {})
    table[fields[-1]] = value


def _field(model: Any, fields: list[str]) -> Any:
    for part in fields:
        model = getattr(model, part, None)
    return model


def _mods_fingerprint(mods: list) -> str:
    """A hash of the text of every mod a world loads."""
    texts = sorted(m.source.text for m in mods)
    return hashlib.sha256("\0".join(texts).encode()).hexdigest()


def _memory_problems(sweep: Sweep, source: TomlSource, jobs: int, max_memory: int | None) -> list[Problem]:
    at_once = max(1, min(jobs, len(sweep.runs)))
    total = sweep.memory_per_run * at_once
    if max_memory is None or total <= max_memory:
        return []
    return [source.problem(("sweep",), (
        f"{at_once} runs at a time, each taking up to about {size_text(sweep.memory_per_run)}, would take {size_text(total)}: "
        f"more than the limit of {size_text(max_memory)} (raise it with --max-memory, or fewer -j)"))]
