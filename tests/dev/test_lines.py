"""``python tools/dev/lines.py``: how often each line of the kernel runs, the kernel run as Python."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

import lines


def counted(args: list[str]) -> tuple[int, list[str]]:
    result = CliRunner().invoke(lines.main, args, catch_exceptions=False)
    return result.exit_code, result.output.splitlines()


def calls_of(output: list[str], version: str) -> dict[str, int]:
    """The calls of each engine function, from the report's line for one version of step_region."""
    line = next(line for line in output if line.startswith(f"  {version}: calls "))
    pairs = line.split(": calls ", 1)[1].split(", ")
    return {name: int(n) for name, n in (pair.rsplit(" ", 1) for pair in pairs)}


def test_the_python_run_reaches_the_compiled_kernels_frames_and_counts_each_call():
    # Frame 1 of halves at 64x64: one tile, which takes the fast loop on frame 1; every cell full.
    code, output = counted(["--scene", "halves", "--size", "64", "--start", "0", "--frames", "1"])
    assert code == 0, output
    assert output[0] == "halves 64x64, frame 1, the kernel run as Python:"
    assert output[-1] == "  the same frames as the compiled kernel"
    fast = calls_of(output, "with the fast loop")
    # The bottom row of sand sinks into the water, each plume block of grains by its chance (0.94):
    # each of the 64 grains rolls once (the fast loop hands on the two at the world's edges to the
    # full update), and 60 of them, in blocks whose chance came up, sink with the grains above
    # them in their runs; the 4 whose run is empty (a run's first row) may knock grains loose.
    assert fast["_plume_roll"] == 64 and fast["sink_run"] == 60 and fast["knock"] == 4
    # The freshly painted grains are loose: those that did not sink with a run and are shut in by the
    # grains around them come to rest in the fast loop; the full update settles the few others (every
    # one calm: ready for its move).
    assert fast["_boxed_in"] > 64 * 20 and "heat_and_fire" not in fast
    assert fast["_update_cell"] == fast["move"] == fast["settle"] < fast["_boxed_in"] / 5
    assert fast["step_region"] == 1


def test_function_and_min_choose_the_lines_shown():
    result = {
        "calls": {"None": {"move": 3, "swap": 1}},
        "lines": {"None": {"moves.py:move:2": 5, "moves.py:move:4": 50, "cells.py:swap:3": 500}},
    }
    sources = {"moves.py": [f"line {n}" for n in range(1, 11)], "cells.py": [f"cell {n}" for n in range(1, 11)]}
    shown = lines._report(result, sources, "move", 10)
    assert shown == ["without the fast loop: calls move 3, swap 1", "        50  moves.py:4     line 4"]
    assert lines._report(result, sources, None, 1)[1:] == ["       500  cells.py:3     cell 3", "         5  moves.py:2     line 2", "        50  moves.py:4     line 4"]


def test_frames_that_differ_from_the_compiled_kernels_are_said_and_exit_1(monkeypatch):
    monkeypatch.setattr(lines.benchmark, "state_digest", lambda world: "not the child's")  # the parent's, not the child's
    code, output = counted(["--scene", "mix", "--size", "32", "--start", "2"])
    assert code == 1
    assert "  OTHER FRAMES than the compiled kernel's: these counts are not the real frames'" in output


def test_a_bad_world_file_is_one_line_per_problem_and_exit_2(tmp_path: Path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[world]\nwidth = -3\nheight = 64\n", encoding="utf-8")
    result = CliRunner().invoke(lines.main, ["--world", str(bad)])
    assert result.exit_code == 2
    assert "world.width: must be >= 4" in result.output
    assert "Traceback" not in result.output
