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
from sandmod.jobs import benchmark
from sandmod.world.world import World
from test_chunks import digest

#: (scene, side of the world): digest after 160 frames. The larger world has more cells than
#: ``layout.CACHED_CELLS``, so the kernel asks for rows ahead of their use there (a hint that must
#: change nothing). Recorded anew when fluids came to trade places by plume blocks (one roll for
#: a block of cells) with the run of fallers behind a sinker following it (no comb, no static),
#: a sinker knocks only the grains diagonally above it, and only with no run following it, and
#: water and steam got latent heat and a boiling spread.
GOLDEN = {
    ("mix", 96): "708346bec7269e98b87259a5ff4c5c073098319530850b7e1082da4c43a2fe3f",
    ("halves", 96): "52369b16d9fcb81ef7445f9bb5352e33ec7211853d3f82a6442e9bf0da2a53ca",
    ("everything", 96): "7aec63bb4013d9e8a3af362f6bd2a3bca4e43d4126cd300cd9890c3b6d78d154",
    ("mix", 272): "4bf3098a29e163ffa4a1f18766515ec09bf9098f569e7820ffb00f47de6f3c01",
    ("halves", 272): "a102bf1a5e5af83aaedd423e4e8b3fbf63bbeb05a017c7b27861db66565a443d",
    ("everything", 272): "1eb2aa21da3250888c44461d36b1119153658a7e6ad153ac4d3d52e77ec33bb0",
}


def test_one_world_is_too_large_for_the_cache():
    from sandmod.engine.layout import CACHED_CELLS

    assert 96 * 96 <= CACHED_CELLS < 272 * 272


@pytest.mark.parametrize(("scene", "size"), sorted(GOLDEN))
def test_bench_scenes_step_to_the_recorded_frames(ruleset, scene, size):
    world = World(ruleset, size, size, seed=7)
    benchmark.SCENES[scene](world, ruleset)
    got = digest(run(world, 160))
    assert got == GOLDEN[scene, size], f"the frames of '{scene}' at {size}x{size} changed: if that is meant, record {got!r} in GOLDEN"
