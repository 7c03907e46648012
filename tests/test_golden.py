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
#: change nothing). Recorded anew when a resting grain came to slump into a fluid diagonally below
#: it (the hourglass ran out), a liquid to sink into a lighter powder, the gas behind a rising gas
#: to follow it in its run and a gas to waver by its plume block's roll (no comb), and lava to set
#: into falling basalt instead of static stone.
GOLDEN = {
    ("mix", 96): "0d54785dd69e3ed8565bdf93146a33013116c3d8b55fca31bcb972ad7cb12783",
    ("halves", 96): "9b84613b83c7151113b97fb91b271dd862efd902a783cfccdd45156f9e903a08",
    ("everything", 96): "ca89836f9a40eb52d99cb0c52c31a4424b353c03dc93ef9c180580736b66e74c",
    ("mix", 272): "671a872c790651533e809632ed0eb002bfa46e916a684e1af521f1e804bf9955",
    ("halves", 272): "64916ab6b869ea20b80edbbc6324e14007f921db1d0b29e0fba652652647fb61",
    ("everything", 272): "af03d4063c5b74ba98727d90fd938f6d176bcf5ecee8ccc54a814050e777b55e",
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
