"""A cell: how it is indexed, hashed and measured, and the two ways it changes (:func:`become`, :func:`swap`).

Every change of a cell's element goes through :func:`become`, and every move
through :func:`swap`, so the flag bits a cell keeps are decided in one place
each. The helpers take and return plain numbers; LLVM inlines them.
"""

from __future__ import annotations

import numpy as np

from . import hashing, traversal
from .jit import compiled, inlined
from .layout import ARCHETYPE_CODES, BURNING, HELD_A, WAS_A, WAS_B, LOOSE, MAX_TEMPERATURE, MIN_TEMPERATURE, MOVED, mask_bit, PLUME, PLUME_RUN, PLUME_RUN_SHIFT, PLUME_SHIFT, REACTED, SCORCHED, TEMP_ONE

STATIC = ARCHETYPE_CODES["static"]
POWDER = ARCHETYPE_CODES["powder"]
LIQUID = ARCHETYPE_CODES["liquid"]
GAS = ARCHETYPE_CODES["gas"]
PARTICLE = ARCHETYPE_CODES["particle"]

DONE = MOVED | REACTED  # flag bits of a cell no other may move this frame
KEPT = LOOSE | BURNING | SCORCHED  # flag bits that travel with a cell from frame to frame
CARRIED = KEPT | REACTED  # and those it takes along when it moves (REACTED until the frame ends)
FRESH = ~(BURNING | SCORCHED)  # a cell turning into another element keeps only these flag bits
T_LOW = int(MIN_TEMPERATURE * TEMP_ONE)
T_HIGH = int(MAX_TEMPERATURE * TEMP_ONE)

_mix32 = compiled(hashing.mix32)
_spawn_state = compiled(hashing.spawn_state)
_line_point = compiled(traversal.line_point)


@compiled
def _at(y, x):
    """The index of row y, column x of a world-sized (or chunk-sized) array, in bounds (the caller checks).

    Unsigned, so numba leaves out its wrap-around of negative indices: a fifth
    of the per-cell time. A negative index here would read out of bounds, not
    from the far edge, so test coordinates before reading (as every cell read
    does); ``tests/test_bounds.py`` runs busy worlds with bounds checks on.
    """
    return np.uint64(y), np.uint64(x)


@compiled
def _within(v, limit):
    """0 <= v < limit, in one unsigned comparison (a negative v wraps to a huge one)."""
    return np.uint64(v) < np.uint64(limit)


@compiled
def _inside(x, y, width, height):
    """Is cell (x, y) in the world? Two comparisons instead of four."""
    return _within(x, width) and _within(y, height)


@compiled
def _cell_key(key, x, y):
    """The hash of cell (x, y) under a frame key."""
    return _mix32(key ^ ((y << 16) | x))


@compiled
def _plume_roll(key, x, y):
    """The exchange roll of cell (x, y) this frame: one hash for every cell of its plume block
    (see :data:`~.layout.PLUME`), so that the cells of a block trade places with fluids together.
    The grid's columns shift with the frame's key, and each column of blocks is shifted up or
    down by a hash of its own, as bricks are laid, so that no edge runs along a whole row."""
    bx = (x + (key & (PLUME - 1))) >> PLUME_SHIFT
    by = (y + (_mix32(key ^ bx) & (PLUME_RUN - 1))) >> PLUME_RUN_SHIFT
    return _mix32(key ^ ((by << 16) | bx))


@compiled
def _run_end(key, x, y, g):
    """The last row, going against ``g`` (up, for a faller), of the run of PLUME_RUN rows that row
    y of column x is in this frame (each column's runs shifted by a hash of its own)."""
    shift = _mix32(key ^ hashing.SALT_RUN ^ x) & (PLUME_RUN - 1)
    first = (((y + shift) >> PLUME_RUN_SHIFT) << PLUME_RUN_SHIFT) - shift
    return first if g > 0 else first + PLUME_RUN - 1


_mask_bit = compiled(mask_bit)


@compiled
def _bit(e):
    """Element e's bit in the element masks (``reactive``, ``displaces``): see :func:`~.layout.mask_bit`."""
    return np.int64(1) << _mask_bit(e)


@compiled
def _enterable(displaceable, occupant, occupant_flags):
    """May a mover take this place? Only lighter fluids give way, and not twice a frame
    (empty cells excepted: they have nothing to lose)."""
    return displaceable != 0 and (occupant == 0 or (occupant_flags & DONE) == 0)


@compiled
def _cells_moved(speed, roll):
    """A speed in 1/256ths of a cell, rounded to whole cells at random (roll: 0..255), unbiased."""
    return (speed >> 8) + (1 if (speed & 255) > roll else 0)


@compiled
def _scaled(value, keep):
    """value * keep / 256, rounded towards zero."""
    return (value * keep) >> 8 if value >= 0 else -((-value * keep) >> 8)


@compiled
def _clamped(value, limit):
    return max(-limit, min(limit, value))


@compiled
def _temperature(energy, recip):
    """A cell's temperature (TEMP_ONE units) from its heat energy and 2**32 / heat capacity.

    Exact for energies that are whole multiples of the capacity, below zero too.
    """
    return (energy * recip) >> 32 if energy >= 0 else -((-energy * recip) >> 32)


@compiled
def _energy(temperature, cap):
    """The heat energy of a cell at ``temperature`` (clamped to the allowed range)."""
    return max(T_LOW, min(T_HIGH, temperature)) * cap


@compiled
def referred(code, a, b, held_a, held_b):
    """The element a reaction's code from :data:`~.layout.REFERS` up names: what the first cell (of
    element ``a``, holding ``held_a``) or the second was, or what it held."""
    if code == WAS_A:
        return a
    if code == WAS_B:
        return b
    return held_a if code == HELD_A else held_b


@inlined
def become(s, t, x, y, into, temperature, flags, roll):
    """Cell (x, y) becomes a new cell of element ``into``: at rest, at ``temperature``, with exactly
    the flag bits ``flags``, and the shade and lifetime that ``roll`` (a hash) gives it; holding
    what it held where ``into`` can hold (``Tables.remembers``), else nothing. Returns ``into``'s
    bit, for the mask of elements present."""
    s.cells[_at(y, x)] = into
    s.shade[_at(y, x)], s.timer[_at(y, x)] = _spawn_state(roll, t.life_frames[into], t.life_jitter[into])
    s.vx[_at(y, x)] = s.vy[_at(y, x)] = 0
    if t.remembers[into] == 0:
        s.carry[_at(y, x)] = 0
    s.heat[_at(y, x)] = _energy(temperature, t.heat_cap[into])
    s.flags[_at(y, x)] = flags
    return _bit(into)


@inlined
def swap(s, x, y, px, py, carries):
    """The mover at (x, y) and the cell at (px, py) trade places: element, shade, timer, heat, and
    what they hold where ``carries`` (a particle's cargo; where a powder, liquid or gas can hold,
    ``Tables.movers_hold``, either cell's).

    The cell left behind takes the other's velocity and flag bits; traded up or
    down, or into an empty cell, it is done for the frame, but traded sideways a
    mover above or below may still take its place. The mover's own velocity and
    flags at (px, py) are the caller's to set.
    """
    cells, shade, timer, heat, vx, vy, flags = s.cells, s.shade, s.timer, s.heat, s.vx, s.vy, s.flags
    entered = cells[_at(py, px)]
    cells[_at(py, px)] = cells[_at(y, x)]
    cells[_at(y, x)] = entered
    shade[_at(y, x)], shade[_at(py, px)] = shade[_at(py, px)], shade[_at(y, x)]
    timer[_at(y, x)], timer[_at(py, px)] = timer[_at(py, px)], timer[_at(y, x)]
    if carries:
        s.carry[_at(y, x)], s.carry[_at(py, px)] = s.carry[_at(py, px)], s.carry[_at(y, x)]
    heat[_at(y, x)], heat[_at(py, px)] = heat[_at(py, px)], heat[_at(y, x)]
    vx[_at(y, x)] = vx[_at(py, px)]
    vy[_at(y, x)] = vy[_at(py, px)]
    flags[_at(y, x)] = (MOVED if py != y or entered == 0 else 0) | (flags[_at(py, px)] & CARRIED)
