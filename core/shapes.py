"""Rasterise the shapes of a world file into boolean masks."""

from __future__ import annotations

from collections import deque

import numpy as np

from .traversal import line_cells


def rect_mask(width: int, height: int, x: int, y: int, w: int, h: int) -> np.ndarray:
    """Cells with x <= cx < x + w and y <= cy < y + h."""
    mask = np.zeros((height, width), bool)
    mask[max(y, 0) : max(y + h, 0), max(x, 0) : max(x + w, 0)] = True
    return mask


def circle_mask(width: int, height: int, cx: int, cy: int, radius: float) -> np.ndarray:
    """Cells whose centres lie within ``radius`` of (cx, cy)."""
    ys, xs = np.ogrid[:height, :width]
    return (xs - cx) ** 2 + (ys - cy) ** 2 <= radius * radius


def brush_offsets(diameter: int) -> list[tuple[int, int]]:
    """The cells of a round brush ``diameter`` cells across, around (0, 0).

    Odd sizes centre on the cell, even sizes on its top-left corner; 1 is one
    cell, 2 a 2x2 block, 3 a 3x3 block, larger sizes discs.
    """
    low = -(diameter // 2)
    centre = low + (diameter - 1) / 2
    span = range(low, low + diameter)
    limit = (diameter / 2) ** 2
    return [(ox, oy) for oy in span for ox in span if (ox - centre) ** 2 + (oy - centre) ** 2 <= limit]


def line_mask(width: int, height: int, start: tuple[int, int], end: tuple[int, int], thickness: int) -> np.ndarray:
    """A brush of diameter ``thickness`` dragged along the line traversal from start to end."""
    return stroke_mask(width, height, [start, end], thickness)


def stroke_mask(width: int, height: int, points, thickness: int) -> np.ndarray:
    """A brush of diameter ``thickness`` dragged along the line traversal from each point to the next."""
    mask = np.zeros((height, width), bool)
    offsets = brush_offsets(thickness)
    for (x0, y0), (x1, y1) in zip(points, points[1:]):
        for x, y in line_cells(x0, y0, x1, y1):
            for ox, oy in offsets:
                px, py = x + ox, y + oy
                if 0 <= px < width and 0 <= py < height:
                    mask[py, px] = True
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
