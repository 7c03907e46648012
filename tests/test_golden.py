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
    ("mix", 96): "31f6bda3b240a5e010e9396b8e04fb888704e5f31978a8b5d3cee7ac10a56d2c",
    ("halves", 96): "c12805703f3c9c9224011547637fc4687e2e6f0db972b300191a26d2916d3661",
    ("everything", 96): "eb149aad0577151c19410e9e9922d54b0fd77171d18468d7911649962c87db70",
    ("mix", 272): "2a510e4736c0bb3d1203084b9f9e45f7e13e5c78b7442bcfcbfabbbc30687fc7",
    ("halves", 272): "e9af47355540a57fc7d5ab8e82b0cdcdb8dd6c89a8f002692a2051aefc30704a",
    ("everything", 272): "cb36ab7219256aa64ef956ab09cd071e3902324db12a2a9469519794eac53823",
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
