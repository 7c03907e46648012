"""Painting from inside the kernel: what emitters and sprays put down every frame."""

from __future__ import annotations

import numpy as np

from .cells import _cell_key, become
from .jit import compiled
from .layout import CHUNK_SHIFT, LOOSE, WAKE_MARGIN, WHOLE
from .hashing import ROLL_BITS


@compiled
def paint_cells(s, t, ys, xs, element, cargo, vx, vy, only_empty, threshold, chance_key, spawn_key, awake, even):
    """:meth:`sandmod.world.world.World.paint_cells` for what is painted every frame: emitters and sprays.

    Each cell ``ys[i]``, ``xs[i]`` (an empty one, with ``only_empty``; a cell
    given twice counts once) whose roll under ``chance_key`` is below
    ``threshold`` becomes a newly born ``element`` (:func:`~.cells.become`)
    carrying ``cargo``, at its starting temperature; at rest and LOOSE, or,
    where ``vx`` and ``vy`` are given (1/256ths of a cell a frame, one per
    cell; empty: none), in flight at that velocity. The chunks within
    WAKE_MARGIN of it wake, their heat no longer known to be even. Returns
    how many were painted.

    The cells come out as the numpy method's (which builds scenes without
    numba; tests compare the two), without its few dozen array operations a
    call: for a few emitters, most of a small world's frame.
    """
    cells = s.cells
    height, width = cells.shape
    moving = len(vx) > 0
    painted = 0
    for i in range(len(ys)):
        y, x = np.int64(ys[i]), np.int64(xs[i])
        if only_empty and cells[y, x] != 0:
            continue
        if (_cell_key(chance_key, x, y) >> (32 - ROLL_BITS)) >= threshold:
            continue
        become(s, t, x, y, element, t.temp_start[element], 0 if moving else LOOSE, _cell_key(spawn_key, x, y))
        s.carry[y, x] = cargo
        if moving:
            s.vx[y, x], s.vy[y, x] = vx[i], vy[i]
        for wy in (max(y - WAKE_MARGIN, 0) >> CHUNK_SHIFT, min(y + WAKE_MARGIN, height - 1) >> CHUNK_SHIFT):
            for wx in (max(x - WAKE_MARGIN, 0) >> CHUNK_SHIFT, min(x + WAKE_MARGIN, width - 1) >> CHUNK_SHIFT):
                awake[wy, wx] = WHOLE
                even[wy, wx] = 0
        painted += 1
    return painted
