"""``sandmod batch``: sweeps of worlds, seeds and parameters, on a process pool or a Dask cluster."""

from __future__ import annotations

import csv
import filecmp
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from conftest import wait_for
from sandmod.jobs import batch as batching
from sandmod.tools.cli import cli

WORLD = """
[world]
width = 48
height = 40
mods = ["sand"]

[[scene]]
shape = "rect"
element = "stone"
x = 0
y = 36
width = 48
height = 4

[[emitters]]
shape = "rect"
element = "sand"
x = 20
y = 0
width = 6
height = 2
chance = 0.5
stop = 40

[render]
frames = 80
"""

SWEEP = """
[sweep]
worlds = ["*.toml"]
seeds = { from = 0, to = 1 }
frames = 60

[parameters]
"elements.sand.friction" = [0.3, 1.2]
"world.gravity" = [1.0, 0.5]

[record]
format = "gif"
every = 10
snapshots = [30]

[metrics]
frames = [30, 60]
"""


@pytest.fixture
def sweep(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("worlds").mkdir()
    Path("worlds/heap.toml").write_text(WORLD)
    Path("worlds/sweep.toml").write_text(SWEEP.replace('worlds = ["*.toml"]', 'worlds = ["heap*.toml"]'))
    return Path("worlds/sweep.toml")


def table(path: Path) -> list[dict]:
    rows = list(csv.DictReader(path.open()))
    for row in rows:
        row.pop("seconds")
    return rows


def same_files(a: Path, b: Path) -> bool:
    left = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file() and p.name != "row.json")
    right = sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file() and p.name != "row.json")
    return left == right and all(filecmp.cmp(a / p, b / p, shallow=False) for p in left)


def invoke(*args: str):
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


def test_every_combination_is_a_run_with_its_files_and_row(sweep):
    result = invoke("batch", str(sweep), "-o", "out", "-j", "2")
    assert result.exit_code == 0, result.output
    rows = table(Path("out/results.csv"))
    assert len(rows) == 8 and {r["status"] for r in rows} == {"done"}  # 2 seeds x 2 frictions x 2 gravities
    assert {(r["parameter.elements.sand.friction"], r["parameter.world.gravity"]) for r in rows} == {
        ("0.3", "1.0"), ("0.3", "0.5"), ("1.2", "1.0"), ("1.2", "0.5")
    }
    first = Path("out/runs") / rows[0]["id"]
    assert sorted(p.name for p in first.iterdir()) == ["animation.gif", "last.png", "row.json", "snapshot_000030.npz"]
    assert float(rows[0]["count.sand:sand@60"]) > 0 and "awake@30" in rows[0] and "heat@60" in rows[0]
    low = [float(r["centre_y.sand:sand@60"]) for r in rows if r["parameter.elements.sand.friction"] == "0.3"]
    high = [float(r["centre_y.sand:sand@60"]) for r in rows if r["parameter.elements.sand.friction"] == "1.2"]
    assert sum(low) / len(low) > sum(high) / len(high)  # less friction: a flatter heap, its sand lower down
    assert Path("out/contact_sheet.png").stat().st_size > 0


def test_a_dask_cluster_of_two_workers_makes_the_same_table_and_files(sweep):
    pytest.importorskip("dask.distributed")
    assert invoke("batch", str(sweep), "-o", "pool", "-j", "2").exit_code == 0
    result = invoke("batch", str(sweep), "-o", "cluster", "-j", "2", "--executor", "dask")
    assert result.exit_code == 0, result.output
    assert table(Path("pool/results.csv")) == table(Path("cluster/results.csv"))
    assert same_files(Path("pool/runs"), Path("cluster/runs"))


def test_a_batch_killed_half_way_and_resumed_ends_as_one_that_was_not(sweep):
    assert invoke("batch", str(sweep), "-o", "whole", "-j", "1").exit_code == 0
    child = subprocess.Popen([sys.executable, "-m", "sandmod", "batch", str(sweep), "-o", "killed", "-j", "1"], stderr=subprocess.PIPE, text=True)
    runs = Path("killed/runs")
    wait_for(lambda: runs.is_dir() and any(p.name[0] != "." for p in runs.iterdir()), child)
    child.send_signal(signal.SIGKILL)
    child.wait()
    done = [p for p in runs.iterdir() if not p.name.startswith(".")]
    assert 1 <= len(done) < 8 and not Path("killed/results.csv").exists()
    assert all((p / "row.json").exists() for p in done)  # no half-written run: a run's folder appears whole
    result = invoke("batch", str(sweep), "-o", "killed", "-j", "2")
    assert result.exit_code == 2 and "--resume" in result.output
    result = invoke("batch", str(sweep), "-o", "killed", "-j", "2", "--resume")
    assert result.exit_code == 0 and f"({len(done)} done before)" in result.output
    assert table(Path("whole/results.csv")) == table(Path("killed/results.csv"))
    assert same_files(Path("whole/runs"), Path("killed/runs"))
    assert not list(runs.glob(".*"))


def test_a_failing_run_has_its_error_in_its_row(sweep, tmp_path):
    run = batching.read_sweep(sweep, Path("out")).runs[0]
    broken = batching.Run(**{**run.__dict__, "world_path": str(tmp_path / "gone.toml")})
    row = batching.execute(broken)
    assert row["status"] == "failed" and "gone.toml" in row["error"] and not Path(broken.folder).exists()


@pytest.mark.parametrize(
    "change, message",
    [
        (('"elements.sand.friction"', '"elements.sand"'), "parameters: 'elements.sand' is not 'elements.NAME.FIELD'"),
        (("[0.3, 1.2]", "[0.3, -1]"), "friction: must be >= 0"),
        (('"elements.sand.friction"', '"elements.snad.friction"'), "sweep.toml:8:1: parameters.elements.snad.friction: elements.snad.friction: no element of the world's mods (base, glass, sand)"),
        (('worlds = ["heap*.toml"]', 'worlds = ["../heap.toml"]'), "sweep.worlds.0:"),
        (('worlds = ["heap*.toml"]', 'worlds = ["nothing*.toml"]'), "no world file 'nothing*.toml'"),
    ],
)
def test_a_bad_sweep_is_one_line_per_problem_and_exit_2(sweep, change, message):
    sweep.write_text(sweep.read_text().replace(*change))
    result = invoke("batch", str(sweep), "-o", "out")
    assert result.exit_code == 2 and message in result.output and "Traceback" not in result.output
    assert not Path("out").exists()


def test_new_sweep_writes_one_that_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("world.toml").write_text(WORLD)
    assert invoke("new", "sweep", "friction").exit_code == 0
    result = invoke("batch", "friction.toml", "--dry-run")
    assert result.exit_code == 0 and result.output.strip().endswith("12 runs")  # 4 seeds x 3 frictions


def test_metrics_are_the_built_in_ones_and_the_plugins(sweep):
    from sandmod.world.loading import load_world

    world = load_world("worlds/heap.toml").world
    for _ in range(30):
        world.step()
    values = batching.measure(world, None, {"top": lambda w: 3.0, "span": lambda w: {"a": 1, "b": 2.5}})
    assert values["count.sand:sand"] > 0 and values["height.base:stone"] == 4 and values["width.base:stone"] == 48
    assert values["top"] == 3.0 and values["span.a"] == 1.0 and values["span.b"] == 2.5 and "awake" in values and "heat" in values
    assert set(batching.measure(world, ["awake"], {"top": lambda w: 1})) == {"awake"}


def test_a_plugin_registers_a_metric():
    from sandmod import hooks
    from sandmod.registry import collect, make_plugin_manager

    class Plugin:
        @hooks.hookimpl
        def register_metrics(self, register):
            register("top", lambda world: 1.0)

    pm = make_plugin_manager(entry_points=False)
    pm.register(Plugin(), name="metric-plugin")
    registry = collect(pm)
    assert registry.metrics["top"].plugin == "metric-plugin" and registry.metrics["top"].value(None) == 1.0


def test_too_many_runs_is_a_problem(sweep):
    sweep.write_text(sweep.read_text().replace("seeds = { from = 0, to = 1 }", "seeds = { from = 0, to = 99999 }"))
    result = invoke("batch", str(sweep), "-o", "out", "--dry-run")
    assert result.exit_code == 2 and "400000 runs: at most 100000 in one sweep" in result.output
