"""One run of a sweep, in a worker: simulate, measure, record, and write its folder whole."""

from __future__ import annotations

import json
import os
import shutil
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...errors import Problem, ProblemsError
from ...formats.recording import VideoSettings, atomic_path, write_png
from .metrics import measure
from .parameters import load_run

RUNS = "runs"
LOGS = "logs"


@dataclass(frozen=True)
class Run:
    """One run of a sweep: everything a worker needs, and nothing that does not pickle."""

    id: str
    world: str  # the world file, as the sweep names it (relative to the sweep's folder)
    world_path: str
    seed: int
    frames: int
    parameters: dict[str, Any]
    record: dict[str, Any]
    metrics: dict[str, Any]
    mod_dirs: tuple[str, ...]
    out: str  # the batch's output folder, absolute

    @property
    def folder(self) -> Path:
        """Where its outputs go: OUT/runs/ID, there only once all are written."""
        return Path(self.out) / RUNS / self.id

    @property
    def log(self) -> Path:
        """Its log: OUT/logs/ID.log."""
        return Path(self.out) / LOGS / f"{self.id}.log"

    def describe(self) -> str:
        """'heap.toml seed 3 elements.sand.friction = 0.4'."""
        values = "".join(f" {k} = {v}" for k, v in self.parameters.items())
        return f"{self.world} seed {self.seed}{values}"


def execute(run: Run) -> dict[str, Any]:
    """Do one run and return its row; its files go into a temporary folder, renamed into place
    (``run.folder``) only when all of them are written. A failure is the row's ``error``, and its
    traceback is in the run's log."""
    began = time.perf_counter()
    work = run.folder.parent / f".{run.id}.{os.getpid()}.part"
    row: dict[str, Any] = {"id": run.id, "world": run.world, "seed": run.seed, **{f"parameter.{k}": v for k, v in run.parameters.items()}}
    details = ""
    try:
        shutil.rmtree(work, ignore_errors=True)
        work.mkdir(parents=True)
        row.update(_simulate(run, work))
        row["status"], row["error"] = "done", ""
    except BaseException as error:  # a run's failure is its row's, and the others go on
        shutil.rmtree(work, ignore_errors=True)
        if not isinstance(error, Exception):
            raise  # interrupted: the batch ends, and leaves nothing half-written
        row.update(status="failed", error=str(error.problems[0]) if isinstance(error, ProblemsError) else f"{type(error).__name__}: {error}")
        details = "".join(traceback.format_exception(error))
    row["seconds"] = round(time.perf_counter() - began, 3)
    _write_log(run, row, details)
    if row["status"] == "done":
        (work / "row.json").write_text(json.dumps(row, sort_keys=True), encoding="utf-8")
        _replace(work, run.folder)
    return row


def _replace(work: Path, folder: Path) -> None:
    """Put the finished ``work`` folder at ``folder``, over a run done before (never through a link)."""
    if folder.is_symlink() or folder.is_file():
        folder.unlink()
    elif folder.exists():
        shutil.rmtree(folder)
    os.replace(work, folder)


def _write_log(run: Run, row: dict[str, Any], details: str) -> None:
    lines = [f"run {run.id}: {run.describe()}", f"{row['status']} in {row['seconds']} s"]
    if row["error"]:
        lines += [f"error: {row['error']}", "", details]
    run.log.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(run.log) as temporary:
        temporary.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _simulate(run: Run, work: Path) -> dict[str, Any]:
    loaded = load_run(run.world_path, run.parameters, run.mod_dirs, run.seed)
    world = loaded.world
    world.threads = 1
    measure_at = set(run.metrics["frames"] or [run.frames])
    snapshots = set(run.record["snapshots"])
    recorder, every, scale = _recorder(loaded, run, work)
    plugins = {name: entry.value for name, entry in loaded.registry.metrics.items()}
    row: dict[str, Any] = {"frames": run.frames}
    outputs = []
    for frame in range(run.frames + 1):
        if frame in measure_at:
            row.update({f"{name}@{frame}": value for name, value in measure(world, run.metrics["names"], plugins).items()})
        if frame in snapshots:
            world.save_snapshot(work / f"snapshot_{frame:06d}.npz")
            outputs.append(f"snapshot_{frame:06d}.npz")
        if recorder is not None and frame % every == 0:
            recorder.add_frame(_scaled(world.image(), scale))
        if frame < run.frames:
            world.step()
    if recorder is not None:
        recorder.close()
        outputs.append(f"animation.{run.record['format']}")
    write_png(work / "last.png", world.image(), world.ruleset.colours)
    outputs.append("last.png")
    row["outputs"] = ";".join(outputs)
    return row


def _scaled(frame, scale: int):
    from ...world.world import enlarge

    return enlarge(frame, scale)


def recording(loaded, record: dict[str, Any]):
    """(the recorder spec, frames per image, scale) a run records with; (None, 1, 1) for 'none'."""
    name = record["format"]
    if name == "none":
        return None, 1, 1
    entry = loaded.registry.recorders.get(name)
    if entry is None:
        raise ProblemsError([Problem("sweep", None, "record.format", f"unknown format {name!r}")])
    render = loaded.spec.render
    return entry.value, record["every"] or render.every, record["scale"] or render.scale


def _recorder(loaded, run: Run, work: Path):
    spec, every, scale = recording(loaded, run.record)
    if spec is None:
        return None, 1, 1
    world, render = loaded.world, loaded.spec.render
    settings = VideoSettings(world.width * scale, world.height * scale, world.ruleset.colours, render.fps, render.loop)
    return spec.open(work / f"animation.{run.record['format']}", settings), every, scale
