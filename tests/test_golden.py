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
#: change nothing). Recorded anew when fluids came to trade places by a chance that grows with
#: their densities' gap (no more combs of alternating rows), reactions stopped ending the turn of a
#: cell they leave as it was, liquids stopped flowing sideways over a drop, and rising gas wavers.
GOLDEN = {
    ("mix", 96): "1eea853b7c84543a90572749c72317b11bea3f4543bfdfc5cd3a0588797e5f41",
    ("halves", 96): "0edb205034dfb7f3ed3f254f97ebb7a40350934e06e29dcc0f9f7f063fb17595",
    ("everything", 96): "e0188aa962f1b8d99fddeafb3036169dad812fda81e11b96b800f6d0dcbf3197",
    ("mix", 272): "9a5fc584f3236884602e2269c823ab3586b03004493ed670eca5588dc53c7e46",
    ("halves", 272): "d6f83b1edaeadeaee6673ef06870382d76fdc7e091f79978f6f8be751deeb6a9",
    ("everything", 272): "da1ab5bdff21aca47ecc9c201e134d423eea50dde22dbe38e42082cf94b6d021",
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
