"""Undo for a play session: the world as it was at each of the player's last actions, kept as the
blocks of cells that changed between one action and the next, within a memory budget.

The newest point is one whole copy of the world's state (:attr:`History.base`). Each older point
keeps only the blocks in which it differs from the point after it, so a stroke on a quiet world
costs the few blocks it touched, and a busy world costs what moved. When the points together pass
:data:`UNDO_MEMORY`, the oldest are forgotten; a world whose one copy passes it has no undo.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The most undo steps kept.
UNDO_DEPTH = 32
#: The most memory undo keeps, the newest whole copy included.
UNDO_MEMORY = 512 * 2**20
#: Cells a side of the blocks compared and kept.
BLOCK = 64


@dataclass
class Point:
    """One action's starting point: when it was, how many events the session had, and (once a newer
    point exists) the blocks of each array in which this point differs from the newer one."""

    label: str
    frame: int
    events: int
    marks: list[np.ndarray]  # small per-chunk arrays, kept whole
    blocks: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))  # (k, 2): block rows, columns
    saved: list[list[np.ndarray]] = field(default_factory=list)  # per array, the k blocks as they were

    @property
    def nbytes(self) -> int:
        return sum(m.nbytes for m in self.marks) + sum(b.nbytes for blocks in self.saved for b in blocks)


def _differing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Which BLOCK x BLOCK blocks of two arrays of one shape differ, as a boolean grid."""
    height, width = a.shape
    rows, columns = -(-height // BLOCK), -(-width // BLOCK)
    padded = np.zeros((rows * BLOCK, columns * BLOCK), bool)
    np.not_equal(a, b, out=padded[:height, :width])
    return padded.reshape(rows, BLOCK, columns, BLOCK).any(axis=(1, 3))


def _cut(array: np.ndarray, blocks: np.ndarray) -> list[np.ndarray]:
    return [array[r * BLOCK : (r + 1) * BLOCK, c * BLOCK : (c + 1) * BLOCK].copy() for r, c in blocks]


def _paste(array: np.ndarray, blocks: np.ndarray, saved: list[np.ndarray]) -> None:
    for (r, c), block in zip(blocks, saved):
        array[r * BLOCK : r * BLOCK + block.shape[0], c * BLOCK : c * BLOCK + block.shape[1]] = block


@dataclass
class History:
    """The undo points of one world (its arrays' shapes never change while it is kept)."""

    memory: int = UNDO_MEMORY
    depth: int = UNDO_DEPTH
    points: list[Point] = field(default_factory=list)
    base: list[np.ndarray] = field(default_factory=list)  # the newest point's arrays, whole

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self.base) + sum(p.nbytes for p in self.points)

    def clear(self) -> None:
        self.points, self.base = [], []

    def push(self, label: str, frame: int, events: int, arrays: list[np.ndarray], marks: list[np.ndarray]) -> bool:
        """A new newest point, the world being ``arrays`` now. False (and no undo) if one copy of
        the world passes the memory budget."""
        if sum(a.nbytes for a in arrays) > self.memory:
            self.clear()
            return False
        if self.base:
            newest = self.points[-1]
            grid = _differing(self.base[0], arrays[0])
            for kept, now in zip(self.base[1:], arrays[1:]):
                grid |= _differing(kept, now)
            newest.blocks = np.argwhere(grid)
            newest.saved = [_cut(kept, newest.blocks) for kept in self.base]
            for kept, now in zip(self.base, arrays):
                _paste(kept, newest.blocks, _cut(now, newest.blocks))
        else:
            self.base = [a.copy() for a in arrays]
        self.points.append(Point(label, frame, events, [m.copy() for m in marks]))
        while len(self.points) > 1 and (len(self.points) > self.depth or self.nbytes > self.memory):
            del self.points[0]
        return True

    def pop(self, arrays: list[np.ndarray], marks: list[np.ndarray]) -> Point | None:
        """Put ``arrays`` and ``marks`` back as they were at the newest point, and forget it; None if
        there is none."""
        if not self.points:
            return None
        point = self.points.pop()
        for now, kept in zip(arrays, self.base):
            now[...] = kept
        for now, kept in zip(marks, point.marks):
            now[...] = kept
        if self.points:  # the base becomes the point before
            older = self.points[-1]
            for kept, saved in zip(self.base, older.saved):
                _paste(kept, older.blocks, saved)
            older.blocks, older.saved = np.zeros((0, 2), np.int64), []
        else:
            self.base = []
        return point
