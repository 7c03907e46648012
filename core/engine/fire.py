"""A cell's own heat, the first phase of its update: phase changes, catching fire, burning, lighting neighbours.

Conduction between cells is :mod:`.heat`'s; this is what a cell's heat does to
the cell. Each phase of the per-cell update returns ``(done, busy, stir, born)``:
the cell's update ends here; something changed, or may on a later frame (its
region stays awake); the heat field or an element changed (its chunk is swept
again); the bits of the elements it made (for the mask of elements present).
"""

from __future__ import annotations

import numpy as np

from .cells import DONE, FRESH, MOVED, _at, _cell_key, _inside, _mix32, _plume_roll, _temperature, become
from .jit import compiled, inlined
from .layout import BURNING, DETONATING, EXPLOSIVE, FLAMMABLE, IGNITES, LOOSE, TEMP_ONE


SURE_CHANGE = 128  # of 256: the most a phase change with a spread comes about in a frame


@compiled
def _comes_about(past, spread, fire_key, x, y):
    """Does a phase change come about this frame, ``past`` the point (in energy) by a ``spread``?
    Without one, at once; with one, by a chance that grows with how far past the point the cell is,
    up to SURE_CHANGE at the spread's end, rolled once for each plume block of cells: a floor heated
    evenly, however hot, boils in bubbles, not as one sheet."""
    if spread == 0:
        return True
    return (_plume_roll(fire_key, x, y) >> 24) < min(SURE_CHANGE, (past * SURE_CHANGE) // spread)


@inlined
def heat_and_fire(s, t, x, y, e, fire_key, spawn_key, detonations, tile):
    """Phase 1: past a phase change the cell becomes its heated or cooled element; a flammable cell
    at its ignition heat catches fire; a burning one burns (:func:`_burn`), or, explosive, goes off
    (marked DETONATING and counted in ``detonations[tile]``); a flame lights its neighbours (:func:`_light`)."""
    flags, heat = s.flags, s.heat
    f = flags[_at(y, x)]
    th = t.thermal[e]
    if (f & BURNING) == 0 and (th == 0 or ((th & (FLAMMABLE | IGNITES)) == 0 and t.cold_limit[e] <= heat[_at(y, x)] <= t.hot_limit[e])):
        return False, False, False, np.int64(0)  # calm (the common case): not burning, no flame, between its phase changes
    busy = stir = False
    born = np.int64(0)
    energy = int(heat[_at(y, x)])
    into = e
    keeps, gain = True, 0  # a phase change keeps the temperature, or, with a latent heat, the heat plus gain
    if energy > t.hot_limit[e]:
        if _comes_about(energy - t.hot_limit[e], t.hot_spread[e], fire_key, x, y):
            into, keeps, gain = t.heated_into[e], t.hot_latent[e] < 0, -t.hot_latent[e]
    elif energy < t.cold_limit[e]:
        if _comes_about(t.cold_limit[e] - energy, t.cold_spread[e], fire_key, x, y):
            into, keeps, gain = t.cooled_into[e], t.cold_latent[e] < 0, t.cold_latent[e]
    elif (th & FLAMMABLE) != 0 and (f & BURNING) == 0 and energy >= t.ignite_limit[e]:
        f |= BURNING
        s.timer[_at(y, x)] = t.burn_frames[e] + (_cell_key(fire_key, x, y) >> 8) % (t.burn_jitter[e] + 1)
    lit = into == e and ((f & BURNING) != 0 or (th & IGNITES) != 0)
    fh = _cell_key(fire_key ^ 0x5BD1E995, x, y) if lit else 0  # rolls for fire, only where there is fire
    if into == e and (f & BURNING) != 0:
        busy = True
        if (th & EXPLOSIVE) != 0:  # it goes off: frozen for the rest of the frame, then the step's blasts are applied
            flags[_at(y, x)] = f | DETONATING | DONE
            detonations[tile] += 1
            return True, True, False, born
        f, energy, into, stir, born = _burn(s, t, x, y, e, f, energy, fh, fire_key, spawn_key)
    if into == e and ((f & BURNING) != 0 or (th & IGNITES) != 0):
        busy = _light(s, t, x, y, fh, fire_key) or busy
    if into != e:
        temperature = _temperature(energy, t.heat_recip[e]) if keeps else _temperature(energy + gain, t.heat_recip[into])
        born |= become(s, t, x, y, into, temperature, (f & FRESH) | MOVED, _cell_key(spawn_key, x, y))
        return True, True, True, born
    if energy != heat[_at(y, x)]:
        heat[_at(y, x)] = energy
        busy = stir = True
    if f != flags[_at(y, x)]:
        flags[_at(y, x)] = f
        busy = True
    return False, busy, stir, born


@inlined
def _burn(s, t, x, y, e, f, energy, fh, fire_key, spawn_key):
    """A burning cell next to an extinguisher goes out (cooled to just below catching fire again);
    else it heats up to its burning heat, and burns out into ash (by a chance) or nothing, or,
    still burning, may put a flame in an empty neighbour. Returns its flags, energy and element,
    whether a flame was born, and the flame's bit."""
    cells = s.cells
    height, width = cells.shape
    out = False
    for k in range(4):
        nx = x + (1, 0, -1, 0)[k]
        ny = y + (0, 1, 0, -1)[k]
        if _inside(nx, ny, width, height) and t.extinguishes[cells[_at(ny, nx)]] != 0:
            out = True
    if out:
        return f & ~BURNING, min(energy, t.ignite_limit[e] - t.heat_cap[e] * TEMP_ONE), e, False, np.int64(0)
    if energy < t.burn_limit[e]:
        energy = min(energy + t.burn_heat[e], t.burn_limit[e])
    left = s.timer[_at(y, x)]
    if left <= 1:  # burnt out
        return f, energy, (t.ash[e] if ((fh >> 8) & 0xFFFFFF) < t.ash_chance[e] else 0), False, np.int64(0)
    s.timer[_at(y, x)] = left - 1
    d = fh & 3
    nx = x + (1, 0, -1, 0)[d]
    ny = y + (0, 1, 0, -1)[d]
    product = t.flame[e]
    if product != 0 and _inside(nx, ny, width, height) and cells[_at(ny, nx)] == 0:
        if (_cell_key(fire_key ^ 0x68E31DA4, x, y) >> 8) < t.flame_chance[e]:
            born = become(s, t, nx, ny, product, t.temp_start[product], MOVED | LOOSE, _cell_key(spawn_key, nx, ny))
            return f, energy, e, True, born
    return f, energy, e, False, np.int64(0)


@inlined
def _light(s, t, x, y, fh, fire_key):
    """A flame lights the flammable cells it touches, each by its own chance; True if any could catch."""
    cells, flags = s.cells, s.flags
    height, width = cells.shape
    busy = False
    for k in range(4):
        nx = x + (1, 0, -1, 0)[k]
        ny = y + (0, 1, 0, -1)[k]
        if not _inside(nx, ny, width, height):
            continue
        n = cells[_at(ny, nx)]
        if (t.thermal[n] & FLAMMABLE) != 0 and (flags[_at(ny, nx)] & BURNING) == 0:
            busy = True  # lit now, or maybe on a later frame
            if (_mix32(fh ^ (k + 1) * 0x9E3779B9) >> 8) < t.catch_chance[n]:
                flags[_at(ny, nx)] |= BURNING
                s.timer[_at(ny, nx)] = t.burn_frames[n] + (_cell_key(fire_key, nx, ny) >> 8) % (t.burn_jitter[n] + 1)
    return busy
