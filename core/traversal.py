"""The line traversal: every cell on the straight line between two cells, in order.

Steps go along the longer axis one cell at a time; the shorter axis follows
the exact line, rounded half away from zero, so a line and its mirror image
in any of the eight octants visit mirrored cells. Neighbouring cells of the
path touch by a side or a corner, with no gaps.
"""

from __future__ import annotations

import numpy as np


def _round_div(a: int, n: int) -> int:
    """a / n rounded half away from zero (n > 0)."""
    q = (abs(a) * 2 + n) // (2 * n)
    return q if a >= 0 else -q


def line_cells(x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
    """The cells from (x0, y0) to (x1, y1), both ends included, as an (n, 2) array of (x, y)."""
    dx, dy = x1 - x0, y1 - y0
    steps = max(abs(dx), abs(dy))
    out = np.empty((steps + 1, 2), np.int64)
    for i in range(steps + 1):
        if steps == 0:
            out[i] = (x0, y0)
        else:
            out[i] = (x0 + _round_div(dx * i, steps), y0 + _round_div(dy * i, steps))
    return out
