"""The kernel never reads or writes outside the world.

The cell update indexes the world's arrays with unsigned integers
(``cells._at``), for which numba does not wrap negative indices around: a
coordinate that slipped below zero would touch memory outside the array
instead of the far edge. So the busiest scenes and the example worlds that
throw cells against the edges run here once with numba's bounds checks
compiled in (and a cache folder of their own, so the checked kernels never
mix with the fast ones).
"""

from __future__ import annotations

import pytest

import os
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).parent.parent / "examples"

RUN = """
import sys
from sandmod.jobs import benchmark
from sandmod.world.loading import load_ruleset, load_world
from sandmod.world.world import World

ruleset = load_ruleset()
for scene, frames in (("everything", 200), ("mix", 60), ("halves", 60)):
    world = World(ruleset, 80, 72, 3)  # not whole chunks: ragged edges too
    benchmark.SCENES[scene](world, ruleset)
    for _ in range(frames):
        world.step()
for name, frames in (("demolition", 300), ("fountain", 200), ("forest_fire", 200), ("timeline", 250)):
    world = load_world(sys.argv[1] + "/" + name + ".toml").world
    for _ in range(frames):
        world.step()
print("in bounds")
"""


@pytest.mark.slow  # compiles the kernel anew
def test_the_kernel_stays_inside_the_world_with_bounds_checks_on(tmp_path):
    env = os.environ | {"NUMBA_BOUNDSCHECK": "1", "NUMBA_CACHE_DIR": str(tmp_path / "checked")}
    done = subprocess.run([sys.executable, "-c", RUN, str(EXAMPLES)], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip().endswith("in bounds")
