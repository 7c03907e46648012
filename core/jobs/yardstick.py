"""The yardstick: the simplest falling sand numba can run, to tell what a machine allows.

``sandmod bench --yardstick`` times it in turns with the engine, so that the
engine's speed can be read as a share of what this machine does today with
the least work a falling-sand step can do (a shared machine's speed drifts,
and machines differ; the share does not drift with them).

Its rules fit in a dozen lines. Rows go bottom-up, each row's direction
alternating with the row and the frame. Sand falls into the cell below, else
into one of the two cells below it (the first picked by a hash), if that cell
is empty, or water that has not moved this frame (they trade places). Water
falls likewise into empty cells, else flows one cell to a side. Anything else
stands still. A cell moved into is not updated again that frame. There is no
velocity, heat, reaction or sleeping chunk: what is left is the per-cell
cost that every falling-sand engine pays. On several threads each takes a
band of the world's columns, and the bands do not touch.
"""

from __future__ import annotations

from numba import njit, prange

from ..engine.kernel import _at, _mix32, _within  # the kernel's unsigned indices: numba's wrap-around would cost a quarter


@njit(cache=True, parallel=True)
def step(cells, moved, sand, water, frame, key, bands):
    """Advance ``cells`` (element ids) by one frame; ``moved`` is scratch of the same shape.

    The world is cut into ``bands`` bands of columns, stepped at the same time
    on as many threads, each as a world of its own (nothing crosses between
    them): what a machine's threads allow when they share nothing.
    """
    width = cells.shape[1]
    for b in prange(bands):
        _step_band(cells, moved, sand, water, frame, key, b * width // bands, (b + 1) * width // bands)


@njit(inline="always", cache=True)
def _step_band(cells, moved, sand, water, frame, key, x0, x1):
    """The dozen lines: step columns x0..x1-1 as if they were the whole world."""
    height = cells.shape[0]
    moved[:, x0:x1] = 0
    for y in range(height - 1, -1, -1):
        forward = ((frame + y) & 1) == 0
        for i in range(x1 - x0):
            x = x0 + i if forward else x1 - 1 - i
            e = cells[_at(y, x)]
            if (e != sand and e != water) or moved[_at(y, x)]:
                continue
            side = 1 if _mix32(key ^ ((y << 16) | x)) & 1 else -1
            for dx, dy in ((0, 1), (side, 1), (-side, 1), (side, 0), (-side, 0)):
                nx, ny = x + dx, y + dy
                if dy == 0 and e == sand:
                    break  # sand does not flow sideways
                if not (_within(nx - x0, x1 - x0) and ny < height):
                    continue
                o = cells[_at(ny, nx)]
                if o == 0 or (e == sand and o == water and not moved[_at(ny, nx)]):
                    cells[_at(y, x)] = o
                    cells[_at(ny, nx)] = e
                    moved[_at(ny, nx)] = 1
                    if o != 0:
                        moved[_at(y, x)] = 1  # the water it traded places with has moved too
                    break
