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

#: (scene, side of the world): digest after 160 frames. The larger world has more cells than
#: ``kernel.CACHED_CELLS``, so the kernel asks for rows ahead of their use there (a hint that must
#: change nothing); its digests were recorded with the kernel before it did.
GOLDEN = {
    ("mix", 96): "45f1a1775dee44bf8ddc4f6fd07d1b597f956b260e2f0f4b9b75f6232f7a62e3",
    ("halves", 96): "223a32a83683e5827cb234ec6785ef16ae9951d876f123fc5e06c8fb3b2fe845",
    ("everything", 96): "c389cccc4eacfc21787863f1d9e9321dc49a05e68febc705e4a67792b941355b",
    ("mix", 272): "66a7f701785c411e26a6901ce4efd30bd99f86c6b68c47568474266c6365e84e",
    ("halves", 272): "3cddc0ab58148dcd0def9640d93c5149455485f92aec6b5f68b0a128bb4bf396",
    ("everything", 272): "55f4caf0c77b518073910ea26ff6e33250a6080c804d125d0287968d91e58765",
}


def test_one_world_is_too_large_for_the_cache():
    from sandmod.kernel import CACHED_CELLS

    assert 96 * 96 <= CACHED_CELLS < 272 * 272


@pytest.mark.parametrize(("scene", "size"), sorted(GOLDEN))
def test_bench_scenes_step_to_the_recorded_frames(ruleset, scene, size):
    world = World(ruleset, size, size, seed=7)
    benchmark.SCENES[scene](world, ruleset)
    got = digest(run(world, 160))
    assert got == GOLDEN[scene, size], f"the frames of '{scene}' at {size}x{size} changed: if that is meant, record {got!r} in GOLDEN"
