"""Shapes and the line traversal, against slow obvious references."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from sandmod.world.shapes import brush_offsets, circle_mask, fill_mask, line_mask, rect_mask
from sandmod.engine.traversal import line_cells


def reference_line(x0, y0, x1, y1):
    """Step along the longer axis; round the other to the nearest cell, halves away from zero."""
    steps = max(abs(x1 - x0), abs(y1 - y0))
    if steps == 0:
        return [(x0, y0)]

    def near(v):
        return int(math.floor(v + 0.5)) if v >= 0 else -int(math.floor(-v + 0.5))

    return [(x0 + near((x1 - x0) * i / steps), y0 + near((y1 - y0) * i / steps)) for i in range(steps + 1)]


@pytest.mark.parametrize("seed", range(5))
def test_line_matches_the_reference_and_has_no_gaps(seed):
    rng = np.random.default_rng(seed)
    for _ in range(200):
        x0, y0, x1, y1 = (int(v) for v in rng.integers(-40, 40, 4))
        cells = [tuple(c) for c in line_cells(x0, y0, x1, y1)]
        assert cells == reference_line(x0, y0, x1, y1)
        assert cells[0] == (x0, y0) and cells[-1] == (x1, y1)
        for (ax, ay), (bx, by) in zip(cells, cells[1:]):
            assert max(abs(ax - bx), abs(ay - by)) == 1


def test_line_is_mirror_symmetric_in_every_octant():
    for dx, dy in [(7, 3), (3, 7), (5, 5), (9, 0), (0, 4), (6, 1)]:
        base = [tuple(c) for c in line_cells(0, 0, dx, dy)]
        for sx in (1, -1):
            for sy in (1, -1):
                mirrored = [tuple(c) for c in line_cells(0, 0, sx * dx, sy * dy)]
                assert mirrored == [(sx * x, sy * y) for x, y in base]
        swapped = [tuple(c) for c in line_cells(0, 0, dy, dx)]
        assert swapped == [(y, x) for x, y in base]


def test_brushes_are_round_and_of_their_size():
    assert brush_offsets(1) == [(0, 0)]
    assert sorted(brush_offsets(2)) == [(-1, -1), (-1, 0), (0, -1), (0, 0)]
    assert len(brush_offsets(3)) == 9
    five = brush_offsets(5)
    assert (2, 2) not in five and (2, 0) in five and len(five) == 21


def test_a_thick_diagonal_line_is_side_connected():
    mask = line_mask(20, 20, (0, 0), (19, 15), 2)
    ys, xs = np.nonzero(mask)
    # Every painted cell in a column run touches the next column's run by a side.
    for x in range(19):
        assert set(ys[xs == x]) & set(ys[xs == x + 1])


def test_rect_circle_and_fill():
    assert rect_mask(10, 10, -2, 8, 5, 5).sum() == 3 * 2
    circle = circle_mask(21, 21, 10, 10, 4)
    assert circle.sum() == sum(1 for x in range(21) for y in range(21) if (x - 10) ** 2 + (y - 10) ** 2 <= 16)
    cells = np.zeros((5, 7), np.uint16)
    cells[:, 3] = 2  # a wall down the middle
    region = fill_mask(cells, 0, 0)
    assert region.sum() == 15 and not region[:, 3:].any()


def test_python_dash_m_runs_the_cli():
    result = subprocess.run([sys.executable, "-m", "sandmod", "--help"], capture_output=True, text=True)
    assert result.returncode == 0 and "render" in result.stdout


def test_a_square_brush_is_a_square_dragged_along_the_line():
    assert sorted(brush_offsets(2, square=True)) == sorted(brush_offsets(2)) and len(brush_offsets(5, square=True)) == 25
    mask = line_mask(20, 20, (5, 5), (10, 10), 3, square=True)
    assert mask[4:7, 4:7].all() and mask[9:12, 9:12].all() and mask[4, 6] and not mask[4, 8]
