"""The yardstick: the simplest falling sand numba can run, to tell what a machine allows.

``python tools/dev/bench.py yardstick`` times it in turns with the engine, so that the
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

from typing import Sequence

import numba
import numpy as np
from numba import njit, prange

from kernels import _KernelRun, in_turns, saved
from sandmod.engine.hashing import SALT_MOVE, frame_key
from sandmod.engine.cells import _at, _mix32, _within  # unsigned indices: numba's wrap-around would cost a quarter
from sandmod.jobs.benchmark import Bench


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


class _YardstickRun:
    """The yardstick on a thread count, stepping cells of its own from its stretch's start."""

    def __init__(self, cells: np.ndarray, sand: int, water: int, keys: list[int], bands: int):
        self.cells, self.start, self.moved = cells, cells.copy(), np.zeros(cells.shape, np.uint8)
        self.sand, self.water, self.keys, self.bands = sand, water, keys, bands

    def rewind(self) -> None:
        numba.set_num_threads(self.bands)
        self.cells[...] = self.start

    def run(self, frames: range) -> None:
        for f in frames:
            step(self.cells, self.moved, self.sand, self.water, f, self.keys[f], self.bands)


def against_yardstick(
    bench: Bench, steps: int, threads: Sequence[int], *, segment: int = 25, repeats: int = 3
) -> tuple[list[float], list[float]]:
    """Seconds the engine and the yardstick take to step ``bench``'s world ``steps`` steps, on each count of ``threads``.

    Both start from the scene's cells and step by their own rules, in turns
    (:func:`kernels.in_turns`). Returns the engine's seconds and the
    yardstick's, one per thread count.
    """
    from sandmod.engine import kernel

    world = bench.make()
    sand, water = world.ruleset.index("sand"), world.ruleset.index("water")
    keys = [frame_key(world.seed, frame, SALT_MOVE) for frame in range(steps)]
    engines = [_KernelRun(world, kernel, count) for count in threads]
    sticks = [_YardstickRun(world.cells.copy(), sand, water, keys, count) for count in threads]
    for stick in sticks:  # compile, or load from the cache
        stick.rewind()
        step(stick.cells.copy(), stick.moved, sand, water, 0, keys[0], stick.bands)

    def after(frames: range) -> None:
        end = saved(world)  # every count steps the world to the same frames
        for engine in engines:
            engine.go_on_from(end)
        for stick in sticks:
            stick.start = stick.cells.copy()

    seconds = in_turns([c for pair in zip(engines, sticks) for c in pair], steps, segment=segment, repeats=repeats, after=after)
    return seconds[0::2], seconds[1::2]

