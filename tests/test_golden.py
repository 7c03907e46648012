"""Pinned frames: the kernel's speed-ups must not change a single cell.

Each bench scene is stepped in a small world and the digest of its whole
state compared with the one recorded here. Frames are integer arithmetic
and hashing only, so the digests are the same on every machine and thread
count. When a change to the kernel or to a bundled mod is *meant* to change
what happens, look at the renders, then record the new digests.
"""

from __future__ import annotations

import pytest

from conftest import run
from sandmod import benchmark
from sandmod.world import World
from test_chunks import digest

GOLDEN = {
    "mix": "45f1a1775dee44bf8ddc4f6fd07d1b597f956b260e2f0f4b9b75f6232f7a62e3",
    "halves": "223a32a83683e5827cb234ec6785ef16ae9951d876f123fc5e06c8fb3b2fe845",
    "everything": "c389cccc4eacfc21787863f1d9e9321dc49a05e68febc705e4a67792b941355b",
}


@pytest.mark.parametrize("scene", sorted(GOLDEN))
def test_bench_scenes_step_to_the_recorded_frames(ruleset, scene):
    world = World(ruleset, 96, 96, seed=7)
    benchmark.SCENES[scene](world, ruleset)
    got = digest(run(world, 160))
    assert got == GOLDEN[scene], f"the frames of '{scene}' changed: if that is meant, record {got!r} in GOLDEN"
