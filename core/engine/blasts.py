"""Explosions: the explosives that went off in a step, and blasts along rays stopped by resistant cells."""

from __future__ import annotations

import numpy as np

from .cells import LIQUID, MOVED, POWDER, _cell_key, _energy, _inside, _line_point, _mix32, _temperature, become
from .jit import compiled
from .layout import (
    BLAST_COLUMNS,
    BLAST_FLING,
    BLAST_HEAT,
    BLAST_LEAVES,
    BLAST_LEAVES_CHANCE,
    BLAST_RADIUS,
    BLAST_SCORCH,
    BLAST_SPEED,
    BLAST_STRENGTH,
    BLAST_X,
    BLAST_Y,
    CHUNK_SHIFT,
    DETONATING,
    LOOSE,
    NO_BREAK,
    SCORCHED,
    TILE,
    TILE_SHIFT,
    WAKE_MARGIN,
    WHOLE,
)

DESTROYED = 1  # a cell's mark in a blast: destroyed; from FRINGE on, in the fringe, FRINGE + d cells past the destruction
FRINGE = 2


@compiled
def take_detonations(s, t, detonations):
    """The blasts of the explosives that went off this step, top to bottom and left to right.

    Their cells are emptied (keeping their temperature); each blast then
    destroys its own centre.
    """
    cells, flags, heat = s.cells, s.flags, s.heat
    height, width = cells.shape
    tiles_y = (height + TILE - 1) >> TILE_SHIFT
    tiles_x = (width + TILE - 1) >> TILE_SHIFT
    rows = np.empty((detonations.sum(), BLAST_COLUMNS), np.int64)
    n = 0
    for ty in range(tiles_y):
        for y in range(ty << TILE_SHIFT, min((ty + 1) << TILE_SHIFT, height)):
            for tx in range(tiles_x):  # row by row across the tiles: the blasts come out in order
                if detonations[ty * tiles_x + tx] == 0:
                    continue
                for x in range(tx << TILE_SHIFT, min((tx + 1) << TILE_SHIFT, width)):
                    if (flags[y, x] & DETONATING) == 0:
                        continue
                    e = cells[y, x]
                    for c in range(BLAST_COLUMNS):  # not a slice: its shape check alone takes seconds to compile
                        rows[n, c] = t.blast[e, c]
                    rows[n, BLAST_X] = x
                    rows[n, BLAST_Y] = y
                    n += 1
                    heat[y, x] = _energy(_temperature(int(heat[y, x]), t.heat_recip[e]), t.heat_cap[0])
                    cells[y, x] = 0
                    flags[y, x] = MOVED
                    s.timer[y, x] = s.vx[y, x] = s.vy[y, x] = s.carry[y, x] = 0
    return rows


@compiled
def explode(s, t, blasts, count, key, particle, awake, even):
    """Set off the first ``count`` explosions of ``blasts``, one after another.

    Each blast sends a ray from its centre to every cell on the border of the
    square of side 2 x radius around it (:func:`_rays`), then changes the
    cells the rays marked (:func:`_blast`). The chunks a blast reaches are
    marked ``awake``, and lose their ``even`` mark.
    """
    for b in range(count):
        cx, cy = blasts[b, BLAST_X], blasts[b, BLAST_Y]
        reach = blasts[b, BLAST_RADIUS] + blasts[b, BLAST_SCORCH]
        for wy in range(max(cy - reach - WAKE_MARGIN, 0) >> CHUNK_SHIFT, min((cy + reach + WAKE_MARGIN) >> CHUNK_SHIFT, awake.shape[0] - 1) + 1):
            for wx in range(max(cx - reach - WAKE_MARGIN, 0) >> CHUNK_SHIFT, min((cx + reach + WAKE_MARGIN) >> CHUNK_SHIFT, awake.shape[1] - 1) + 1):
                awake[wy, wx] = WHOLE
                even[wy, wx] = 0
        mark = _rays(s.cells, t.resistance, cx, cy, blasts[b, BLAST_RADIUS], blasts[b, BLAST_STRENGTH], blasts[b, BLAST_SCORCH])
        _blast(s, t, blasts[b], mark, _mix32(key ^ (b * 0x9E3779B9)), particle)


@compiled
def _rays(cells, resistance, cx, cy, radius, strength, scorch):
    """Which cells a blast at (cx, cy) reaches: a square of marks of side 2 x (radius + scorch) + 1.

    The rays (they cover every cell of the disc) start with the blast's
    strength; each cell within the radius that resists no more than the ray
    has left is destroyed and costs the ray its resistance per cell of length,
    so the hole in uniform ground is round. A cell that resists more stops the
    destruction there. The ray then marks a fringe of ``scorch`` cells, and
    stops behind a cell no blast of this strength could break. Rays only read
    the world, so a cell that several rays reach is destroyed or scorched once,
    whatever the order of the rays.
    """
    height, width = cells.shape
    reach = radius + scorch
    mark = np.zeros((2 * reach + 1, 2 * reach + 1), np.int16)
    if _inside(cx, cy, width, height):
        mark[reach, reach] = DESTROYED
    for r in range(8 * radius):
        side = r // (2 * radius)
        o = r % (2 * radius)
        if side == 0:
            bx, by = o - radius, -radius
        elif side == 1:
            bx, by = radius, o - radius
        elif side == 2:
            bx, by = radius - o, radius
        else:
            bx, by = -radius, radius - o
        minor = min(abs(bx), abs(by))
        step_len = int(np.floor(256.0 * np.sqrt(float(radius * radius + minor * minor)) / radius + 0.5))
        left = strength
        destroying = True
        past = 0
        for k in range(1, reach + 1):
            qx, qy = _line_point(cx, cy, bx, by, radius, k)
            if not _inside(qx, qy, width, height):
                break
            ox = qx - cx
            oy = qy - cy
            c = cells[qy, qx]
            if destroying:
                if ox * ox + oy * oy <= radius * radius and resistance[c] <= left:
                    left -= (resistance[c] * step_len) >> 8
                    mark[oy + reach, ox + reach] = DESTROYED
                    continue
                destroying = False
            if past >= scorch:
                break
            m = mark[oy + reach, ox + reach]
            if c != 0 and m != DESTROYED and (m == 0 or m > FRINGE + past):
                mark[oy + reach, ox + reach] = FRINGE + past
            past += 1
            if resistance[c] > strength:
                break  # an unbreakable wall: nothing behind it is touched
    return mark


@compiled
def _blast(s, t, blast, mark, blast_key, particle):
    """Change the cells a blast marked: a destroyed cell whose element breaks (``breaks_into``) is
    taken for what it breaks into; destroyed powder and liquid cells may fly off as particles
    (away from the centre, fastest near it), other destroyed cells become what they broke into, or
    else what the blast leaves (by its chance) or nothing; scorched cells darken, with a chance that
    falls off across the fringe. Every cell it touches is heated to at least the blast's heat."""
    cells, flags, heat = s.cells, s.flags, s.heat
    cx, cy, radius, scorch = blast[BLAST_X], blast[BLAST_Y], blast[BLAST_RADIUS], blast[BLAST_SCORCH]
    leaves, leaves_chance, fling = blast[BLAST_LEAVES], blast[BLAST_LEAVES_CHANCE], blast[BLAST_FLING]
    speed, hot = blast[BLAST_SPEED], blast[BLAST_HEAT]
    reach = radius + scorch
    for my in range(2 * reach + 1):
        for mx in range(2 * reach + 1):
            m = mark[my, mx]
            if m == 0:
                continue
            ox = mx - reach
            oy = my - reach
            qx = cx + ox
            qy = cy + oy
            c = cells[qy, qx]
            h = _cell_key(blast_key, qx, qy)
            roll = h >> 8
            warmth = max(_temperature(int(heat[qy, qx]), t.heat_recip[c]), hot)
            if m == DESTROYED:
                broken = t.breaks_into[c] != NO_BREAK
                if broken:
                    c = t.breaks_into[c]  # what is left of it: flung or left as any destroyed cell is, never `leaves`
                kind = t.archetype[c]
                if (kind == POWDER or kind == LIQUID) and roll < fling:
                    dist = np.sqrt(float(ox * ox + oy * oy))
                    if dist == 0.0:
                        angle = (h & 255) * (2.0 * np.pi / 256.0)
                        dx, dy = np.cos(angle), np.sin(angle)
                    else:
                        dx, dy = ox / dist, oy / dist
                    v = speed * (1.0 - dist / (radius + 1.0)) * (0.6 + 0.4 * ((h & 255) / 256.0))
                    cells[qy, qx] = particle
                    s.carry[qy, qx] = c
                    s.vx[qy, qx] = int(np.floor(dx * v + 0.5))
                    s.vy[qy, qx] = int(np.floor(dy * v + 0.5))
                    flags[qy, qx] = 0
                    heat[qy, qx] = _energy(warmth, t.heat_cap[particle])
                else:
                    into = c if broken else (leaves if (_mix32(h) >> 8) < leaves_chance else 0)
                    become(s, t, qx, qy, into, warmth, LOOSE, h)
            elif roll % (scorch + 1) < scorch - (m - FRINGE):  # scorched: chance (scorch - d) / (scorch + 1)
                flags[qy, qx] |= SCORCHED
                heat[qy, qx] = _energy(warmth, t.heat_cap[c])
