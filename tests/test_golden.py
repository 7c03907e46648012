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


#: The same scenes in a world of more cells than ``kernel.CACHED_CELLS``, where the kernel asks for
#: rows ahead of their use (a hint that must change nothing); recorded before it did.
GOLDEN_LARGE = {
    "mix": "926ae1e586095a3daf4ff06de21c8e7de15917d87c391d476843b268e60c75b1",
    "halves": "801ee410008f844fe44f7f1ad1354411a5e2b4d47ba846709c1e2cfb1d1ccea9",
    "everything": "17f951c8e5a82acf7c425e4f9c0cb34aedc79ea039175bf8a9e8212121b73a8f",
}


@pytest.mark.parametrize("scene", sorted(GOLDEN_LARGE))
def test_a_world_too_large_for_the_cache_steps_to_the_recorded_frames(ruleset, scene):
    from sandmod.kernel import CACHED_CELLS

    world = World(ruleset, 272, 272, seed=7)
    assert world.width * world.height > CACHED_CELLS
    benchmark.SCENES[scene](world, ruleset)
    got = digest(run(world, 120))
    assert got == GOLDEN_LARGE[scene], f"the frames of '{scene}' changed: if that is meant, record {got!r} in GOLDEN_LARGE"
