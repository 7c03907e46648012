"""``python tools/dev/lines.py``: how often each line of the kernel runs, the kernel run as Python."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

import lines


def counted(args: list[str]) -> tuple[int, list[str]]:
    result = CliRunner().invoke(lines.main, args, catch_exceptions=False)
    return result.exit_code, result.output.splitlines()


def count_of(output: list[str], text: str) -> list[int]:
    return [int(line.split()[0]) for line in output if line.endswith(text)]


def test_the_python_run_reaches_the_compiled_kernels_frames_and_counts_each_cell():
    # Frame 1 of halves at 64x64: one tile, which takes the fast loop on frame 1; every cell full.
    code, output = counted(["--scene", "halves", "--size", "64", "--start", "0", "--frames", "1"])
    assert code == 0, output
    assert output[0] == "halves 64x64, frame 1, step_region, the kernel run as Python:"
    assert output[-1] == "  the same frames as the compiled kernel"
    # The fast loop looks at each of the 4096 cells once.
    assert output[1].startswith("  with the fast loop: ")
    assert count_of(output, "e = cells[_at(y, x)]") == [64 * 64]
    # The bottom row of sand sinks into the water, each grain by its chance (0.56): the fast loop
    # moves the 33 of the 62 inner grains whose chance came up, and hands on the two at the world's
    # edges to the full update.
    assert count_of(output, "cells[_at(ty, x)] = e") == [33]
    assert count_of(output, "cells[_at(py, px)] = e") == [2]


def test_from_and_min_choose_the_lines_shown():
    source = [f"line {n}" for n in range(1, 11)]
    shown = lines._report({"False": {"2": 5, "4": 50, "8": 500}}, source, first=3, least=10)
    assert shown == ["without the fast loop: 555 lines run", "        50     4  line 4", "       500     8  line 8"]


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
