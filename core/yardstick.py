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
velocity, heat, reaction, sleeping chunk or thread: what is left is the
per-cell cost that every falling-sand engine pays.
"""

from __future__ import annotations

from numba import njit

from .kernel import _at, _mix32, _within  # the kernel's unsigned indices: numba's wrap-around would cost a quarter


@njit(cache=True)
def step(cells, moved, sand, water, frame, key):
    """Advance ``cells`` (element ids) by one frame; ``moved`` is scratch of the same shape."""
    height, width = cells.shape
    moved[:] = 0
    for y in range(height - 1, -1, -1):
        forward = ((frame + y) & 1) == 0
        for i in range(width):
            x = i if forward else width - 1 - i
            e = cells[_at(y, x)]
            if (e != sand and e != water) or moved[_at(y, x)]:
                continue
            side = 1 if _mix32(key ^ ((y << 16) | x)) & 1 else -1
            for dx, dy in ((0, 1), (side, 1), (-side, 1), (side, 0), (-side, 0)):
                nx, ny = x + dx, y + dy
                if dy == 0 and e == sand:
                    break  # sand does not flow sideways
                if not (_within(nx, width) and ny < height):
                    continue
                o = cells[_at(ny, nx)]
                if o == 0 or (e == sand and o == water and not moved[_at(ny, nx)]):
                    cells[_at(y, x)] = o
                    cells[_at(ny, nx)] = e
                    moved[_at(ny, nx)] = 1
                    if o != 0:
                        moved[_at(y, x)] = 1  # the water it traded places with has moved too
                    break

