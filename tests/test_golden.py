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
    "mix": "3bf6a1cad6d0b735ed065404369afd4ae287f3d462bb578695dd4ace7e78245e",
    "halves": "950aee83c382ec37377d786530f1ca604634afcc74f924851d83109efc77323b",
    "everything": "f5c0450be061aa876edcf5a0109a6f9dc09bf5715c21e7f1e48250ff460cc05f",
}


@pytest.mark.parametrize("scene", sorted(GOLDEN))
def test_bench_scenes_step_to_the_recorded_frames(ruleset, scene):
    world = World(ruleset, 96, 96, seed=7)
    benchmark.SCENES[scene](world, ruleset)
    got = digest(run(world, 160))
    assert got == GOLDEN[scene], f"the frames of '{scene}' changed: if that is meant, record {got!r} in GOLDEN"
