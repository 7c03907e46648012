"""tools/dev: kernels compared on the same frames (``bench.py against``), thread counts in turns."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import bench
import kernels
import numba
import numpy as np
import pytest
from click.testing import CliRunner

from sandmod.jobs.benchmark import scene_bench

DEV = Path(kernels.__file__).parent


class _Meddler:
    """A kernel that steps as sandmod's does, then changes one cell from ``frame`` on."""

    def __init__(self, frame: int):
        from sandmod.engine import kernel

        self.frame, self.take_detonations, self.explode, self._step = frame, kernel.take_detonations, kernel.explode, kernel.step

    def step(self, s, t, move_key, react_key, spawn_key, frame, *rest):
        went_off = self._step(s, t, move_key, react_key, spawn_key, frame, *rest)
        if frame >= self.frame:
            s.cells[0, 0] = 1 - min(s.cells[0, 0], 1)
        return went_off


def test_compare_times_kernels_that_step_to_the_same_frames(ruleset):
    from sandmod.engine import kernel

    seconds = kernels.compare(scene_bench(ruleset, "everything", 64), 30, 1, [kernel, kernels.load_kernel(Path(kernel.__file__))], segment=8)
    assert len(seconds) == 2 and min(seconds) > 0


def test_the_kernel_compared_with_its_own_file_is_itself():
    """A second import of kernel.py would write numba's cache files of the first under another module's
    name: after an edit, a later process would load code that names a module it cannot import."""
    from sandmod.engine import kernel

    assert kernels.load_kernel(Path(kernel.__file__)) is kernel


def test_compare_finds_the_stretch_where_frames_part(ruleset):
    from sandmod.engine import kernel

    with pytest.raises(kernels.FramesDiffer) as differ:
        kernels.compare(scene_bench(ruleset, "mix", 64), 40, 1, [kernel, _Meddler(frame=17)], segment=8, repeats=2)
    assert differ.value.frame == 24  # the end of the stretch of frames 16..23


def test_bench_against_another_kernel_file(tmp_path):
    from sandmod.engine import kernel

    args = ["against", "--scene", "halves", "--size", "256", "--steps", "6", "--threads", "1", "--json"]
    result = CliRunner().invoke(bench.main, [*args, kernel.__file__], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    run = json.loads(result.stdout)
    assert run["scene"] == "halves" and run["against"] == kernel.__file__
    assert run["mcell_updates_per_second"] > 0 and run["against_mcell_updates_per_second"] > 0 and run["speedup"] > 0
    broken = tmp_path / "kernel.py"
    broken.write_text("from .no_such_module import step\n")
    result = CliRunner().invoke(bench.main, [*args, str(broken)])
    assert result.exit_code == 2 and "cannot be imported beside this sandmod (ModuleNotFoundError" in result.output
    (tmp_path / "other.py").write_text("def step():\n    pass\n")
    result = CliRunner().invoke(bench.main, [*args, str(tmp_path / "other.py")])
    assert result.exit_code == 2 and "not a sandmod kernel (no take_detonations, explode)" in result.output
    (tmp_path / "misfit.py").write_text(
        "from numba import njit\n\n\n@njit\ndef step(s, t, a, b, c, frame, awake, woken, even, stirred, detonations, hands):\n"
        "    return woken[0, 0, 0, 0]\n\n\ntake_detonations = explode = step\n"
    )
    result = CliRunner().invoke(bench.main, [*args, str(tmp_path / "misfit.py")])
    assert result.exit_code == 2 and "misfit.py: does not compile beside this sandmod (TypingError: " in result.output


def test_a_kernel_from_before_the_marks_had_their_own_lines_is_handed_them_flat(tmp_path):
    (tmp_path / "kernel.py").write_text(
        "def step(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands):\n"
        "    return woken.shape, stirred.shape, awake.shape\n\n\ntake_detonations = explode = step\n"
    )
    marks = np.zeros((3, 4, 32), np.uint16)
    old = kernels.load_kernel(tmp_path / "kernel.py")
    assert old.step(0, 0, 0, 0, 0, 0, marks[:, :, 0], marks, 0, marks, 0, 1, 0) == ((3, 4), (3, 4), (3, 4))


def test_a_kernel_from_before_a_later_argument_of_step_is_handed_those_it_takes(tmp_path):
    (tmp_path / "kernel.py").write_text(
        "def _mark(cy, cx):\n    return cy, cx, 0\n\n\n"
        "def step(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands):\n"
        "    return hands, woken.shape\n\n\ntake_detonations = explode = step\n"
    )
    marks = np.zeros((3, 4, 32), np.uint16)
    old = kernels.load_kernel(tmp_path / "kernel.py")
    assert old.step(0, 0, 0, 0, 0, 0, marks[:, :, 0], marks, 0, marks, 0, 2, -1) == (2, (3, 4, 32))
    from sandmod.engine import kernel

    assert kernels.load_kernel(kernel.__file__) is kernel


def test_a_kernel_file_loads_from_numbas_cache_in_a_later_process(tmp_path):
    # numba's cache imports the module of what it compiled by name: a second process must find it.
    (tmp_path / "kernel.py").write_text(
        "from numba import njit\n\n\n@njit(cache=True)\ndef step(x):\n    return x + 1\n\n\ntake_detonations = explode = step\n"
    )
    code = f"import sys; sys.path.insert(0, {str(DEV)!r}); import kernels; print(kernels.load_kernel({str(tmp_path / 'kernel.py')!r}).step(1))"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    for _ in range(2):  # compiled and cached, then loaded from the cache
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
        assert (done.returncode, done.stdout.strip()) == (0, "2"), done.stderr


def test_bench_in_turns_times_thread_counts_on_the_same_frames():
    threads = min(2, numba.config.NUMBA_NUM_THREADS)
    args = ["--scene", "everything", "--size", "256", "--steps", "30", "--threads", "1", "--threads", str(threads)]
    result = CliRunner().invoke(bench.main, ["in-turns", *args, "--json"], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    runs = [json.loads(line) for line in result.stdout.splitlines()]
    assert [(r["scene"], r["threads"], r["over_threads"]) for r in runs] == [("everything", 1, 1), ("everything", threads, 1)]
    assert runs[0]["speedup"] == 1.0 and runs[1]["speedup"] > 0 and runs[1]["mcell_updates_per_second"] > 0
    result = CliRunner().invoke(bench.main, ["in-turns", *args], catch_exceptions=False)
    assert result.exit_code == 0 and result.stdout.strip().endswith("million cell-updates/s, same frames")


def test_bench_steps_a_world_alike_on_any_thread_count():
    """Emitters, sprays and the timeline run by the frame number, so stretches timed again from a saved state repeat."""
    threads = min(2, numba.config.NUMBA_NUM_THREADS)
    args = ["in-turns", "--world", str(DEV.parent.parent / "examples" / "fountain.toml"), "--steps", "30", "--threads", "1", "--threads", str(threads)]
    result = CliRunner().invoke(bench.main, args, catch_exceptions=False)
    assert result.exit_code == 0 and result.stdout.strip().endswith("same frames"), result.output
