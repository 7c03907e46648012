"""The garden's behaviours: plain functions of one cell's view, compiled by sandmod with numba.

They read and change cells only through sandmod.api's helpers, within two cells,
and draw their randomness from ``random``/``chance`` (hashes of the seed, frame and
cell), so a garden grows the same on every run and any number of threads.
"""

from __future__ import annotations

from sandmod.api import arg, behaviour, chance, helper, here, look, put, random

#: sprout's arguments, in the order arg() numbers them.
SOIL, TIP = 0, 1
#: grow's.
STEM, FLOWER, SPEED, LEAN, FORK, BLOOM = 0, 1, 2, 3, 4, 5


@behaviour(args=("soil", "tip"))
def sprout(v):
    """A seed on soil, under an empty cell, becomes a tip."""
    if look(v, 0, 1) == int(arg(v, SOIL)) and look(v, 0, -1) == 0:
        put(v, 0, 0, int(arg(v, TIP)))


@behaviour(args={"stem": None, "flower": None, "speed": 0.25, "lean": 0.3, "fork": 0.06, "bloom": 0.03})
def grow(v):
    """A tip climbs: it leaves stem where it was and moves up (or up and aside), may fork, may bloom."""
    if not chance(v, arg(v, SPEED)):
        return
    if chance(v, arg(v, BLOOM)):
        put(v, 0, 0, int(arg(v, FLOWER)))
        return
    side = 0
    if chance(v, arg(v, LEAN)):
        side = -1 if random(v) < 0.5 else 1
    if not _open(v, side):
        side = -side  # blocked: try the other way
        if not _open(v, side):
            return
    tip = here(v)
    put(v, side, -1, tip)
    put(v, 0, 0, int(arg(v, STEM)))
    if chance(v, arg(v, FORK)) and _open(v, -side if side != 0 else 1):
        put(v, -side if side != 0 else 1, -1, tip)


@helper
def _open(v, side):
    """Is the cell up and ``side`` empty, with room above it (empty, or the world's edge)?"""
    return look(v, side, -1) == 0 and look(v, side, -2) <= 0
