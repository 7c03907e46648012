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

The per-cell update is written out in one function on purpose: numba counts
references to every array handed to a helper, and at a few hundred million
cells a second that bookkeeping costs more than the physics. Helpers here take
and return plain numbers only.
"""

from __future__ import annotations

import os
from pathlib import Path


def kernel_cache_dir() -> Path:
    """Where compiled kernels are kept: ``$NUMBA_CACHE_DIR``, else the user's cache folder.

    Not beside the installed package, where numba would put them by default:
    files pip did not install would survive an uninstall there, leaving a
    stray ``sandmod`` folder that shadows a later editable install.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.environ.get("LOCALAPPDATA") or Path.home() / ".cache"
    return Path(base) / "sandmod" / "numba"


os.environ.setdefault("NUMBA_CACHE_DIR", str(kernel_cache_dir()))  # read when numba is first imported

from numba import njit  # noqa: E402

from . import hashing  # noqa: E402
from .compiler import ARCHETYPE_CODES  # noqa: E402

_mix32 = njit(inline="always", cache=True)(hashing.mix32)
_spawn_state = njit(inline="always", cache=True)(hashing.spawn_state)

LIQUID = ARCHETYPE_CODES["liquid"]
MOVED = 1
REACTED = 2


@njit(inline="always", cache=True)
def _cell_key(key, x, y):
    """The hash of cell (x, y) under a frame key."""
    return _mix32(key ^ ((y << 16) | x))


@njit(inline="always", cache=True)
def _enterable(displaceable, occupant, occupant_moved):
    """May a mover take this place? Only lighter fluids give way, and not twice a frame
    (empty cells excepted: they have nothing to lose)."""
    return displaceable != 0 and (occupant == 0 or occupant_moved == 0)


@njit(cache=True)
def step_region(cells, shade, timer, moved, t, move_key, react_key, spawn_key, frame, x0, y0, x1, y1):
    """Update the cells of rows y0..y1-1 and columns x0..x1-1 (moves may leave the region)."""
    height, width = cells.shape
    archetype, gravity, dispersion, rest_chance = t.archetype, t.gravity, t.dispersion, t.rest_chance
    life_frames, life_jitter, life_into = t.life_frames, t.life_jitter, t.life_into
    reactive, displace = t.reactive, t.displace
    react_chance, react_into_a, react_into_b = t.react_chance, t.react_into_a, t.react_into_b

    for y in range(y1 - 1, y0 - 1, -1):
        forward = ((frame + y) & 1) == 0
        for i in range(x1 - x0):
            x = x0 + i if forward else x1 - 1 - i
            e = cells[y, x]
            if e == 0 or moved[y, x] != 0:
                continue

            # 1. Lifetime: count down, and at zero become another element.
            if life_frames[e] != 0:
                left = timer[y, x]
                if left <= 1:
                    into = life_into[e]
                    cells[y, x] = into
                    shade[y, x], timer[y, x] = _spawn_state(_cell_key(spawn_key, x, y), life_frames[into], life_jitter[into])
                    moved[y, x] = MOVED
                    continue
                timer[y, x] = left - 1
            h = _cell_key(move_key, x, y)

            # 2. Reactions: try each touching neighbour once, in a hashed order.
            if reactive[e] != 0:
                reacted = False
                start = (h >> 1) & 3
                for k in range(4):
                    d = (start + k) & 3
                    nx = x + (1, 0, -1, 0)[d]
                    ny = y + (0, 1, 0, -1)[d]
                    if nx < 0 or ny < 0 or nx >= width or ny >= height or moved[ny, nx] == REACTED:
                        continue
                    b = cells[ny, nx]
                    threshold = react_chance[e, b]
                    if threshold == 0:
                        continue
                    # One roll per touching pair and frame, the same whichever cell looks.
                    roll = _mix32(react_key ^ ((min(y, ny) << 16) | min(x, nx)) ^ ((d & 1) << 31)) >> 8
                    if roll >= threshold:
                        continue
                    into_a = react_into_a[e, b]
                    into_b = react_into_b[e, b]
                    if into_a != e:
                        cells[y, x] = into_a
                        shade[y, x], timer[y, x] = _spawn_state(_cell_key(spawn_key, x, y), life_frames[into_a], life_jitter[into_a])
                    if into_b != b:
                        cells[ny, nx] = into_b
                        shade[ny, nx], timer[ny, nx] = _spawn_state(_cell_key(spawn_key, nx, ny), life_frames[into_b], life_jitter[into_b])
                    moved[y, x] = REACTED
                    moved[ny, nx] = REACTED
                    reacted = True
                    break
                if reacted:
                    continue

            # 3. Movement: fall (or rise) straight, then diagonally, then flow sideways.
            g = gravity[e]
            if g == 0:
                continue
            tx = -1
            ty = y + g
            vertical_ok = 0 <= ty < height
            if vertical_ok and _enterable(displace[e, cells[ty, x]], cells[ty, x], moved[ty, x]):
                tx = x
            elif archetype[e] != LIQUID or (h >> 8) >= rest_chance[e]:  # viscous liquids often rest
                side = 1 if h & 1 else -1
                if vertical_ok:
                    for s in (side, -side):
                        nx = x + s
                        # A cell rolls over the side, never squeezes between two corners.
                        if (
                            0 <= nx < width
                            and displace[e, cells[y, nx]] != 0
                            and _enterable(displace[e, cells[ty, nx]], cells[ty, nx], moved[ty, nx])
                        ):
                            tx = nx
                            break
                reach_max = dispersion[e]
                if tx < 0 and reach_max > 0:
                    for s in (side, -side):
                        reach = 0
                        for k in range(1, reach_max + 1):
                            nx = x + s * k
                            if nx < 0 or nx >= width or not _enterable(displace[e, cells[y, nx]], cells[y, nx], moved[y, nx]):
                                break
                            reach = k
                        if reach > 0:
                            tx = x + s * reach
                            ty = y
                            break
            if tx >= 0:
                cells[y, x], cells[ty, tx] = cells[ty, tx], cells[y, x]
                shade[y, x], shade[ty, tx] = shade[ty, tx], shade[y, x]
                timer[y, x], timer[ty, tx] = timer[ty, tx], timer[y, x]
                moved[y, x] = MOVED
                moved[ty, tx] = MOVED


@njit(cache=True)
def step(cells, shade, timer, moved, t, move_key, react_key, spawn_key, frame):
    """Advance the whole world by one frame."""
    moved[:, :] = 0
    height, width = cells.shape
    step_region(cells, shade, timer, moved, t, move_key, react_key, spawn_key, frame, 0, 0, width, height)
