"""Rasterise the shapes of a world file into boolean masks."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from ..engine.traversal import line_cells


def rect_mask(width: int, height: int, x: int, y: int, w: int, h: int) -> np.ndarray:
    """Cells with x <= cx < x + w and y <= cy < y + h."""
    mask = np.zeros((height, width), bool)
    mask[max(y, 0) : max(y + h, 0), max(x, 0) : max(x + w, 0)] = True
    return mask


def circle_mask(width: int, height: int, cx: int, cy: int, radius: float) -> np.ndarray:
    """Cells whose centres lie within ``radius`` of (cx, cy)."""
    mask = np.zeros((height, width), bool)
    reach = int(np.ceil(radius))
    x0, x1 = max(cx - reach, 0), min(cx + reach + 1, width)
    y0, y1 = max(cy - reach, 0), min(cy + reach + 1, height)
    if x0 < x1 and y0 < y1:  # only the box around the disc is computed
        ys, xs = np.ogrid[y0:y1, x0:x1]
        mask[y0:y1, x0:x1] = (xs - cx) ** 2 + (ys - cy) ** 2 <= radius * radius
    return mask


def brush_offsets(diameter: int, square: bool = False) -> list[tuple[int, int]]:
    """The cells of a round (or ``square``) brush ``diameter`` cells across, around (0, 0).

    Odd sizes centre on the cell, even sizes on its top-left corner; 1 is one
    cell, 2 a 2x2 block, 3 a 3x3 block, larger round sizes discs.
    """
    low = -(diameter // 2)
    centre = low + (diameter - 1) / 2
    span = range(low, low + diameter)
    limit = float("inf") if square else (diameter / 2) ** 2
    return [(ox, oy) for oy in span for ox in span if (ox - centre) ** 2 + (oy - centre) ** 2 <= limit]


def line_mask(width: int, height: int, start: tuple[int, int], end: tuple[int, int], thickness: int, square: bool = False) -> np.ndarray:
    """A brush of diameter ``thickness`` dragged along the line traversal from start to end."""
    return stroke_mask(width, height, [start, end], thickness, square)


def stroke_mask(width: int, height: int, points, thickness: int, square: bool = False) -> np.ndarray:
    """A round (or ``square``) brush ``thickness`` cells across, dragged along the line traversal from each point to the next."""
    mask = np.zeros((height, width), bool)
    offsets = brush_offsets(thickness, square)
    reach = thickness // 2 + 1
    for (x0, y0), (x1, y1) in zip(points, points[1:]):
        cells = line_cells(x0, y0, x1, y1)
        xs, ys = cells[:, 0], cells[:, 1]
        near = (xs >= -reach) & (xs < width + reach) & (ys >= -reach) & (ys < height + reach)
        xs, ys = xs[near], ys[near]  # only cells whose brush can reach the world
        for ox, oy in offsets:
            px, py = xs + ox, ys + oy
            inside = (px >= 0) & (px < width) & (py >= 0) & (py < height)
            mask[py[inside], px[inside]] = True
    return mask


def fill_mask(cells: np.ndarray, x: int, y: int) -> np.ndarray:
    """The region of cells equal to cells[y, x] that (x, y) reaches through sides (paint bucket)."""
    height, width = cells.shape
    target = cells[y, x]
    mask = np.zeros((height, width), bool)
    mask[y, x] = True
    queue = deque([(x, y)])
    while queue:
        cx, cy = queue.popleft()
        for nx, ny in ((cx + 1, cy), (cx - 1, cy), (cx, cy + 1), (cx, cy - 1)):
            if 0 <= nx < width and 0 <= ny < height and not mask[ny, nx] and cells[ny, nx] == target:
                mask[ny, nx] = True
                queue.append((nx, ny))
    return mask


@dataclass(frozen=True)
class Patch:
    """A world-sized array kept as its smallest box that holds everything but ``blank``: what a
    timeline shape or picture covers, stored small until its frame comes."""

    height: int
    width: int
    top: int
    left: int
    box: np.ndarray
    blank: object

    @classmethod
    def of(cls, whole: np.ndarray, blank=False) -> "Patch":
        """The patch of ``whole`` (a (height, width) array), cut to its cells other than ``blank``."""
        rows = np.flatnonzero((whole != blank).any(axis=1))
        columns = np.flatnonzero((whole != blank).any(axis=0))
        if rows.size == 0:
            return cls(*whole.shape, 0, 0, whole[:0, :0].copy(), blank)
        top, left = int(rows[0]), int(columns[0])
        box = whole[top : rows[-1] + 1, left : columns[-1] + 1].copy()
        return cls(*whole.shape, top, left, box, blank)

    def whole(self) -> np.ndarray:
        """The world-sized array again."""
        out = np.full((self.height, self.width), self.blank, self.box.dtype)
        out[self.top : self.top + self.box.shape[0], self.left : self.left + self.box.shape[1]] = self.box
        return out
