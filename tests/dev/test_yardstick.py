"""The yardstick (``tools/dev/bench.py yardstick``) against a slow, obvious reference."""

from __future__ import annotations

import json

import numba
import numpy as np
import pytest
from click.testing import CliRunner

import bench
import yardstick

from sandmod.jobs import benchmark
from sandmod.engine.hashing import SALT_MOVE, cell_hash, frame_key

SAND, WATER, STONE = 1, 2, 3


def reference_step(cells: np.ndarray, frame: int, key: int, x0: int = 0) -> None:
    """The yardstick's rules, one cell at a time in plain Python (``cells``: the world's columns from x0 on)."""
    height, width = cells.shape
    moved = np.zeros(cells.shape, bool)
    for y in reversed(range(height)):
        xs = range(width) if (frame + y) % 2 == 0 else reversed(range(width))
        for x in xs:
            e = int(cells[y, x])
            if e not in (SAND, WATER) or moved[y, x]:
                continue
            side = 1 if cell_hash(key, x0 + x, y) & 1 else -1
            tries = [(0, 1), (side, 1), (-side, 1)] + ([(side, 0), (-side, 0)] if e == WATER else [])
            for dx, dy in tries:
                nx, ny = x + dx, y + dy
                if not (0 <= nx < width and ny < height):
                    continue
                o = int(cells[ny, nx])
                if o == 0 or (e == SAND and o == WATER and not moved[ny, nx]):
                    cells[y, x], cells[ny, nx] = o, e
                    moved[ny, nx] = True
                    moved[y, x] = o != 0
                    break


@pytest.mark.parametrize("bands", [1, 3])
def test_the_yardstick_steps_as_the_reference_does(bands):
    rng = np.random.default_rng(5)
    cells = rng.choice(np.array([0, SAND, WATER, STONE], np.uint16), size=(37, 53), p=[0.4, 0.25, 0.25, 0.1])
    edges = [b * cells.shape[1] // bands for b in range(bands + 1)]
    expected = [cells[:, x0:x1].copy() for x0, x1 in zip(edges, edges[1:])]  # each band a world of its own
    moved = np.zeros(cells.shape, np.uint8)
    for frame in range(40):
        key = frame_key(7, frame, SALT_MOVE)
        yardstick.step(cells, moved, SAND, WATER, frame, key, bands)
        for x0, band in zip(edges, expected):
            reference_step(band, frame, key, x0)
        assert np.array_equal(cells, np.hstack(expected)), f"frame {frame}"
    assert (cells[-1] == SAND).sum() > (cells[0] == SAND).sum()  # it did fall


def test_against_yardstick_times_both_on_each_thread_count(ruleset):
    threads = [1, min(2, numba.config.NUMBA_NUM_THREADS)]
    ours, theirs = yardstick.against_yardstick(benchmark.scene_bench(ruleset, "halves", 64), 30, threads, segment=8, repeats=2)
    assert len(ours) == len(theirs) == 2 and min(ours + theirs) > 0


def test_bench_yardstick_prints_both_speeds():
    threads = str(min(2, numba.config.NUMBA_NUM_THREADS))
    args = ["yardstick", "--scene", "mix", "--size", "256", "--steps", "4", "--threads", "1", "--threads", threads]
    result = CliRunner().invoke(bench.main, [*args, "--json"], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    runs = [json.loads(line) for line in result.stdout.splitlines()]
    assert [(r["scene"], r["width"], r["steps"], r["threads"], r["over_threads"]) for r in runs] == [
        ("mix", 256, 4, 1, 1), ("mix", 256, 4, int(threads), 1)
    ]
    for run in runs:  # timings are whatever the machine gives: only that each was taken
        assert run["mcell_updates_per_second"] > 0 and run["yardstick_mcell_updates_per_second"] > 0 and run["over_yardstick"] > 0
    assert runs[0]["speedup"] == runs[0]["yardstick_speedup"] == 1.0 and runs[1]["speedup"] > 0 and runs[1]["yardstick_speedup"] > 0
    result = CliRunner().invoke(bench.main, args, catch_exceptions=False)
    assert result.exit_code == 0 and "1 thread: this kernel" in result.stdout and f"{threads} over 1: this kernel" in result.stdout
    result = CliRunner().invoke(bench.main, [*args, "--threads", "auto"])
    assert result.exit_code == 2 and "give --threads N" in result.output
