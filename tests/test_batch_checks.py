"""``sandmod batch``: every mistake in a sweep refused before any run, and what the tables say."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import pytest

from sandmod.jobs import batch as batching
from test_batch import SWEEP, WORLD, invoke


@pytest.fixture
def sweep(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("worlds").mkdir()
    Path("worlds/heap.toml").write_text(WORLD)
    Path("worlds/sweep.toml").write_text(SWEEP.replace('worlds = ["*.toml"]', 'worlds = ["heap.toml"]').replace("seeds = { from = 0, to = 1 }", "seeds = [0, 1]"))
    return Path("worlds/sweep.toml")


def edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))


@pytest.mark.parametrize(
    "old, new, message",
    [
        ("frames = [30, 60]", 'frames = [30, 60]\nnames = ["countz"]', "sweep.toml:18:1: metrics.names.0: unknown metric 'countz' (did you mean 'counts'?)"),
        ("frames = [30, 60]", 'frames = [30, 60]\nnames = ["count.sand"]', "unknown metric 'count.sand' (did you mean 'counts'?)"),
        ("frames = [30, 60]", "frames = [30, 61]", "sweep.toml:17:1: metrics.frames.1: frame 61 is past the last frame of heap.toml, 60"),
        ("snapshots = [30]", "snapshots = [90]", "record.snapshots.0: frame 90 is past the last frame of heap.toml, 60"),
        ("seeds = [0, 1]", "seeds = [0, 1, 0]", "sweep.seeds: 0 is listed twice"),
        ("seeds = [0, 1]", "seeds = []", "sweep.seeds"),
        ("[0.3, 1.2]", "[0.3, 0.3]", "0.3 is listed twice"),
        ("[0.3, 1.2]", '[0.3, "a"]', "the values must be all numbers, all text or all true/false"),
        ("[0.3, 1.2]", "[true, false]", "parameters.elements.sand.friction: true is not a value for elements.sand.friction (a float)"),
        ('"world.gravity" = [1.0, 0.5]', '"world.gravity" = [false]', "false is not a value for world.gravity"),
        ('format = "gif"', 'format = "mp4"', "sweep.toml:12:1: record.format: unknown format 'mp4'"),
        ('format = "gif"', 'format = "gfi"', "(did you mean 'gif'?)"),
        ('"world.gravity" = [1.0, 0.5]', '"world.seed" = [1, 2]', "world.seed would not take effect: the seeds of [sweep] set each run's seed"),
        ('"world.gravity" = [1.0, 0.5]', '"render.frames" = [10, 20]', "render.frames would not take effect: [sweep] frames sets every run's frames"),
        ('"world.gravity" = [1.0, 0.5]', '"render.every" = [1, 2]', "[record] every sets it for every run"),
        ('"world.gravity" = [1.0, 0.5]', '"render.crop" = [1, 2]', "a batch run does not use it"),
        ('"world.gravity" = [1.0, 0.5]', '"world.width" = [48, 100000]', "world.width = 100000: "),
        ("[0.3, 1.2]", "[0.3, -1]", "sweep.toml:8:1: parameters.elements.sand.friction: must be >= 0 (got -1)"),
    ],
)
def test_a_mistake_is_one_line_naming_the_line_and_nothing_is_written(sweep, old, new, message):
    edit(sweep, old, new)
    for command in (["batch", str(sweep), "-o", "out"], ["validate", str(sweep)]):
        result = invoke(*command)
        assert result.exit_code == 2 and message in result.output, result.output
        assert "Traceback" not in result.output and len(result.output.strip().splitlines()) == 1
    assert not Path("out").exists()


def test_a_render_parameter_that_takes_effect_is_taken(sweep):
    edit(sweep, '"world.gravity" = [1.0, 0.5]', '"render.scale" = [1, 2]')
    edit(sweep, "every = 10\n", "")
    edit(sweep, "frames = 60\n", "")
    edit(sweep, '"render.scale" = [1, 2]', '"render.scale" = [1, 2]\n"render.frames" = [40, 60]')
    edit(sweep, "frames = [30, 60]", "frames = [30]")
    edit(sweep, "snapshots = [30]", "snapshots = []")
    edit(sweep, "[0.3, 1.2]", "[0.3]")
    edit(sweep, "seeds = [0, 1]", "seeds = [0]")
    assert invoke("batch", str(sweep), "-o", "out").exit_code == 0
    from PIL import Image

    for row in csv.DictReader(open("out/results.csv")):
        assert int(row["frames"]) == int(row["parameter.render.frames"])
        with Image.open(Path("out/runs") / row["id"] / "animation.gif") as gif:
            assert gif.width == 48 * int(row["parameter.render.scale"])


def test_images_too_wide_for_the_format_or_runs_beyond_the_memory_are_refused_before_any_run(sweep):
    edit(sweep, "every = 10", "every = 10\nscale = 16")
    edit(sweep, '"world.gravity" = [1.0, 0.5]', '"world.width" = [48, 4200]')
    result = invoke("batch", str(sweep), "-o", "out")
    assert result.exit_code == 2 and "gif images are at most 65535 pixels a side; these would be 67200x640" in result.output
    edit(sweep, "scale = 16", "scale = 1")
    edit(sweep, 'format = "gif"', 'format = "webp"')
    result = invoke("batch", str(sweep), "-o", "out", "-j", "2", "--max-memory", "1000M")
    assert result.exit_code == 2 and "2 runs at a time" in result.output and "raise it with --max-memory, or fewer -j" in result.output
    assert not Path("out").exists()


def test_world_files_are_read_through_the_capped_reader_and_globs_stay_in_the_folder(sweep, tmp_path):
    with open("worlds/huge.toml", "wb") as file:
        file.truncate(5 * 2**20)  # sparse: the check must come before the read
    edit(sweep, 'worlds = ["heap.toml"]', 'worlds = ["huge.toml"]')
    result = invoke("batch", str(sweep), "-o", "out")
    assert result.exit_code == 2 and "huge.toml: cannot read file: larger than 4 MB" in result.output
    os.remove("worlds/huge.toml")
    Path(tmp_path / "outside").mkdir()
    Path(tmp_path / "outside/heap.toml").write_text(WORLD)
    os.symlink(tmp_path / "outside/heap.toml", "worlds/link.toml")
    edit(sweep, 'worlds = ["huge.toml"]', 'worlds = ["*.toml"]')
    result = invoke("batch", str(sweep), "-o", "out", "--dry-run")
    assert result.exit_code == 2 and "link.toml: the world must lie inside" in result.output


def test_rows_name_their_world_absent_elements_count_zero_and_the_summary_has_each_combination(sweep):
    Path("worlds/copy.toml").write_text(WORLD)
    edit(sweep, 'worlds = ["heap.toml"]', 'worlds = ["heap.toml", "copy.toml"]')
    edit(sweep, '"world.gravity" = [1.0, 0.5]', '"world.gravity" = [1.0]')
    edit(sweep, 'format = "gif"', 'format = "none"')
    result = invoke("batch", str(sweep), "-o", "out", "--long", "-j", "2")
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader(open("out/results.csv")))
    assert len(rows) == 8 and len({r["id"] for r in rows}) == 8 and {r["world"] for r in rows} == {"heap.toml", "copy.toml"}
    assert all(r["count.glass:glass@60"] == "0" for r in rows) and all(r["count.sand:sand@60"].isdigit() for r in rows)
    summary = list(csv.DictReader(open("out/summary.csv")))
    assert len(summary) == 4 and all(s["runs"] == "2" and s["failed"] == "0" for s in summary)
    for line in summary:
        values = [float(r["count.sand:sand@60"]) for r in rows if r["world"] == line["world"]
                  and r["parameter.elements.sand.friction"] == line["parameter.elements.sand.friction"]]
        assert float(line["count.sand:sand@60.mean"]) == pytest.approx(sum(values) / 2)
        assert float(line["count.sand:sand@60.std"]) == pytest.approx(abs(values[0] - values[1]) / 2**0.5)
    long = list(csv.DictReader(open("out/results_long.csv")))
    metrics = [k for k in rows[0] if "@" in k]
    assert len(long) == sum(1 for r in rows for k in metrics if r[k] != "")
    assert {(l["metric"], l["frame"]) for l in long} >= {("count.sand:sand", "60"), ("awake", "30")}
    assert sorted(p.name for p in Path("out/logs").iterdir()) == sorted(f"{r['id']}.log" for r in rows)


def test_quiet_says_nothing_and_dry_run_with_resume_lists_what_is_done(sweep):
    edit(sweep, 'format = "gif"', 'format = "none"')
    edit(sweep, "seeds = [0, 1]", "seeds = [0]")
    edit(sweep, "[0.3, 1.2]", "[0.3]")
    result = invoke("batch", str(sweep), "-o", "out", "-q")
    assert result.exit_code == 0 and result.output == ""
    edit(sweep, "seeds = [0]", "seeds = [0, 1]")
    result = invoke("batch", str(sweep), "-o", "out", "--dry-run", "--resume")
    assert result.exit_code == 0 and result.output.count("(done)") == 2 and result.output.strip().endswith("4 runs, 2 done")


def test_a_failed_run_has_its_traceback_in_its_log(sweep, tmp_path):
    run = batching.read_sweep(sweep, Path("out")).runs[0]
    assert Path(run.out).is_absolute()  # a worker elsewhere writes where the batch meant
    broken = batching.Run(**{**run.__dict__, "world_path": str(tmp_path / "gone.toml")})
    row = batching.execute(broken)
    log = broken.log.read_text()
    assert row["status"] == "failed" and "gone.toml" in log and "Traceback" in log


def test_new_sweep_in_an_empty_folder_writes_a_world_too_and_runs_as_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = invoke("new", "sweep", "friction")
    assert result.exit_code == 0, result.output
    assert invoke("validate", "friction.toml").exit_code == 0
    result = invoke("batch", "friction.toml", "--dry-run")
    assert result.exit_code == 0 and result.output.strip().endswith("12 runs")
