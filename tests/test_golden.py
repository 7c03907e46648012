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
#: into falling basalt instead of static stone. Recorded again, the frames unchanged, when the digest came
#: to name elements by id among those present, so that adding an element to a bundled mod changes none.
#: The everything scene's recorded anew when stone came to break into rubble in blasts (gunpowder goes
#: off among its stones) and glass (made there from molten sand) into shards; with nothing that breaks
#: it steps to the frames before (``test_breaking``), and mix and halves are as they were.
GOLDEN = {
    ("everything", 96): "a9ff8ed57bbcc29d357bf367ae071a6586ec5799ed8e585821391b2bc16b0529",
    ("everything", 272): "d69c5614379149ba037e53ab915a47c251470f3c65185528d76a1b463fe5b9e3",
    ("halves", 96): "a1d49c56ca143b9278da40c4fafee4f9ca1ce5c300d2f517a9f3cf9db9dac040",
    ("halves", 272): "0097867167638433d420fe91042a7872f2e6bfbc25f5d1bc010df2f7dbf23d37",
    ("mix", 96): "71370443719d99691315e2e1393ae726616c502d651ccdf7cb6ddb4c90df6aa3",
    ("mix", 272): "e7dd24977ec7a779bc4720e320ddf6dad0bab94fda5d4ed80f0cca7026733868",
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
