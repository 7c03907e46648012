"""The compiled forms of the behaviour helpers (:mod:`sandmod.formats.behaviour`), for numba.

Importing this module imports numba (through :mod:`sandmod.engine.jit`, which sets
its cache folder first) and registers an implementation for each helper, so that
a behaviour calling ``look(v, 0, -1)`` compiles. A change of a cell goes as the
kernel's ``become`` makes one: a new shade and lifetime, at rest, the temperature
the cell had, MOVED and LOOSE; its chunk, and those within WAKE_MARGIN, woken and
their heat no longer known to be even.

The hash functions are compiled here, not taken from the engine's compiled ones:
a call from here with other types would add to the kernel's cache.
"""

from __future__ import annotations

import numpy as np

from ..engine import hashing
from ..engine.jit import njit
from ..engine.layout import CHUNK_SHIFT, LOOSE, MAX_TEMPERATURE, MIN_TEMPERATURE, MOVED, TEMP_ONE
from ..formats import behaviour as api
from .visit import wake_around
from numba.extending import overload

_mix32 = njit(hashing.mix32)
_spawn_state = njit(hashing.spawn_state)
#: Salts of the behaviours' own uses of the frame's key.
SALT_DRAW = 0x6C8E9CF5
SALT_BORN = 0x1D872B41
T_LOW, T_HIGH = int(MIN_TEMPERATURE * TEMP_ONE), int(MAX_TEMPERATURE * TEMP_ONE)


@njit
def _reaches(v, dx, dy):
    """Is the cell at (dx, dy) from the view's within reach and in the world?"""
    height, width = v.cells.shape
    x, y = v.x + dx, v.y + dy
    return -api.REACH <= dx <= api.REACH and -api.REACH <= dy <= api.REACH and 0 <= x < width and 0 <= y < height


@njit
def _temperature_units(v, x, y):
    """Cell (x, y)'s temperature, TEMP_ONE units, as the kernel reads it."""
    energy = np.int64(v.heat[y, x])
    recip = v.heat_recip[v.cells[y, x]]
    return (energy * recip) >> 32 if energy >= 0 else -((-energy * recip) >> 32)


@njit
def _touched(v, x, y, was):
    """Cell (x, y), element ``was`` before, was changed by a behaviour: done for the frame, its
    chunks woken; its chunk held (walked next frame) if it is a behaviour's element now, and
    to be checked again (2) if it was one."""
    v.stamp[y, x] = np.uint32((v.frame + 1) & 0xFFFFFFFF)
    height, width = v.cells.shape
    wake_around(v.awake, v.even, x, y, width, height)
    cy, cx = y >> CHUNK_SHIFT, x >> CHUNK_SHIFT
    if v.codes[was] != 0:
        v.held[cy, cx] = 2
    elif v.codes[v.cells[y, x]] != 0:
        v.held[cy, cx] = max(v.held[cy, cx], 1)


@njit
def recheck(cells, codes, held):
    """Chunks marked 2 (a behaviour cell changed there): 1 if they still hold one, else 0."""
    height, width = cells.shape
    chunks_y, chunks_x = held.shape
    for cy in range(chunks_y):
        for cx in range(chunks_x):
            if held[cy, cx] == 2:
                held[cy, cx] = 0
                for y in range(cy << CHUNK_SHIFT, min((cy + 1) << CHUNK_SHIFT, height)):
                    for x in range(cx << CHUNK_SHIFT, min((cx + 1) << CHUNK_SHIFT, width)):
                        if codes[cells[y, x]] != 0:
                            held[cy, cx] = 1


@overload(api.look)
def _look(v, dx, dy):
    def look(v, dx, dy):
        return np.int64(v.cells[v.y + dy, v.x + dx]) if _reaches(v, dx, dy) else np.int64(-1)

    return look


@overload(api.here)
def _here(v):
    return lambda v: np.int64(v.element)


@overload(api.frame)
def _frame(v):
    return lambda v: np.int64(v.frame)


@overload(api.put)
def _put(v, dx, dy, element):
    def put(v, dx, dy, element):
        if not _reaches(v, dx, dy) or not 0 <= element < len(v.codes):
            return False
        x, y = v.x + dx, v.y + dy
        was = v.cells[y, x]
        warmth = max(T_LOW, min(T_HIGH, _temperature_units(v, x, y)))
        h = _mix32(_mix32(v.key ^ SALT_BORN) ^ ((y << 16) | x))
        v.cells[y, x] = element
        v.shade[y, x], v.timer[y, x] = _spawn_state(h, v.life_frames[element], v.life_jitter[element])
        v.vx[y, x] = v.vy[y, x] = 0
        if v.remembers[element] == 0:
            v.carry[y, x] = 0  # what it held, kept where the new element can hold (as the kernel's become)
        v.heat[y, x] = warmth * v.heat_cap[element]
        v.flags[y, x] = MOVED | LOOSE
        _touched(v, x, y, was)
        return True

    return put


@overload(api.swap)
def _swap(v, dx, dy):
    def swap(v, dx, dy):
        if not _reaches(v, dx, dy):
            return False
        x, y, qx, qy = v.x, v.y, v.x + dx, v.y + dy
        was, other = v.cells[y, x], v.cells[qy, qx]
        for a in (v.cells, v.carry):
            a[y, x], a[qy, qx] = a[qy, qx], a[y, x]
        v.shade[y, x], v.shade[qy, qx] = v.shade[qy, qx], v.shade[y, x]
        v.timer[y, x], v.timer[qy, qx] = v.timer[qy, qx], v.timer[y, x]
        v.flags[y, x], v.flags[qy, qx] = v.flags[qy, qx] | MOVED, v.flags[y, x] | MOVED
        v.heat[y, x], v.heat[qy, qx] = v.heat[qy, qx], v.heat[y, x]
        for a in (v.vx, v.vy):
            a[y, x], a[qy, qx] = a[qy, qx], a[y, x]
        _touched(v, x, y, was)
        _touched(v, qx, qy, other)
        return True

    return swap


@overload(api.temperature)
def _temperature(v, dx, dy):
    def temperature(v, dx, dy):
        if not _reaches(v, dx, dy):
            return np.nan
        return _temperature_units(v, v.x + dx, v.y + dy) / TEMP_ONE

    return temperature


@overload(api.random)
def _random(v):
    def random(v):
        n = v.draws[0]
        v.draws[0] = n + 1
        h = _mix32(_mix32(v.key ^ SALT_DRAW ^ ((v.y << 16) | v.x)) ^ n)
        return (h >> 8) / 16777216.0

    return random


@overload(api.chance)
def _chance(v, p):
    return lambda v, p: api.random(v) < p


@overload(api.arg)
def _arg(v, k):
    return lambda v, k: v.args[v.element, k]


_registered: set = set()


def register_marked() -> None:
    """Give numba the plugins' functions marked with ``sandmod.api.helper`` since the last call."""
    for function in api.MARKED:
        if function not in _registered:
            overload(function, strict=False)(lambda *args, _f=function: _f)
            _registered.add(function)


register_marked()
