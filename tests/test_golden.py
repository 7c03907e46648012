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
#: sinking stopped knocking grains loose, and water and steam got latent heat and a boiling spread.
GOLDEN = {
    ("mix", 96): "46eb43f3ae888077aa5e3fd12335713ead40db7c1fdc247e8f2bd48b5114098d",
    ("halves", 96): "30eea7a9392c6e2892ee09040eab43b334512edbcfb304cd59202e87e49e56ef",
    ("everything", 96): "98646b8a0ec5d8ae8bac1db80b42b260e6ab4f8e9330c13b5938711396fd9199",
    ("mix", 272): "ea0c9b010c26f5eec75f48cab8459077a72a1ebb39246007eab25bbf17506ac1",
    ("halves", 272): "7ebbb792bade73e624502c01acc2c8f19ca99feab9966e0bf1ae6870ec0a4cfe",
    ("everything", 272): "8d1d289e1d386becd6a3b9caf4d625fbb9af97f6d570542739f59fa8198441b7",
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
