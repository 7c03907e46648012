"""``sandmod bench``, its scenes, and the first-run compile notice."""

from __future__ import annotations

import json
import os
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from sandmod.jobs import benchmark

from sandmod.engine import kernelcache
from sandmod.tools.cli import cli
from sandmod.rules.compiler import BLAST_COLUMNS
from sandmod.jobs import warmup
from sandmod.jobs.warmup import compile_kernels
from sandmod.world.world import World

EXAMPLES = Path(__file__).parent.parent / "examples"
KEYS = {
    "scene", "width", "height", "steps", "threads", "seconds", "steps_per_second", "mcell_updates_per_second",
    "awake_fraction", "compile_seconds", "peak_memory_mb",
}  # fmt: skip


def test_mix_scene_is_the_published_one(ruleset):
    world = World(ruleset, 512, 512)
    benchmark.mix(world, ruleset)
    counts = world.counts()
    assert (counts["sand:sand"], counts["water:water"]) == (65328, 65737)


def test_bench_json_prints_one_object_per_run():
    args = ["bench", "--scene", "settled", "--scene", "mix", "--size", "256", "--steps", "3", "--threads", "1", "--json"]
    result = CliRunner().invoke(cli, args, catch_exceptions=False)
    assert result.exit_code == 0, result.output
    runs = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["scene"] for r in runs] == ["settled", "mix"]
    for r in runs:
        assert KEYS <= set(r) and (r["width"], r["height"], r["steps"], r["threads"]) == (256, 256, 3, 1)
        assert r["mcell_updates_per_second"] > 0 and r["peak_memory_mb"] > 0
        assert r["state_bytes_per_cell"] <= 16.2  # 16 a cell (4,096 elements: what a particle carries is uint16) and the chunks' marks
    assert runs[0]["awake_fraction"] == 0.0 and runs[1]["awake_fraction"] > 0.5


POURING = """
[world]
width = 64
height = 48
seed = 3

[[emitters]]
shape = "rect"
element = "sand"
x = 30
y = 2
width = 4
height = 2

[render]
frames = 7
"""


def test_bench_times_a_world_file_at_its_own_size_for_its_own_frames(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("pouring.toml").write_text(POURING)
    args = ["bench", "--world", "pouring.toml", "--scene", "mix", "--size", "256", "--threads", "1", "--json"]
    result = CliRunner().invoke(cli, [*args, "--steps", "4"], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    runs = [json.loads(line) for line in result.stdout.splitlines()]
    assert [(r["scene"], r["width"], r["height"], r["steps"]) for r in runs] == [("mix", 256, 256, 4), ("pouring.toml", 64, 48, 4)]
    result = CliRunner().invoke(cli, ["bench", "--world", "pouring.toml", "--threads", "1", "--json"], catch_exceptions=False)
    (run,) = [json.loads(line) for line in result.stdout.splitlines()]
    assert KEYS <= set(run) and run["steps"] == 7 and run["awake_fraction"] > 0


def test_a_world_bench_builds_the_file_afresh_and_runs_its_emitters(ruleset, tmp_path):
    path = tmp_path / "pouring.toml"
    path.write_text(POURING)
    bench, warnings = benchmark.world_bench(path)
    first, second = bench.make(), bench.make()
    assert first is not second and warnings == [] and first.seed == 3
    for _ in range(5):
        first.step()
    assert first.counts().get("sand:sand", 0) > 0 and second.counts().get("sand:sand", 0) == 0
    assert benchmark.world_bench(path, seed=9)[0].make().seed == 9


@pytest.mark.parametrize(
    "args, message",
    [
        (["--world", "bad.toml"], "bad.toml:3:1: world.width: must be >= 4 (got 1)"),
        (["--world", "nosuch.toml"], "nosuch.toml: cannot read file"),
        (["--world", "pouring.toml", "--size", "256"], "--size sizes the built-in scenes; a world file has its own size"),
    ],
)
def test_bench_says_what_is_wrong_with_a_world(tmp_path, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    Path("pouring.toml").write_text(POURING)
    Path("bad.toml").write_text(POURING.replace("width = 64", "width = 1"))
    result = CliRunner().invoke(cli, ["bench", *args])
    assert result.exit_code == 2 and message in result.output and "Traceback" not in result.output


def test_peak_memory_without_the_resource_module_asks_windows(monkeypatch):
    """Windows has no ``resource``: bench must still run there, reporting the peak working set."""
    assert benchmark.peak_memory_mb() > 1
    monkeypatch.setattr(sys, "platform", "win32")
    monkeypatch.setitem(sys.modules, "resource", None)  # import resource -> ImportError
    monkeypatch.setattr(benchmark, "_peak_working_set", lambda: 3 * 2**20)
    assert benchmark.peak_memory_mb() == 3.0


def test_bench_rejects_sizes_out_of_range():
    result = CliRunner().invoke(cli, ["bench", "--size", "100"])
    assert result.exit_code == 2 and "256<=x<=2048" in result.output


def test_no_sleep_updates_every_chunk(ruleset):
    kept = benchmark.run(benchmark.scene_bench(ruleset, "settled", 256), 2, 1, sleep=False)
    assert kept.awake_fraction == 1.0 and not kept.sleep


def test_compiling_the_kernels_runs_every_one_then_notes_the_version(ruleset, tmp_path, monkeypatch):
    """Every kernel a world calls, explosions' too: a first explosion must not compile unannounced later."""
    called = []

    class Recording:
        def step(self, *args):
            called.append("step")
            return 0

        def step_soon(self, *args):
            called.append("step_soon")
            return 0

        def take_detonations(self, *args):
            called.append("take_detonations")
            return np.zeros((0, BLAST_COLUMNS), np.int64)

        def explode(self, *args):
            called.append("explode")

        def conduct(self, *args):
            called.append("conduct")

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    from sandmod.engine import kernel

    from sandmod.world import world as world_module

    for name in ("step", "step_soon", "take_detonations", "explode", "conduct"):
        monkeypatch.setattr(kernel, name, getattr(Recording(), name))
    monkeypatch.setattr(world_module, "_STEP_COMPILED", False)  # as in a first run's process

    class Worker(_FakeWorker.recording([])):  # no processes
        def compile(self, part):
            if part == "step":
                _until(lambda: called)  # as long as it takes, after the quick step
            return super().compile(part)

    monkeypatch.setattr(warmup, "_Worker", Worker)
    assert not kernelcache.is_compiled()
    said = []
    compile_kernels(ruleset, announce=lambda line: (time.sleep(0.02), said.append(line)))  # slow to say it, as a terminal may be
    assert sorted(Worker.events) == sorted(("compile", part) for part in warmup.PARTS if part not in warmup.ASKED)
    # The quick step here (conduct: compiled by a part, linked by it), then the best step loaded, and the blasts'.
    assert called == ["step_soon", "step", "take_detonations", "explode"]
    assert kernelcache.is_compiled() and not warmup._LATER  # all of it done as it returns, nothing left for later
    parts = len(warmup.PARTS) - len(warmup.ASKED)
    assert any(line.startswith(f"compiling the kernel: {parts} of {parts} parts done") for line in said)


def _until(condition, seconds=60):
    """Wait until ``condition()`` is true, for ``seconds`` at most."""
    deadline = time.monotonic() + seconds
    while not condition() and time.monotonic() < deadline:
        time.sleep(0.01)


class _FakeWorker:
    """Stands in for a worker process: says each part compiled at once, and records what it was asked."""

    events: list

    @classmethod
    def recording(cls, events):
        return type("Worker", (cls,), {"events": events})

    @classmethod
    def holding(cls, events, parts, release):
        """One that records into ``events`` and holds each of ``parts`` until ``release`` is set."""

        def compile(self, part):
            if part in parts:
                release.wait(300)
            return cls.compile(self, part)

        return type("Worker", (cls,), {"events": events, "compile": compile})

    def compile(self, part):
        self.events.append(("compile", part))
        return part not in getattr(self, "failing", ())

    def close(self):
        pass


def test_warmup_starts_each_part_once_those_it_calls_are_done_and_steps_when_the_step_can():
    events = []
    Worker = _FakeWorker.recording(events)
    compiling = warmup._Compiling(lambda done: None, warmup.PARTS, worker=Worker)
    with compiling.here_after(warmup.STEP_NEEDS):
        events.append(("step", None))
    compiling.join()
    started = [part for event, part in events if event == "compile"]
    assert sorted(started) == sorted(warmup.PARTS)  # each once
    for part, needs in warmup.PARTS.items():
        assert set(needs) <= set(warmup.PARTS) and all(events.index(("compile", need)) < events.index(("compile", part)) for need in needs)
    assert set(warmup.STEP_NEEDS) <= set(warmup.PARTS)
    assert all(events.index(("compile", part)) < events.index(("step", None)) for part in warmup.STEP_NEEDS)
    assert compiling.done() and compiling.succeeded()


def test_a_first_frame_waits_only_for_the_parts_its_world_uses_and_the_rest_finish_before_the_command_exits(ruleset, tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))  # not compiled yet
    world = World(ruleset, 64, 64)
    later = warmup.unused_at_first(world)
    assert "taps and sprays" in later and "blasts" not in later  # the bundled rules have explosives
    events, release = [], threading.Event()

    # Still compiling when the first frame may start (a step may compile for a while here).
    monkeypatch.setattr(warmup, "_Worker", _FakeWorker.holding(events, later, release))
    compile_kernels(ruleset, first_frame_of=world)
    assert not kernelcache.is_compiled() and warmup._LATER  # the first frame need not wait
    assert {part for _, part in events} >= set(warmup.PARTS) - set(later) - set(warmup.ASKED)
    release.set()
    warmup.finish_later()
    assert kernelcache.is_compiled() and not warmup._LATER and sorted(part for _, part in events) == sorted(set(warmup.PARTS) - set(warmup.ASKED))


def test_while_the_parts_waited_for_wait_for_theirs_a_worker_compiles_a_later_part(monkeypatch):
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    events, release = [], threading.Event()

    first = [part for part in warmup.PARTS if part not in warmup.LATER]
    compiling = warmup._Compiling(lambda done: None, first, worker=_FakeWorker.holding(events, ("moves",), release))
    _until(lambda: ("compile", "blasts") in events)
    waiting = list(events)
    release.set()
    compiling.join()
    assert ("compile", "blasts") in waiting and ("compile", "cells") not in waiting  # cells waits for moves; blasts need not
    assert [part for _, part in waiting if part in first] == [part for part in first if not warmup.PARTS[part] and part != "moves"]
    assert compiling.succeeded()


def test_a_first_run_switches_to_the_best_step_once_its_part_is_done(ruleset, tmp_path, monkeypatch):
    from sandmod.engine import kernel
    from sandmod.world import world as world_module

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))  # not compiled yet
    monkeypatch.setattr(world_module, "_STEP_COMPILED", False)
    events, release = [], threading.Event()

    monkeypatch.setattr(warmup, "_Worker", _FakeWorker.holding(events, ("step",), release))
    compile_kernels(ruleset, first_frame_of=World(ruleset, 64, 64))
    assert world_module._serial_step(kernel) is kernel.step_soon
    release.set()
    _until(kernelcache.best_step_cached)
    assert world_module._serial_step(kernel) is kernel.step and not kernelcache.is_compiled()  # the rest may still compile
    warmup.finish_later()


def test_asked_to_the_warmup_compiles_the_kernel_for_several_threads_side_by_side(ruleset, tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))  # not compiled yet
    monkeypatch.setattr(warmup, "_several_cpus", lambda: True)
    monkeypatch.setattr(warmup, "_Worker", Worker := _FakeWorker.recording([]))
    compile_kernels(ruleset, several_threads=True)
    assert ("compile", "several threads") in Worker.events and kernelcache.is_compiled()


def test_a_part_that_failed_leaves_the_version_not_compiled(ruleset, tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    Failing = type("Failing", (_FakeWorker.recording([]),), {"failing": ("neighbour rules",)})
    compiling = warmup._Compiling(lambda done: None, warmup.PARTS, worker=Failing)
    compiling.join()
    assert compiling.done() and not compiling.succeeded()


def test_warmup_compiles_for_one_thread_and_several_and_says_where(tmp_path, monkeypatch):
    called = []
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))  # an empty cache: as on a first run
    monkeypatch.setattr(warmup, "compile_kernels", lambda announce, several_threads: called.append(("one thread", several_threads)) or 0.0)
    monkeypatch.setattr(warmup, "compile_parallel", lambda announce: called.append("several"))
    first = CliRunner().invoke(cli, ["warmup"])
    assert first.exit_code == 0 and called == [("one thread", True), "several"]  # several side by side with the rest; then loaded
    assert kernelcache.NOTICE in first.stderr and "compiled in" in first.stderr and "cache" in first.stderr.splitlines()[-1]
    assert CliRunner().invoke(cli, ["warmup", "-q"]).stderr == ""


def test_warmup_with_the_kernel_compiled_loads_it():
    warmup.compile_new_kernels()  # as the test session's start does, if it has not
    warmup.compile_parallel()
    result = CliRunner().invoke(cli, ["warmup"])
    assert result.exit_code == 0 and result.stderr.startswith("already compiled: loaded in")


@pytest.mark.slow  # compiles the kernel anew
def test_the_first_render_of_a_version_says_it_compiles(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))  # an empty cache: as on a first run
    monkeypatch.chdir(tmp_path)
    assert not kernelcache.is_compiled()
    args = ["render", str(EXAMPLES / "hourglass.toml"), "--frames", "2", "-o", "a.gif"]
    first = CliRunner().invoke(cli, args, catch_exceptions=False)
    assert first.exit_code == 0 and "compiling" in first.stderr
    assert kernelcache.is_compiled()
    again = CliRunner().invoke(cli, args, catch_exceptions=False)
    assert again.exit_code == 0 and "compiling" not in again.stderr


def test_state_is_sixteen_bytes_a_cell_and_a_little_per_chunk(ruleset):
    world = World(ruleset, 512, 512)
    assert sum(a.nbytes for a in world.state) == 16 * 512 * 512
    # The chunks' marks, the two that threads write a cache line each, count too.
    assert 16.1 < benchmark.state_bytes(world) / 512**2 < 16.2


def test_patch_scene_keeps_its_work_in_its_box(ruleset):
    world = World(ruleset, 768, 768)
    benchmark.patch(world, ruleset)
    for _ in range(10):
        world.step()
    box = np.zeros(world.cells.shape, bool)
    box[127:641, 127:641] = True
    assert not world.cells[~box].any()
    assert world.awake_fraction < 0.6


def test_bench_record_splits_a_render_into_steps_images_and_encoding():
    args = ["bench", "--record", "gif", "--record", "png-frames", "--size", "256", "--steps", "3", "--threads", "1", "--json"]
    result = CliRunner().invoke(cli, args, catch_exceptions=False)
    assert result.exit_code == 0, result.output
    runs = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["format"] for r in runs] == ["gif", "png-frames"]
    for r in runs:
        assert (r["width"], r["height"], r["images"], r["threads"]) == (256, 256, 3, 1)
        assert r["step_seconds"] > 0 and r["image_seconds"] > 0 and r["encode_seconds"] > 0 and r["file_mb"] > 0
        assert r["images_per_second"] == pytest.approx(3 / r["encode_seconds"], rel=0.05) and 0 < r["encode_share"] < 1
    bad = CliRunner().invoke(cli, ["bench", "--record", "mp4", "--size", "256", "--steps", "1"])
    assert bad.exit_code == 2 and "unknown format 'mp4'" in bad.stderr


def test_a_render_measured_from_a_large_process_reports_its_own_peak_not_that_of_the_process_that_started_it():
    import numpy as np

    from sandmod.jobs.benchmark import render_peak_memory

    ballast = np.ones(600 * 2**20 // 8)  # 600 MB touched here: ru_maxrss would hand it to the render's process
    assert render_peak_memory(128).peak_mb < 500 and ballast[-1] == 1


def test_bench_memory_measures_a_render_in_a_process_of_its_own_and_the_estimate_covers_it():
    result = CliRunner().invoke(cli, ["bench", "--memory", "512", "--json"], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    found = json.loads(result.output)
    assert found["width"] == found["height"] == 512 and found["format"] == "gif"
    assert 0 < found["peak_mb"] <= found["estimate_mb"]
