"""The state of a world: a few numpy arrays, painted by shapes and stepped by the kernel.

Per cell: the element (uint16), a shade (uint8, picked at birth, travels with
the cell), a lifetime timer (uint16) and a moved-this-frame mark (uint8):
6 bytes. Building and painting a world needs no numba; stepping it does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .compiler import Ruleset
from .hashing import (
    ROLL_BITS,
    SALT_MOVE,
    SALT_PAINT,
    SALT_REACT,
    SALT_SPAWN,
    cell_hash,
    chance_threshold,
    frame_key,
    spawn_state,
)


@dataclass(frozen=True)
class Emitter:
    """Pours ``element`` into the empty ones of its cells while start <= frame < stop."""

    ys: np.ndarray  # the rows and columns of the emitter's cells
    xs: np.ndarray
    element: int
    start: int
    stop: int | None
    chance: float

    def active(self, frame: int) -> bool:
        return self.start <= frame and (self.stop is None or frame < self.stop)


class World:
    """A grid of cells under one ruleset and seed."""

    def __init__(self, ruleset: Ruleset, width: int, height: int, seed: int = 0):
        self.ruleset = ruleset
        self.width, self.height, self.seed = width, height, seed
        self.frame = 0
        self.cells = np.zeros((height, width), np.uint16)
        self.shade = np.zeros((height, width), np.uint8)
        self.timer = np.zeros((height, width), np.uint16)
        self.moved = np.zeros((height, width), np.uint8)
        self.emitters: list[Emitter] = []
        self.paint(np.ones((height, width), bool), 0)  # empty, with its own shades

    def paint(self, mask: np.ndarray, element: int, *, chance: float = 1.0, only_empty: bool = False, salt: int = SALT_PAINT) -> int:
        """Set the cells of ``mask`` to ``element`` as newly born cells; returns how many changed."""
        ys, xs = np.nonzero(mask)
        return self.paint_cells(ys, xs, element, chance=chance, only_empty=only_empty, salt=salt)

    def paint_cells(
        self, ys: np.ndarray, xs: np.ndarray, element: int, *, chance: float = 1.0, only_empty: bool = False, salt: int = SALT_PAINT
    ) -> int:
        """:meth:`paint` for cells given by their rows and columns."""
        if only_empty:
            keep = self.cells[ys, xs] == 0
            ys, xs = ys[keep], xs[keep]
        ys, xs = ys.astype(np.uint64), xs.astype(np.uint64)
        if chance < 1.0:
            roll = cell_hash(frame_key(self.seed, self.frame, salt), xs, ys)
            keep = (roll >> (32 - ROLL_BITS)) < chance_threshold(chance)
            ys, xs = ys[keep], xs[keep]
        t = self.ruleset.tables
        h = cell_hash(frame_key(self.seed, self.frame, SALT_SPAWN ^ salt), xs, ys)
        shade, timer = spawn_state(h, int(t.life_frames[element]), int(t.life_jitter[element]))
        self.cells[ys, xs] = element
        self.shade[ys, xs] = shade
        self.timer[ys, xs] = timer
        return len(xs)

    def step(self) -> None:
        """Advance one frame: emitters pour, then the kernel updates every cell."""
        from .kernel import step

        for number, emitter in enumerate(self.emitters):
            if emitter.active(self.frame):
                self.paint_cells(
                    emitter.ys, emitter.xs, emitter.element, chance=emitter.chance, only_empty=True, salt=SALT_PAINT + 1 + number
                )
        step(
            self.cells,
            self.shade,
            self.timer,
            self.moved,
            self.ruleset.tables,
            frame_key(self.seed, self.frame, SALT_MOVE),
            frame_key(self.seed, self.frame, SALT_REACT),
            frame_key(self.seed, self.frame, SALT_SPAWN),
            self.frame,
        )
        self.frame += 1

    def counts(self) -> dict[str, int]:
        """How many cells of each element there are, by element id."""
        numbers = np.bincount(self.cells.ravel(), minlength=len(self.ruleset.elements))
        return {e.id: int(numbers[e.index]) for e in self.ruleset.elements if numbers[e.index]}

    def image(self, scale: int = 1) -> np.ndarray:
        """Palette indices of every cell, each cell a ``scale`` x ``scale`` block."""
        rs = self.ruleset
        bucket = (self.shade.astype(np.uint16) * rs.shades) >> 8
        frame = rs.color_lut[self.cells, bucket]
        if scale > 1:
            frame = np.repeat(np.repeat(frame, scale, axis=0), scale, axis=1)
        return frame
