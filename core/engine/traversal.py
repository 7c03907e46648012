"""The line traversal: every cell on the straight line between two cells, in order.

Steps go along the longer axis one cell at a time; the shorter axis follows
the exact line, rounded half away from zero, so a line and its mirror image
in any of the eight octants visit mirrored cells. Neighbouring cells of the
path touch by a side or a corner, with no gaps.

:func:`line_point` is plain integer arithmetic, like :mod:`sandmod.engine.hashing`:
the kernel compiles this very function for every multi-cell move (falls,
slides, liquid flow, particles), and :func:`line_cells` uses it for brushes,
scene lines and emitters, so all of them walk the same cells.
"""

from __future__ import annotations

import numpy as np


def line_point(x0, y0, dx, dy, steps, i):
    """Cell ``i`` (0..steps) of the line from (x0, y0) to (x0 + dx, y0 + dy); steps = max(|dx|, |dy|) > 0."""
    # |d| * i / steps, rounded half away from zero; no division on the long axis or a straight line.
    ax, ay = abs(dx), abs(dy)
    ox = i if ax == steps else (0 if ax == 0 else (ax * i * 2 + steps) // (2 * steps))
    oy = i if ay == steps else (0 if ay == 0 else (ay * i * 2 + steps) // (2 * steps))
    return x0 + (ox if dx >= 0 else -ox), y0 + (oy if dy >= 0 else -oy)


def line_cells(x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
    """The cells from (x0, y0) to (x1, y1), both ends included, as an (n, 2) array of (x, y)."""
    dx, dy = x1 - x0, y1 - y0
    steps = max(abs(dx), abs(dy))
    if steps == 0:
        return np.array([(x0, y0)], np.int64)
    xs, ys = line_point(x0, y0, dx, dy, steps, np.arange(steps + 1, dtype=np.int64))  # all the cells at once
    return np.stack([np.broadcast_to(xs, steps + 1), np.broadcast_to(ys, steps + 1)], axis=1).astype(np.int64)
