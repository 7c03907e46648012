"""``python tools/dev/instructions.py``: counting the kernel's instructions under valgrind."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner

import instructions

from sandmod.engine import kernel


def _can_count() -> bool:
    if shutil.which("valgrind") is None or shutil.which("cc") is None:
        return False
    probe = subprocess.run(["cc", "-E", "-x", "c", "-"], input="#include <valgrind/callgrind.h>\n", capture_output=True, text=True)
    return probe.returncode == 0


def test_totals_line_is_read_in_callgrinds_event_order():
    count = instructions.Count.from_totals("totals: 1000 200 30 4 1", "digest")
    assert (count.instructions, count.branches, count.mispredicted, count.digest) == (1000, 204, 31, "digest")


@pytest.mark.slow  # compiles the kernel anew
@pytest.mark.skipif(not _can_count(), reason="needs valgrind, a C compiler and valgrind's headers")
def test_the_same_kernel_counts_the_same_to_the_instruction():
    args = ["--scene", "mix", "--size", "64", "--start", "3", "--frames", "2", "--against", kernel.__file__]
    result = CliRunner().invoke(instructions.main, args, catch_exceptions=False)
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[0] == "mix 64x64, frames 4-5, one thread, counted by callgrind:"
    per_frame = [float(m) for m in re.findall(r": ([\d.]+) million instructions a frame", result.output)]
    assert len(per_frame) == 2 and per_frame[0] == per_frame[1] > 0
    assert lines[-1].endswith("runs 1.000x the instructions of " + kernel.__file__ + ", same frames")


def test_a_missing_tool_is_one_line_not_a_traceback(monkeypatch):
    monkeypatch.setattr(instructions.shutil, "which", lambda name: None)
    result = CliRunner().invoke(instructions.main, ["--scene", "mix", "--size", "64"])
    assert result.exit_code == 1
    assert result.output.splitlines()[-1] == "Error: no C compiler (cc) on PATH: one is needed to call valgrind"
    assert result.exception is None or isinstance(result.exception, SystemExit)


def test_a_bad_world_file_is_one_line_per_problem_and_exit_2(tmp_path: Path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[world]\nwidth = -3\nheight = 64\n", encoding="utf-8")
    result = CliRunner().invoke(instructions.main, ["--world", str(bad)])
    assert result.exit_code == 2
    assert "world.width: must be >= 4" in result.output
    assert "Traceback" not in result.output


def test_against_a_file_that_is_no_kernel_is_a_usage_error_before_any_count(tmp_path: Path):
    other = tmp_path / "other.py"
    other.write_text("x = 1\n", encoding="utf-8")
    result = CliRunner().invoke(instructions.main, ["--against", str(other)])
    assert result.exit_code == 2
    assert result.output.splitlines()[-1].endswith("not a sandmod kernel (no step, take_detonations, explode)")
    assert "counted by callgrind" not in result.output
