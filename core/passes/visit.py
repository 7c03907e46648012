"""Where a pass after the step looks: the tiles (64 x 64 cells, numbered row-major) whose rows the
step updated held an element the pass concerns (the kernel's per-tile mask, ``World._seen``), and
how a change it makes wakes the chunks around it for the next step."""

from __future__ import annotations

import numpy as np

from ..engine.jit import compiled
from ..engine.layout import CHUNK_SHIFT, WAKE_MARGIN, WHOLE


def tiles_holding(seen: np.ndarray, mask: int) -> np.ndarray:
    """The tiles whose mask from the last step has any of ``mask``'s bits (element-mask bits)."""
    return np.flatnonzero(seen & np.int64(mask)).astype(np.int64)


@compiled
def wake_around(awake, even, x, y, width, height):
    """Wake the chunks within WAKE_MARGIN of cell (x, y) for the next step, whole, their heat no longer known to be even."""
    for wy in range(max(y - WAKE_MARGIN, 0) >> CHUNK_SHIFT, (min(y + WAKE_MARGIN, height - 1) >> CHUNK_SHIFT) + 1):
        for wx in range(max(x - WAKE_MARGIN, 0) >> CHUNK_SHIFT, (min(x + WAKE_MARGIN, width - 1) >> CHUNK_SHIFT) + 1):
            awake[wy, wx] = WHOLE
            even[wy, wx] = 0
