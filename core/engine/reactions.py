"""Phases 2 and 3 of a cell's update: its lifetime runs out, or it reacts with a touching neighbour.

Each returns ``(done, busy, stir, born)`` as the phases of :mod:`.fire` do.
"""

from __future__ import annotations

import numpy as np

from .cells import FRESH, GAS, LIQUID, MOVED, POWDER, _at, _bit, _cell_key, _energy, _inside, _mix32, _temperature, become, referred
from .jit import in_place, inlined
from .layout import BURNING, HELD, KEEPS, REACTED, REFERS, STAYS


@inlined
def lifetime(s, t, x, y, e, spawn_key):
    """Phase 2: a cell with a lifetime counts down, and at zero becomes its ``life_into`` (HELD:
    what it holds), not while burning."""
    if t.life_frames[e] == 0 or (s.flags[_at(y, x)] & BURNING) != 0:
        return False, False, False, np.int64(0)
    left = s.timer[_at(y, x)]
    if left <= 1:
        into = t.life_into[e]
        if into == HELD:
            into = s.carry[_at(y, x)]
        temperature = _temperature(int(s.heat[_at(y, x)]), t.heat_recip[e])
        born = become(s, t, x, y, into, temperature, (s.flags[_at(y, x)] & FRESH) | MOVED, _cell_key(spawn_key, x, y))
        return True, True, True, born
    s.timer[_at(y, x)] = left - 1
    return False, True, False, np.int64(0)


@inlined
def react(s, t, x, y, e, present, move_key, react_key, spawn_key):
    """Phase 3: try each touching neighbour once, in a hashed order, for a reaction; the first that
    comes up turns both cells into its products, warmed by its heat, and marks both REACTED (once
    a frame). Done if the cell became another element; one the reaction left as it was goes on to move.

    First a cheap test: does any neighbour's bit show in the element's partner mask (``present``:
    the elements that may be next to it)?
    """
    cells, flags, heat = s.cells, s.flags, s.heat
    height, width = cells.shape
    partners = t.reactive[e] & present
    if partners != 0 and (flags[_at(y, x)] & REACTED) != 0:
        partners = 0  # once a frame
    if partners != 0:
        near = 0
        if x + 1 < width:
            near |= _bit(cells[_at(y, x + 1)])
        if y + 1 < height:
            near |= _bit(cells[_at(y + 1, x)])
        if x > 0:
            near |= _bit(cells[_at(y, x - 1)])
        if y > 0:
            near |= _bit(cells[_at(y - 1, x)])
        partners &= near
    busy = stir = False
    born = np.int64(0)
    if partners == 0:
        return False, busy, stir, born
    start = (_cell_key(move_key, x, y) >> 1) & 3
    for k in range(4):
        d = (start + k) & 3
        nx = x + (1, 0, -1, 0)[d]
        ny = y + (0, 1, 0, -1)[d]
        if not _inside(nx, ny, width, height) or (flags[_at(ny, nx)] & REACTED) != 0:
            continue
        b = cells[_at(ny, nx)]
        group = t.react_pair[e, b]
        if group == 0:
            continue
        row = t.react_group[group, d]  # the reaction of b on this side of the cell
        if row == 0:
            continue
        threshold = t.react_chance[row]
        # One roll per touching pair and frame, the same whichever cell looks.
        roll = _mix32(react_key ^ ((min(y, ny) << 16) | min(x, nx)) ^ ((d & 1) << 31)) >> 8
        ta = _temperature(int(heat[_at(y, x)]), t.heat_recip[e])
        tb = _temperature(int(heat[_at(ny, nx)]), t.heat_recip[b])
        if ta + tb < t.react_tsum_min[row] or ta + tb > t.react_tsum_max[row]:
            continue
        busy = True  # it reacts now, or may on a later frame
        if roll >= threshold:
            continue
        into_a = e if t.react_into_a[row] == STAYS else t.react_into_a[row]
        into_b = b if t.react_into_b[row] == STAYS else t.react_into_b[row]
        held_a = held_b = 0
        if t.react_holds[row] != 0:  # it names what a cell holds or was (rare)
            held_a, held_b = s.carry[_at(y, x)], s.carry[_at(ny, nx)]
            if into_a >= REFERS:
                into_a = referred(into_a, e, b, held_a, held_b)
            if into_b >= REFERS:
                into_b = referred(into_b, e, b, held_a, held_b)
        warm = t.react_heat[row]
        if into_a != e:
            born |= become(s, t, x, y, into_a, ta + warm, (flags[_at(y, x)] & FRESH) | MOVED, _cell_key(spawn_key, x, y))
            stir = True
        if into_b != b:
            born |= become(s, t, nx, ny, into_b, tb + warm, (flags[_at(ny, nx)] & FRESH) | MOVED, _cell_key(spawn_key, nx, ny))
            stir = True
        if t.react_holds[row] != 0:
            hold(s, t, x, y, into_a, t.react_holds_a[row], e, b, held_a, held_b)
            hold(s, t, nx, ny, into_b, t.react_holds_b[row], e, b, held_a, held_b)
        flags[_at(y, x)] |= REACTED
        flags[_at(ny, nx)] |= REACTED
        flew = False
        if t.react_push_b[row] != 0 and _pushable(t, into_b):
            born |= fly(s, t, nx, ny, into_b, t.react_push_b[row], d)
            stir = True
        if t.react_push_a[row] != 0 and _pushable(t, into_a):
            born |= fly(s, t, x, y, into_a, t.react_push_a[row], (d + 2) & 3)
            stir = flew = True
        return into_a != e or flew, busy, stir, born
    return False, busy, stir, born


@in_place  # rare: called, not copied into the cell update
def hold(s, t, x, y, now, code, a, b, held_a, held_b):
    """After a reaction of a cell of ``a`` holding ``held_a`` with one of ``b`` holding ``held_b``, the
    cell at (x, y), of element ``now``, holds what ``code`` names (``Tables.react_holds_a``: KEEPS
    leaves it), where ``now`` can hold."""
    if code != KEEPS and t.remembers[now] != 0:
        s.carry[_at(y, x)] = referred(code, a, b, held_a, held_b) if code >= REFERS else code


@inlined
def _pushable(t, e):
    """Can a cell of element e be pushed: is it a powder, a liquid or a gas?"""
    kind = t.archetype[e]
    return kind == POWDER or kind == LIQUID or kind == GAS


@in_place  # rare (a push): called, not copied into the cell update, which compiles faster so
def fly(s, t, x, y, cargo, speed, d):
    """Cell (x, y), of element ``cargo``, flies off towards side ``d`` (see layout.SIDES) at ``speed``
    (SUBCELL units) as ``t.particle[0]`` carrying it: its shade and temperature kept, its lifetime
    dropped, done for the frame. Returns the particle's bit, for the mask of elements present."""
    particle = t.particle[0]
    temperature = _temperature(int(s.heat[_at(y, x)]), t.heat_recip[cargo])
    s.cells[_at(y, x)] = particle
    s.carry[_at(y, x)] = cargo
    s.vx[_at(y, x)] = speed * (1, 0, -1, 0)[d]
    s.vy[_at(y, x)] = speed * (0, 1, 0, -1)[d]
    s.timer[_at(y, x)] = 0
    s.heat[_at(y, x)] = _energy(temperature, t.heat_cap[particle])
    s.flags[_at(y, x)] = MOVED | REACTED
    return _bit(particle)
