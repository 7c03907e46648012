"""The numba kernel: one frame of the cellular automaton.

The kernel reads only what it is given: the world's arrays, the compiled
:class:`~sandmod.compiler.Tables`, and three per-frame hash keys. Adding or
editing a mod changes the tables' contents, never the compiled code.

Order within a frame: rows bottom-up; the horizontal direction alternates
with the row and the frame. A cell is updated once: its lifetime ticks, it
may react with a touching neighbour, and then it moves by its archetype.
A cell that moved or changed this frame is marked in ``moved`` and left
alone for the rest of the frame. :func:`step_region` updates one rectangle,
so the world can later be stepped chunk by chunk.
"""

from __future__ import annotations

from numba import njit

from . import hashing
from .compiler import ARCHETYPE_CODES

_mix32 = njit(inline="always", cache=True)(hashing.mix32)
_spawn_state = njit(inline="always", cache=True)(hashing.spawn_state)

LIQUID = ARCHETYPE_CODES["liquid"]
MOVED = 1
REACTED = 2
# The four orthogonal neighbours.
_DX = (1, 0, -1, 0)
_DY = (0, 1, 0, -1)


@njit(inline="always", cache=True)
def _cell_key(key, x, y):
    return _mix32(key ^ ((y << 16) | x))


@njit(inline="always", cache=True)
def _set(cells, shade, timer, moved, t, spawn_key, x, y, element, mark):
    """Turn the cell at (x, y) into ``element``, a newly born cell."""
    cells[y, x] = element
    s, life = _spawn_state(_cell_key(spawn_key, x, y), t.life_frames[element], t.life_jitter[element])
    shade[y, x] = s
    timer[y, x] = life
    moved[y, x] = mark


@njit(inline="always", cache=True)
def _swap(cells, shade, timer, moved, x0, y0, x1, y1):
    cells[y0, x0], cells[y1, x1] = cells[y1, x1], cells[y0, x0]
    shade[y0, x0], shade[y1, x1] = shade[y1, x1], shade[y0, x0]
    timer[y0, x0], timer[y1, x1] = timer[y1, x1], timer[y0, x0]
    moved[y0, x0] = MOVED
    moved[y1, x1] = MOVED


@njit(inline="always", cache=True)
def _can_enter(cells, moved, t, e, x, y):
    """May a moving cell of element ``e`` swap into (x, y)? (x, y) must be inside the world.

    Only lighter fluids give way, and a cell that already moved this frame
    stays put (empty cells excepted: they have nothing to lose).
    """
    b = cells[y, x]
    return t.displace[e, b] != 0 and (b == 0 or moved[y, x] == 0)


@njit(cache=True)
def _react(cells, shade, timer, moved, t, react_key, spawn_key, x, y, e, h, width, height):
    """Try each touching neighbour once; apply the first reaction whose roll succeeds."""
    start = (h >> 1) & 3
    for k in range(4):
        d = (start + k) & 3
        nx = x + _DX[d]
        ny = y + _DY[d]
        if nx < 0 or ny < 0 or nx >= width or ny >= height or moved[ny, nx] == REACTED:
            continue
        b = cells[ny, nx]
        threshold = t.react_chance[e, b]
        if threshold == 0:
            continue
        # One roll per touching pair and frame, the same whichever cell looks.
        vertical = d & 1
        px = min(x, nx)
        py = min(y, ny)
        roll = _mix32(react_key ^ ((py << 16) | px) ^ (vertical << 31)) >> 8
        if roll >= threshold:
            continue
        into_a = t.react_into_a[e, b]
        into_b = t.react_into_b[e, b]
        if into_a != e:
            _set(cells, shade, timer, moved, t, spawn_key, x, y, into_a, REACTED)
        if into_b != b:
            _set(cells, shade, timer, moved, t, spawn_key, nx, ny, into_b, REACTED)
        moved[y, x] = REACTED
        moved[ny, nx] = REACTED
        return True
    return False


@njit(cache=True)
def _move(cells, shade, timer, moved, t, x, y, e, h, width, height):
    """Move by archetype: fall (or rise), slide diagonally, and for fluids flow sideways."""
    g = t.gravity[e]
    if g == 0:
        return
    ny = y + g
    if 0 <= ny < height and _can_enter(cells, moved, t, e, x, ny):
        _swap(cells, shade, timer, moved, x, y, x, ny)
        return
    if t.archetype[e] == LIQUID and (h >> 8) < t.rest_chance[e]:
        return  # viscous: falls freely, flows reluctantly
    if 0 <= ny < height:
        side = 1 if h & 1 else -1
        for s in (side, -side):
            nx = x + s
            # A cell rolls over the side, never squeezes between two corners.
            if 0 <= nx < width and t.displace[e, cells[y, nx]] != 0 and _can_enter(cells, moved, t, e, nx, ny):
                _swap(cells, shade, timer, moved, x, y, nx, ny)
                return
    reach_max = t.dispersion[e]
    if reach_max == 0:
        return
    side = 1 if h & 1 else -1
    for s in (side, -side):
        reach = 0
        for k in range(1, reach_max + 1):
            nx = x + s * k
            if nx < 0 or nx >= width or not _can_enter(cells, moved, t, e, nx, y):
                break
            reach = k
        if reach > 0:
            _swap(cells, shade, timer, moved, x, y, x + s * reach, y)
            return


@njit(cache=True)
def _update_cell(cells, shade, timer, moved, t, move_key, react_key, spawn_key, x, y, width, height):
    e = cells[y, x]
    if t.life_frames[e] != 0:
        left = timer[y, x]
        if left <= 1:
            _set(cells, shade, timer, moved, t, spawn_key, x, y, t.life_into[e], MOVED)
            return
        timer[y, x] = left - 1
    h = _cell_key(move_key, x, y)
    if t.reactive[e] != 0 and _react(cells, shade, timer, moved, t, react_key, spawn_key, x, y, e, h, width, height):
        return
    _move(cells, shade, timer, moved, t, x, y, e, h, width, height)


@njit(cache=True)
def step_region(cells, shade, timer, moved, t, move_key, react_key, spawn_key, frame, x0, y0, x1, y1):
    """Update the cells of rows y0..y1-1 and columns x0..x1-1 (moves may leave the region)."""
    height, width = cells.shape
    for row in range(y1 - 1, y0 - 1, -1):
        forward = ((frame + row) & 1) == 0
        for i in range(x1 - x0):
            x = x0 + i if forward else x1 - 1 - i
            if moved[row, x] != 0 or cells[row, x] == 0:
                continue
            _update_cell(cells, shade, timer, moved, t, move_key, react_key, spawn_key, x, row, width, height)


@njit(cache=True)
def step(cells, shade, timer, moved, t, move_key, react_key, spawn_key, frame):
    """Advance the whole world by one frame."""
    moved[:, :] = 0
    height, width = cells.shape
    step_region(cells, shade, timer, moved, t, move_key, react_key, spawn_key, frame, 0, 0, width, height)

