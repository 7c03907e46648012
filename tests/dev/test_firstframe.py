"""``tools/dev/firstframe.py``: a first run's render from an empty cache, timed to its first frame and its end."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

TOOL = Path(__file__).resolve().parents[2] / "tools" / "dev" / "firstframe.py"


@pytest.mark.slow  # it compiles the kernel from an empty cache
def test_a_first_run_draws_its_first_frame_before_it_ends():
    done = subprocess.run([sys.executable, str(TOOL), "examples/hourglass.toml"], cwd=TOOL.parents[2], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    first, end = map(float, re.fullmatch(r"first frame ([\d.]+) s, done ([\d.]+) s\n", done.stdout).groups())
    assert 0 < first <= end
