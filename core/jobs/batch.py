"""``sandmod batch``: the runs of a sweep (:mod:`sandmod.formats.sweepspec`), on a process pool or a
Dask cluster, each written whole into its own folder, and a table of what they measured.

A run is a world file, a seed, a number of frames and a value for each of the sweep's
parameters. Its id hashes all of these, the world file's and every mod's text, and sandmod's
version, so a run already done (its folder is there: a run's folder appears only when the run
is complete) is skipped by ``--resume``, and the same run on any machine, executor or number
of workers makes the same files bit for bit.
"""

from __future__ import annotations

import csv
import glob
import hashlib
import io
import itertools
import json
import math
import os
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

import numpy as np

from .. import __version__
from ..errors import Problem, ProblemsError, display_path
from ..formats.recording import VideoSettings, atomic_path, write_png
from ..formats.sweepspec import MAX_RUNS, SweepFile
from ..formats.tomlsource import TomlSource
from ..formats.userfiles import Refused, inside
from ..formats.validation import validate

RUNS = "runs"
_RULESETS: dict[str, tuple] = {}  # in each worker: (registry, ruleset) by mods and values


@dataclass(frozen=True)
class Run:
    """One run of a sweep: everything a worker needs, and nothing that does not pickle."""

    id: str
    world: str  # the world file, as the sweep names it (relative to the sweep's folder)
    world_path: str
    seed: int
    frames: int | None
    parameters: dict[str, Any]
    record: dict[str, Any]
    metrics: dict[str, Any]
    mod_dirs: tuple[str, ...]
    folder: str  # where its outputs go: OUT/runs/ID


@dataclass
class Sweep:
    """A sweep file read and checked, with its runs planned."""

    path: Path
    spec: SweepFile
    runs: list[Run] = field(default_factory=list)


def read_sweep(path: Path, out: Path, mod_dirs: Iterable[Path] = ()) -> Sweep:
    """Read ``path`` and plan its runs into ``out``. ProblemsError names each mistake, in the file
    or in a world or mod it names (each world is loaded once here, so no run fails for a typo)."""
    from ..world.loading import mod_folders

    source = TomlSource.read(path)
    spec = validate(SweepFile, source)
    sweep = Sweep(Path(path), spec)
    folder = source.folder or Path(".")
    worlds = _worlds(spec, source, folder)
    grid = sorted(spec.parameters.items())
    count = len(worlds) * math.prod(len(values) for _, values in grid) * len(spec.sweep.seed_list())
    if count > MAX_RUNS:
        raise ProblemsError([source.problem(("sweep",), f"{count} runs: at most {MAX_RUNS} in one sweep")])
    combos = list(itertools.product(*(values for _, values in grid)))
    for world_name, world_path in worlds:
        extra = [str(d) for d in mod_folders(mod_dirs, world_path)]
        mods_text = _mods_fingerprint(extra)
        world_text = world_path.read_bytes()
        for combo in combos:
            parameters = {name: value for (name, _), value in zip(grid, combo)}
            _check(world_path, parameters, extra, source)  # raises on a bad path or value
            for seed in spec.sweep.seed_list():
                key = json.dumps([world_text.hex(), mods_text, parameters, seed, spec.sweep.frames, spec.record.model_dump(),
                                  spec.metrics.model_dump(), __version__], sort_keys=True, default=str)
                run_id = hashlib.sha256(key.encode()).hexdigest()[:16]
                sweep.runs.append(Run(run_id, world_name, str(world_path), seed, spec.sweep.frames, parameters,
                                      spec.record.model_dump(), spec.metrics.model_dump(), tuple(extra), str(Path(out) / RUNS / run_id)))
    return sweep


def _worlds(spec: SweepFile, source: TomlSource, folder: Path) -> list[tuple[str, Path]]:
    """The world files the sweep names, globs expanded, each once, confined to the sweep's folder."""
    found: dict[Path, str] = {}
    for number, pattern in enumerate(spec.sweep.worlds):
        try:
            inside(folder, pattern.replace("*", "x").replace("?", "x"), "world")  # no absolute path, no '..'
        except Refused as exc:
            raise ProblemsError([source.problem(("sweep", "worlds", number), str(exc))]) from None
        matches = sorted(glob.glob(str(folder / pattern))) if any(c in pattern for c in "*?[") else [str(folder / pattern)]
        if not matches or not all(Path(m).is_file() for m in matches):
            raise ProblemsError([source.problem(("sweep", "worlds", number), f"no world file {pattern!r} in {display_path(folder)}")])
        for match in matches:
            found.setdefault(Path(match).resolve(), str(Path(match).relative_to(folder)))
    return [(name, path) for path, name in found.items()]


def _mods_fingerprint(mod_dirs: list[str]) -> str:
    """A hash of every mod file's text a run may load."""
    from ..rules.modset import find_mods
    from ..world.loading import load_registry

    modset = find_mods(load_registry(), [Path(d) for d in mod_dirs])
    texts = sorted(m.source.text for m in modset.mods.values())
    return hashlib.sha256("\0".join(texts).encode()).hexdigest()


def _check(world_path: Path, parameters: dict[str, Any], mod_dirs: list[str], sweep_source: TomlSource) -> None:
    """Load the world under the parameters once, so that a wrong path or value is a problem now."""
    try:
        _load(str(world_path), parameters, mod_dirs, None)
    except ProblemsError as error:
        raise ProblemsError([sweep_source.problem(("parameters",), f"{p}") for p in error.problems]) from None
    except ValueError as error:
        raise ProblemsError([sweep_source.problem(("parameters",), str(error))]) from None


# --- one run, in a worker ---------------------------------------------------------------------


def _load(world_path: str, parameters: dict[str, Any], mod_dirs: Iterable[str], seed: int | None):
    """The world file loaded with the parameters applied: 'world.X' and 'render.X' to its tables,
    'elements.NAME.FIELD' to the element NAME of whichever mod defines it."""
    from ..formats.worldspec import WorldFile
    from ..world.loading import load_world_spec, world_rules

    path = Path(world_path)
    source = TomlSource.read(path)
    data = json.loads(json.dumps(source.data))  # a deep copy
    for name, value in parameters.items():
        table, _, key = name.partition(".")
        if table in ("world", "render"):
            data.setdefault(table, {})[key] = value
    source = TomlSource(source.name, source.text, data, source.positions, source.path, source.folder)
    spec = validate(WorldFile, source)
    values = {name: value for name, value in parameters.items() if name.startswith("elements.")}
    key = json.dumps([list(mod_dirs), spec.world.mods, values], default=str)
    if key not in _RULESETS:  # a worker compiles each set of mods and values once
        dirs = [Path(d) for d in mod_dirs]
        _RULESETS[key] = world_rules(spec, source, path, mod_dirs=dirs, change=lambda mods: _with_values(mods, values))
    return load_world_spec(spec, source, path, seed=seed, rules=_RULESETS[key])


def _with_values(mods: list, values: dict[str, Any]) -> list:
    """The loaded mods with the parameters that name their elements set (validated as a file's values
    are). ProblemsError for a parameter whose element no loaded mod defines."""
    from ..formats.modspec import ModFile
    from ..rules.modset import LoadedMod

    changed, used = [], set()
    for mod in mods:
        data = json.loads(json.dumps(mod.source.data))
        for name, value in values.items():
            _, element, *fields = name.split(".")  # elements.NAME.FIELD[.FIELD]; NAME may be 'mod:name'
            owner, _, own = element.rpartition(":")
            table = data.get("elements", {}).get(own)
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


def measure(world, names: list[str] | None, plugins: dict[str, Callable]) -> dict[str, float]:
    """The built-in metrics and the plugins', of a world as it is now: ``counts`` (cells of each
    element), ``centre`` (each element's centre of mass), ``extent`` (the rows and columns each
    element spans: a heap's height and width), ``awake`` (the share of chunks awake), ``heat``
    (the total heat energy)."""
    values: dict[str, float] = {}
    wanted = (lambda name: names is None or name in names)
    cells = world.cells
    if wanted("counts") or wanted("centre") or wanted("extent"):
        ids = np.bincount(cells.ravel(), minlength=len(world.ruleset.elements))
        ys, xs = np.indices(cells.shape)
        for element, count in enumerate(ids):
            if element == 0 or count == 0:
                continue
            name = world.ruleset.elements[element].id
            if wanted("counts"):
                values[f"count.{name}"] = float(count)
            mask = cells == element
            if wanted("centre"):
                values[f"centre_x.{name}"] = round(float(xs[mask].mean()), 6)
                values[f"centre_y.{name}"] = round(float(ys[mask].mean()), 6)
            if wanted("extent"):
                rows, columns = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
                values[f"height.{name}"] = float(rows[-1] - rows[0] + 1)
                values[f"width.{name}"] = float(columns[-1] - columns[0] + 1)
    if wanted("awake"):
        values["awake"] = round(world.awake_fraction, 6)
    if wanted("heat"):
        values["heat"] = float(world.heat_total())
    for name, function in sorted(plugins.items()):
        if wanted(name):
            result = function(world)
            if isinstance(result, dict):
                values.update({f"{name}.{key}": float(v) for key, v in result.items()})
            else:
                values[name] = float(result)
    return values


def execute(run: Run) -> dict[str, Any]:
    """Do one run and return its row; its files go into a temporary folder, renamed into place
    (``run.folder``) only when all of them are written. A failure is the row's ``error``."""
    began = time.perf_counter()
    folder = Path(run.folder)
    work = folder.parent / f".{folder.name}.{os.getpid()}.part"
    row: dict[str, Any] = {"id": run.id, "world": run.world, "seed": run.seed, **{f"parameter.{k}": v for k, v in run.parameters.items()}}
    try:
        shutil.rmtree(work, ignore_errors=True)
        work.mkdir(parents=True)
        row.update(_simulate(run, work))
        row["status"], row["error"] = "done", ""
    except Exception as error:  # a run's failure is its row's, and the others go on
        shutil.rmtree(work, ignore_errors=True)
        row.update(status="failed", error=str(error.problems[0]) if isinstance(error, ProblemsError) else f"{type(error).__name__}: {error}")
        row["seconds"] = round(time.perf_counter() - began, 3)
        return row
    row["seconds"] = round(time.perf_counter() - began, 3)
    (work / "row.json").write_text(json.dumps(row, sort_keys=True), encoding="utf-8")
    shutil.rmtree(folder, ignore_errors=True)  # a run that was done again
    os.replace(work, folder)
    return row


def _simulate(run: Run, work: Path) -> dict[str, Any]:
    loaded = _load(run.world_path, run.parameters, run.mod_dirs, run.seed)
    world, render = loaded.world, loaded.spec.render
    world.threads = 1
    frames = run.frames or render.frames
    measure_at = sorted(set(run.metrics["frames"] or [frames]))
    snapshots = sorted(set(run.record["snapshots"]))
    recorder, every, scale = _recorder(loaded, run, work)
    plugins = {name: entry.value for name, entry in loaded.registry.metrics.items()}
    row: dict[str, Any] = {"frames": frames}
    outputs = []
    for frame in range(frames + 1):
        if frame in measure_at:
            row.update({f"{name}@{frame}": value for name, value in measure(world, run.metrics["names"], plugins).items()})
        if frame in snapshots:
            world.save_snapshot(work / f"snapshot_{frame:06d}.npz")
            outputs.append(f"snapshot_{frame:06d}.npz")
        if recorder is not None and frame % every == 0:
            recorder.add_frame(_scaled(world.image(), scale))
        if frame < frames:
            world.step()
    if recorder is not None:
        recorder.close()
        outputs.append(f"animation.{run.record['format']}")
    write_png(work / "last.png", world.image(), world.ruleset.palette)
    outputs.append("last.png")
    row["outputs"] = ";".join(outputs)
    return row


def _scaled(frame: np.ndarray, scale: int) -> np.ndarray:
    from ..world.world import enlarge

    return enlarge(frame, scale)


def _recorder(loaded, run: Run, work: Path):
    """The run's animation recorder (None for 'none'), its frames per image and its scale."""
    name = run.record["format"]
    if name == "none":
        return None, 1, 1
    entry = loaded.registry.recorders.get(name)
    if entry is None:
        raise ProblemsError([Problem("sweep", None, "record.format", f"unknown format {name!r} (known: {loaded.registry.recorder_choices()}, none)")])
    spec, render = entry.value, loaded.spec.render
    every, scale = run.record["every"] or render.every, run.record["scale"] or render.scale
    world = loaded.world
    settings = VideoSettings(world.width * scale, world.height * scale, world.ruleset.palette, render.fps, render.loop)
    return spec.open(work / f"animation.{name}", settings), every, scale


# --- many runs --------------------------------------------------------------------------------


def _worker_start() -> None:
    """A worker process: one numba thread (the workers are the parallelism; each run steps on one
    thread in any case), and on Linux gone with the batch (a batch killed outright must not leave
    workers writing into its folder)."""
    if "numba" not in sys.modules:  # a fresh interpreter; a forked one keeps numba's settings as they are
        os.environ["NUMBA_NUM_THREADS"] = "1"
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        PR_SET_PDEATHSIG = 1
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)


def done_row(run: Run) -> dict[str, Any] | None:
    """The row of a run whose folder is complete, or None."""
    try:
        return json.loads((Path(run.folder) / "row.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def run_all(runs: list[Run], executor: str, jobs: int, scheduler: str | None) -> Iterator[dict[str, Any]]:
    """Each run's row as it finishes, on ``jobs`` worker processes or a Dask cluster."""
    if not runs:
        return
    if executor == "dask":
        yield from _on_dask(runs, jobs, scheduler)
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    # Linux: forked workers start at once with what this process loaded (it has started no threads:
    # it never steps a world); elsewhere each starts a fresh interpreter.
    context = multiprocessing.get_context("fork" if sys.platform.startswith("linux") else "spawn")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context, initializer=_worker_start) as pool:
        futures = [pool.submit(execute, run) for run in runs]
        try:
            for future in as_completed(futures):
                yield future.result()
        except BaseException:
            for future in futures:
                future.cancel()
            raise


def _on_dask(runs: list[Run], jobs: int, scheduler: str | None) -> Iterator[dict[str, Any]]:
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise ProblemsError([Problem("batch", None, "", 'the dask executor needs dask: pip install "sandmod[dask]"')]) from None
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None,
                               env={"NUMBA_NUM_THREADS": "1"})
    client = Client(cluster if cluster is not None else scheduler)
    try:
        client.run(_warm)  # each worker loads its kernels from the cache once
        futures = [client.submit(execute, run, pure=False, key=f"sandmod-run-{run.id}") for run in runs]
        for future in as_completed(futures):
            yield future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _warm() -> None:
    from .warmup import compile_kernels

    compile_kernels()


def write_table(rows: list[dict[str, Any]], out: Path) -> list[Path]:
    """results.csv (and results.parquet where pyarrow is installed), whole or not at all."""
    columns = ["id", "world", "seed", "frames", "status", "error", "seconds", "outputs"]
    parameters = sorted({k for row in rows for k in row if k.startswith("parameter.")})
    metrics = sorted({k for row in rows for k in row if "@" in k}, key=lambda k: (int(k.split("@")[1]), k))
    header = columns[:3] + parameters + columns[3:] + metrics
    text = io.StringIO()
    writer = csv.DictWriter(text, header, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    written = [out / "results.csv"]
    with atomic_path(written[0]) as temporary:
        temporary.write_text(text.getvalue(), encoding="utf-8")
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    table = pa.Table.from_pylist([{k: row.get(k) for k in header} for row in rows])
    written.append(out / "results.parquet")
    with atomic_path(written[1]) as temporary:
        pq.write_table(table, temporary)
    return written


def contact_sheet(rows: list[dict[str, Any]], runs: list[Run], out: Path) -> Path | None:
    """One PNG of every done run's last frame, in a grid, each labelled with its parameters and seed."""
    from PIL import Image, ImageDraw

    by_id = {run.id: run for run in runs}
    done = [row for row in rows if row.get("status") == "done"]
    if not done:
        return None
    images = [Image.open(Path(by_id[row["id"]].folder) / "last.png").convert("RGB") for row in done]
    width = max(i.width for i in images)
    height = max(i.height for i in images)
    scale = max(1, 240 // max(width, height))
    label = 14 * (1 + max(len(by_id[row["id"]].parameters) for row in done))
    columns = math.ceil(math.sqrt(len(done)))
    rows_count = math.ceil(len(done) / columns)
    cell_w, cell_h = width * scale + 8, height * scale + label + 8
    sheet = Image.new("RGB", (columns * cell_w, rows_count * cell_h), (24, 24, 28))
    draw = ImageDraw.Draw(sheet)
    for number, (row, image) in enumerate(zip(done, images)):
        x, y = (number % columns) * cell_w + 4, (number // columns) * cell_h + 4
        sheet.paste(image.resize((image.width * scale, image.height * scale), Image.NEAREST), (x, y))
        run = by_id[row["id"]]
        lines = [f"{run.world} seed {run.seed}"] + [f"{k.split('.', 1)[1] if k.startswith('elements.') else k} = {v}" for k, v in run.parameters.items()]
        for line_number, line in enumerate(lines):
            draw.text((x, y + height * scale + 2 + 14 * line_number), line, fill=(220, 220, 220))
    path = out / "contact_sheet.png"
    with atomic_path(path) as temporary:
        sheet.save(temporary, "PNG")
    return path

