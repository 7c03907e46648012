"""The neighbour-count pass: after the step, each cell of an element that neighbour rules change
(:mod:`sandmod.rules.neighbours`) counts its neighbours; every cell is decided from the cells as
the step left them, and then they all change together, so Conway's Life is exact. Serial and in a
fixed order, its rolls hashed from (seed, frame, x, y): the same frames on any thread count."""

from __future__ import annotations

import numpy as np

from ..engine.cells import LOOSE, _cell_key, _temperature, become
from ..engine.hashing import ROLL_BITS, SALT_NEIGHBOURS, frame_key
from ..engine.jit import compiled
from ..engine.layout import TILE, TILE_SHIFT
from .visit import tiles_holding, wake_around

#: (dx, dy) of the 8 neighbours, by their bit in NeighbourTables.where (as rules.neighbours.AROUND).
_DX = np.array([-1, 0, 1, -1, 1, -1, 0, 1], np.int64)
_DY = np.array([-1, -1, -1, 0, 0, 1, 1, 1], np.int64)


def apply_neighbour_rules(world) -> int:
    """Run the world's neighbour rules over the tiles its last step saw their elements in; returns how many cells changed."""
    rules = world.ruleset.neighbours
    tiles = tiles_holding(world._seen, rules.mask)
    if len(tiles) == 0:
        return 0
    key = frame_key(world.seed, world.frame, SALT_NEIGHBOURS)
    return _apply(world.state, world.tables, rules.start, rules.stop, rules.counted, rules.counts, rules.where,
                  rules.into, rules.chance, tiles, key, world.awake, world._even, _DX, _DY)


def compile_pass(world) -> None:
    """Compile the pass (or load it from the cache) with no rules, on no tiles: for the warm-up."""
    n = len(world.tables.archetype)
    none = np.zeros(1, np.int64)[:0]
    _apply(world.state, world.tables, np.zeros(n, np.int32), np.zeros(n, np.int32), np.zeros((1, n), np.uint8),
           np.zeros(1, np.uint16), np.zeros(1, np.uint8), np.zeros(1, np.uint16), np.zeros(1, np.uint32), none, 0,
           world.awake, world._even, _DX, _DY)


@compiled
def _decide(cells, start, stop, counted, counts, where, into, chance, x, y, key, dx, dy):
    """What cell (x, y) becomes by the first of its element's rules that fires (-1: none; -2: one
    matched but its roll did not come up, so the cell must be looked at again)."""
    height, width = cells.shape
    e = cells[y, x]
    for r in range(start[e], stop[e]):
        n = 0
        for k in range(8):
            if (where[r] >> k) & 1:
                nx, ny = x + dx[k], y + dy[k]
                if 0 <= nx < width and 0 <= ny < height and counted[r, cells[ny, nx]]:
                    n += 1
        if (counts[r] >> n) & 1:
            if (_cell_key(key ^ r, x, y) >> (32 - ROLL_BITS)) < chance[r]:
                return np.int64(into[r])
            return np.int64(-2)
    return np.int64(-1)


@compiled
def _apply(s, t, start, stop, counted, counts, where, into, chance, tiles, key, awake, even, dx, dy):
    cells = s.cells
    height, width = cells.shape
    tiles_x = (width + TILE - 1) >> TILE_SHIFT
    changes = [(np.int64(0), np.int64(0), np.int64(0))]  # as many as there are: a tile's worth each would be 96 kB
    changes.pop()
    for tile in tiles:
        x0, y0 = (tile % tiles_x) << TILE_SHIFT, (tile // tiles_x) << TILE_SHIFT
        for y in range(y0, min(y0 + TILE, height)):
            for x in range(x0, min(x0 + TILE, width)):
                if start[cells[y, x]] == stop[cells[y, x]]:
                    continue
                becomes = _decide(cells, start, stop, counted, counts, where, into, chance, x, y, key, dx, dy)
                if becomes == -2:
                    wake_around(awake, even, x, y, width, height)  # it may fire next frame
                elif becomes >= 0 and becomes != cells[y, x]:
                    changes.append((np.int64(x), np.int64(y), becomes))
    for x, y, becomes in changes:  # together, once every cell is decided
        warmth = _temperature(int(s.heat[y, x]), t.heat_recip[cells[y, x]])
        become(s, t, x, y, becomes, warmth, LOOSE, _cell_key(key, x, y))
        wake_around(awake, even, x, y, width, height)
    return len(changes)
