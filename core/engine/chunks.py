"""Sleeping chunks and tiles: the wake marks of 32 x 32 chunks, and the passes of 64 x 64 tiles.

A chunk's mark in ``awake`` (last frame's) or ``woken`` (this frame's, one
cache line per chunk, entry ``[cy, cx, 0]``) names the rows of the chunk to
update: none, all (WHOLE), or a run of rows (PART, see
:data:`sandmod.engine.layout.WHOLE`). Tiles of 2 x 2 chunks are updated in
four passes by the parity of their column and row (see
:func:`sandmod.engine.kernel.step`).
"""

from __future__ import annotations

import numpy as np

from .cells import KEPT
from .jit import compiled, inlined
from .layout import CHUNK, CHUNK_SHIFT, PART, TILE_SHIFT, WAKE_MARGIN, WHOLE


@compiled
def _mark(cy, cx):
    """The index of chunk (cy, cx)'s entry in ``woken`` or ``stirred`` (each entry on a cache line of its own)."""
    return np.uint64(cy), np.uint64(cx), np.uint64(0)


@compiled
def _first_row(mark):
    """The first (chunk-local) row a PART wake mark names."""
    return mark & 63


@compiled
def _last_row(mark):
    """The last (chunk-local) row a PART wake mark names."""
    return (mark >> 6) & 63


@compiled
def _widened(mark, y0, y1):
    """A chunk's wake mark widened to cover its rows y0..y1 (chunk-local)."""
    if mark == WHOLE:
        return WHOLE
    if mark != 0:
        y0 = min(y0, _first_row(mark))
        y1 = max(y1, _last_row(mark))
    if y0 == 0 and y1 == CHUNK - 1:
        return WHOLE  # quicker to read, and to widen
    return PART | y0 | (y1 << 6)


@compiled
def _covers(mark, row):
    """Does a chunk's wake mark cover its (chunk-local) row?"""
    return mark == WHOLE or (mark != 0 and _first_row(mark) <= row <= _last_row(mark))


@compiled
def _grown(x0, y0, x1, y1, width, height):
    """The cells x0..x1, y0..y1 and those within WAKE_MARGIN of them, in the world (inclusive)."""
    return max(x0 - WAKE_MARGIN, 0), max(y0 - WAKE_MARGIN, 0), min(x1 + WAKE_MARGIN, width - 1), min(y1 + WAKE_MARGIN, height - 1)


@inlined
def _wake(woken, stirred, stir, x0, y0, x1, y1):
    """Mark the cells x0..x1, y0..y1 (in the world, inclusive) in the wake marks of their chunks, and stir those chunks if ``stir``."""
    for wy in range(y0 >> CHUNK_SHIFT, (y1 >> CHUNK_SHIFT) + 1):
        oy = wy << CHUNK_SHIFT
        for wx in range(x0 >> CHUNK_SHIFT, (x1 >> CHUNK_SHIFT) + 1):
            woken[_mark(wy, wx)] = _widened(woken[_mark(wy, wx)], max(y0 - oy, 0), min(y1 - oy, CHUNK - 1))
            if stir:
                stirred[_mark(wy, wx)] = 1


@compiled
def _pass_tiles(p, frame):
    """The parity of the tiles' columns and rows that pass p (0..3) of a frame updates.

    The order of the four passes changes with the frame, so a falling stream
    crosses each seam in step (see :func:`sandmod.engine.kernel.step`)."""
    return (p & 1) ^ ((frame >> 1) & 1), (p >> 1) ^ (frame & 1) ^ 1


@compiled
def _pass_of(tx, ty, frame):
    """The pass (0..3) of a frame in which tile (tx, ty) is updated."""
    for p in range(4):
        px, py = _pass_tiles(p, frame)
        if px == (tx & 1) and py == (ty & 1):
            return p
    return -1


@compiled
def _unvisited(qx, qy, x, y, forward, x0, y0, x1, y1, frame):
    """Is cell (qx, qy) still to have its turn this frame, while (x, y) has its own in the
    region x0..x1-1, y0..y1-1 (rows bottom-up, each row forward or back)? A cell of another
    tile has it if that tile's pass comes later."""
    if x0 <= qx < x1 and y0 <= qy < y1:
        return qy < y or (qy == y and (qx > x) == forward)
    return _pass_of(qx >> TILE_SHIFT, qy >> TILE_SHIFT, frame) > _pass_of(x0 >> TILE_SHIFT, y0 >> TILE_SHIFT, frame)


@compiled
def clear_marks(flags, awake):
    """Forget last frame's moved and reacted marks, in the awake chunks (no others have any)."""
    height, width = flags.shape
    chunks_y, chunks_x = awake.shape
    for cy in range(chunks_y):
        for y in range(cy << CHUNK_SHIFT, min((cy + 1) << CHUNK_SHIFT, height)):
            row = flags[y]
            for cx in range(chunks_x):
                if awake[cy, cx] != 0:
                    run = row[cx << CHUNK_SHIFT : min((cx + 1) << CHUNK_SHIFT, width)]
                    run &= np.uint8(KEPT)  # a whole-slice operation: numba vectorises it, a loop it did not
