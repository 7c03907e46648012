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
#: into falling basalt instead of static stone; written anew, the same frames, when the digest came to
#: name elements by their ids (a bundled mod that adds an element no longer changes them). The
#: everything scene's recorded anew when stone came to break into rubble in blasts (gunpowder goes
#: off among its stones) and glass (made there from molten sand) into shards; with nothing that breaks
#: it steps to the frames before (``test_breaking``), and mix and halves are as they were.
GOLDEN = {
    ("mix", 96): "3ed9455839a9f985294f3d9c12602cc87d28cfe13300e00c963e9bbecb8811c8",
    ("halves", 96): "6c61dd0cc6be28738018eb7825e4bc12e896bdfad3e0b5e97d68cdf63529efb8",
    ("everything", 96): "0a8befea7ef0ef0452be96e1e711718223e3f005dd475908fa5e90c78e4768c6",
    ("mix", 272): "cccca06f7462fc3c81cdb0c86f241cbf0a78a8d6577b97d989e7cea84320acd0",
    ("halves", 272): "fb60448e57a90d26014f348bbfc8e9c5ba272c21a750787ae03ba0fef922f126",
    ("everything", 272): "f6b310c1c0f0af41eee5a1904057efbe90c51fe1049babf95d807490a106d352",
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
