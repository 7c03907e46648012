"""The numba kernel: one frame of the cellular automaton.

The kernel reads only what it is given: the world's arrays (a
:class:`~sandmod.world.State`), the compiled :class:`~sandmod.compiler.Tables`,
and per-frame hash keys. Adding or editing a mod changes the tables' contents,
never the compiled code.

Order within a frame: rows bottom-up; the horizontal direction alternates
with the row and the frame. A cell is updated once: its lifetime ticks, it
may react with a touching neighbour, and then it moves by its archetype.
A cell that moved or changed this frame is marked and left alone for the rest
of the frame. :func:`step_region` updates one rectangle, so the world can be
stepped chunk by chunk.

Movement. Movers (powders, liquids, gases) carry a velocity in 1/256ths of a
cell per frame. While the cell below (above, for rising gases) is open they
fall, accelerating by their gravity up to their terminal speed, and drift by
their sideways speed. On the ground a loose powder grain turns its landing
speed into sideways speed, rolls or slides, and loses speed to friction until
it rests; a resting grain moves again when the cell below opens or a moving
neighbour knocks it loose. Liquids and gases on the ground flow sideways up to
their dispersion. Particles fly by their velocity through empty cells and put
down what they carry where they hit something.

Every move of more than one cell walks the line traversal
(:func:`sandmod.traversal.line_point`) and stops at the first cell it may not
enter: only the first cell of a move may be a fluid to swap with (the move
ends there), the others must be empty, and a diagonal step needs one of its
two side cells open, so nothing passes through a wall or between two corners.

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

from . import hashing, traversal  # noqa: E402
from .compiler import ARCHETYPE_CODES, SUBCELL  # noqa: E402
from .world import LOOSE, MOVED, REACTED  # noqa: E402

_mix32 = njit(inline="always", cache=True)(hashing.mix32)
_spawn_state = njit(inline="always", cache=True)(hashing.spawn_state)
_line_point = njit(inline="always", cache=True)(traversal.line_point)

STATIC = ARCHETYPE_CODES["static"]
POWDER = ARCHETYPE_CODES["powder"]
LIQUID = ARCHETYPE_CODES["liquid"]
PARTICLE = ARCHETYPE_CODES["particle"]

DONE = MOVED | REACTED  # flag bits (defined beside world.State) of a cell finished this frame

# Powder on landing: its impact_share of the landing speed becomes sideways
# speed, and at least MIN_SLIDE; sideways speed below STOP_SPEED comes to rest.
MIN_SLIDE = SUBCELL // 4
STOP_SPEED = SUBCELL // 8
KNOCK_SPEED = SUBCELL // 2  # sideways speed of a grain knocked loose
SALT_KNOCK = 0x27D4EB2F
SALT_ROUND = 0x165667B1


@njit(inline="always", cache=True)
def _cell_key(key, x, y):
    """The hash of cell (x, y) under a frame key."""
    return _mix32(key ^ ((y << 16) | x))


@njit(inline="always", cache=True)
def _enterable(displaceable, occupant, occupant_flags):
    """May a mover take this place? Only lighter fluids give way, and not twice a frame
    (empty cells excepted: they have nothing to lose)."""
    return displaceable != 0 and (occupant == 0 or (occupant_flags & DONE) == 0)


@njit(inline="always", cache=True)
def _cells_moved(speed, roll):
    """A speed in 1/256ths of a cell, rounded to whole cells at random (roll: 0..255), unbiased."""
    return (speed >> 8) + (1 if (speed & 255) > roll else 0)


@njit(inline="always", cache=True)
def _scaled(value, keep):
    """value * keep / 256, rounded towards zero."""
    return (value * keep) >> 8 if value >= 0 else -((-value * keep) >> 8)


@njit(inline="always", cache=True)
def _clamped(value, limit):
    return max(-limit, min(limit, value))


@njit(cache=True)
def step_region(s, t, move_key, react_key, spawn_key, frame, x0, y0, x1, y1):
    """Update the cells of rows y0..y1-1 and columns x0..x1-1 (moves may leave the region)."""
    cells, shade, timer, flags, vx, vy, carry = s.cells, s.shade, s.timer, s.flags, s.vx, s.vy, s.carry
    height, width = cells.shape
    archetype, fall_dir, accel, max_speed = t.archetype, t.fall_dir, t.accel, t.max_speed
    friction, impact_share, knock_chance, drag_keep = t.friction, t.impact_share, t.knock_chance, t.drag_keep
    dispersion, rest_chance = t.dispersion, t.rest_chance
    life_frames, life_jitter, life_into = t.life_frames, t.life_jitter, t.life_into
    reactive, displace = t.reactive, t.displace
    react_chance, react_into_a, react_into_b = t.react_chance, t.react_into_a, t.react_into_b
    knock_key = _mix32(move_key ^ SALT_KNOCK)

    for y in range(y1 - 1, y0 - 1, -1):
        forward = ((frame + y) & 1) == 0
        for i in range(x1 - x0):
            x = x0 + i if forward else x1 - 1 - i
            e = cells[y, x]
            if e == 0 or (flags[y, x] & DONE) != 0:
                continue

            # 1. Lifetime: count down, and at zero become another element.
            if life_frames[e] != 0:
                left = timer[y, x]
                if left <= 1:
                    into = life_into[e]
                    cells[y, x] = into
                    shade[y, x], timer[y, x] = _spawn_state(_cell_key(spawn_key, x, y), life_frames[into], life_jitter[into])
                    vx[y, x] = vy[y, x] = carry[y, x] = 0
                    flags[y, x] |= MOVED
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
                    if nx < 0 or ny < 0 or nx >= width or ny >= height or (flags[ny, nx] & REACTED) != 0:
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
                        vx[y, x] = vy[y, x] = carry[y, x] = 0
                    if into_b != b:
                        cells[ny, nx] = into_b
                        shade[ny, nx], timer[ny, nx] = _spawn_state(_cell_key(spawn_key, nx, ny), life_frames[into_b], life_jitter[into_b])
                        vx[ny, nx] = vy[ny, nx] = carry[ny, nx] = 0
                    flags[y, x] |= REACTED
                    flags[ny, nx] |= REACTED
                    reacted = True
                    break
                if reacted:
                    continue

            # 3. Movement: choose up to four moves to try in order, then walk them.
            kind = archetype[e]
            if kind == STATIC:
                continue
            old_vx = int(vx[y, x])
            old_vy = int(vy[y, x])
            cvx = old_vx
            cvy = old_vy
            loose = flags[y, x] & LOOSE
            g = fall_dir[e]
            falling = False
            coasting = False
            only_empty = kind == PARTICLE
            tries = 0
            d0x = d0y = d1x = d1y = d2x = d2y = d3x = d3y = 0
            if kind == PARTICLE:
                r = _mix32(h ^ SALT_ROUND)  # rolls for rounding speeds to cells
                loose = 0  # set when it lands
                cvy += accel[e]
                keep = drag_keep[e]
                if keep != 256:
                    cvx = _scaled(cvx, keep)
                    cvy = _scaled(cvy, keep)
                cvx = _clamped(cvx, max_speed[e])
                cvy = _clamped(cvy, max_speed[e])
                d0x = _cells_moved(cvx, r & 255)
                d0y = _cells_moved(cvy, (r >> 8) & 255)
                tries = 1 if d0x != 0 or d0y != 0 else 0
            else:
                ty = y + g
                if 0 <= ty < height and _enterable(displace[e, cells[ty, x]], cells[ty, x], flags[ty, x]):
                    # Falling (rising): speed up, go at least one cell, drift sideways.
                    falling = True
                    r = _mix32(h ^ SALT_ROUND)
                    speed = min(cvy * g + accel[e], max_speed[e])
                    cvy = speed * g
                    d0x = _cells_moved(cvx, (r >> 8) & 255)
                    d0y = g * max(1, _cells_moved(speed, r & 255))
                    d1y = g  # if the drift is blocked: straight on, one cell
                    tries = 2
                    loose = LOOSE
                elif kind == POWDER:
                    if loose == 0:
                        continue  # resting: stays put until the cell below opens or it is knocked
                    # Landing turns speed sideways; sliding on the ground wears it down.
                    u = abs(cvx)
                    side = (1 if cvx > 0 else -1) if cvx != 0 else (1 if h & 1 else -1)
                    impact = cvy * g
                    if impact > 0 or u == 0:  # landing, or freshly placed
                        u = min(max(u + ((impact * impact_share[e]) >> 8), MIN_SLIDE), max_speed[e])
                    cvy = 0
                    cvx = side * u
                    if u >= STOP_SPEED:
                        slide = _cells_moved(u, _mix32(h ^ SALT_ROUND) & 255)
                        coasting = slide == 0  # too slow to cross a cell this frame
                        d0x, d0y = side, g  # roll down the slope
                        d1x = side * slide  # slide along the ground
                        d2x, d2y = -side, g  # roll down the other side
                        tries = 1 if coasting else 3
                else:
                    # Liquids and gases on the ground: down a side, else flow sideways.
                    cvx = cvy = 0
                    if kind != LIQUID or (h >> 8) >= rest_chance[e]:  # viscous liquids often rest
                        side = 1 if h & 1 else -1
                        reach = int(dispersion[e])
                        d0x, d0y = side, g
                        d1x, d1y = -side, g
                        d2x = side * reach
                        d3x = -side * reach
                        tries = 4 if reach > 0 else 2

            # Walk each move along the line traversal; the first that gets anywhere wins.
            px = x
            py = y
            hit = False
            used = -1
            for a in range(tries):
                if a == 0:
                    dx, dy = d0x, d0y
                elif a == 1:
                    dx, dy = d1x, d1y
                elif a == 2:
                    dx, dy = d2x, d2y
                else:
                    dx, dy = d3x, d3y
                steps = max(abs(dx), abs(dy))
                hit = False
                for k in range(1, steps + 1):
                    qx, qy = _line_point(x, y, dx, dy, steps, k)
                    if qx < 0 or qy < 0 or qx >= width or qy >= height:
                        hit = True
                        break
                    o = cells[qy, qx]
                    if o != 0 and (only_empty or k > 1 or not _enterable(displace[e, o], o, flags[qy, qx])):
                        hit = archetype[o] != PARTICLE  # particles in a swarm wait for each other
                        break
                    if qx != px and qy != py:  # a diagonal step: one of its side cells must be open
                        c1 = cells[py, qx]
                        c2 = cells[qy, px]
                        if only_empty:
                            side_open = c1 == 0 or c2 == 0
                            hit = archetype[c1] != PARTICLE and archetype[c2] != PARTICLE
                        else:
                            side_open = displace[e, c1] != 0 or displace[e, c2] != 0
                            hit = True
                        if not side_open:
                            break
                        hit = False
                    px = qx
                    py = qy
                    if o != 0:
                        break  # swapped into a fluid: the move ends there
                if px != x or py != y:
                    used = a
                    break

            # Settle the new velocity.
            entered = cells[py, px]  # what the mover swaps with (0 when it goes into empty)
            if kind == PARTICLE:
                if hit or (tries == 0 and cvx == 0 and cvy == 0):
                    loose = LOOSE  # it lands: what it carries takes its place, moving as it flew
            elif falling:
                if entered != 0:
                    cvx = cvy = 0  # into a fluid: slowed to a crawl
                elif used == 1:
                    cvx = 0  # drift blocked
            elif kind == POWDER:
                # Friction brakes every frame of contact; rolling down a step gains speed.
                u = abs(cvx) - _scaled(accel[e], friction[e]) + (accel[e] if py != y else 0)
                if (used < 0 and not coasting) or u < STOP_SPEED or entered != 0:
                    loose = 0  # at rest (it may have moved this frame)
                    cvx = 0
                else:
                    cvx = (1 if (px > x or (px == x and cvx > 0)) else -1) * min(u, max_speed[e])

            if used < 0 and not (kind == PARTICLE and loose != 0):
                if cvx != old_vx or cvy != old_vy:
                    vx[y, x] = cvx
                    vy[y, x] = cvy
                if kind == POWDER:
                    flags[y, x] = (flags[y, x] & ~LOOSE) | loose
                continue

            # Move: swap everything with the cell at the end of the walk.
            if px != x or py != y:
                cells[y, x] = entered
                cells[py, px] = e
                shade[y, x], shade[py, px] = shade[py, px], shade[y, x]
                timer[y, x], timer[py, px] = timer[py, px], timer[y, x]
                carry[y, x], carry[py, px] = carry[py, px], carry[y, x]
                vx[y, x] = vx[py, px]
                vy[y, x] = vy[py, px]
                flags[y, x] = MOVED | (flags[py, px] & LOOSE)
            vx[py, px] = cvx
            vy[py, px] = cvy
            flags[py, px] = MOVED | loose

            if kind == PARTICLE:
                if loose != 0:  # landed: put down what it carries (or vanish)
                    into = carry[py, px]
                    cells[py, px] = into
                    carry[py, px] = 0
                    if into == 0:
                        vx[py, px] = vy[py, px] = 0
                    elif life_frames[e] != 0:  # the particle's own clock ran: start the cargo's
                        _, timer[py, px] = _spawn_state(_cell_key(spawn_key, px, py), life_frames[into], life_jitter[into])
                continue

            # A move knocks resting grains loose: those that could follow into the
            # vacated cell (pushed towards it) and those beside the arrival (pushed away).
            for k in range(6):
                if k < 4:
                    nx = x + (-1, 1, -1, 1)[k]
                    ny = y - (0, 0, 1, 1)[k]
                    push = (1, -1, 1, -1)[k]
                else:
                    nx = px + (-1, 1)[k - 4]
                    ny = py
                    push = (-1, 1)[k - 4]
                if nx < 0 or ny < 0 or nx >= width or ny >= height:
                    continue
                c = cells[ny, nx]
                if archetype[c] == POWDER and (flags[ny, nx] & LOOSE) == 0:
                    if (_cell_key(knock_key, nx, ny) >> 8) < knock_chance[c]:
                        flags[ny, nx] |= LOOSE
                        vx[ny, nx] = push * KNOCK_SPEED


@njit(cache=True)
def clear_marks(flags):
    """Forget what moved last frame; keep which grains are loose."""
    for y in range(flags.shape[0]):
        for x in range(flags.shape[1]):
            flags[y, x] &= LOOSE


@njit(cache=True)
def step(s, t, move_key, react_key, spawn_key, frame):
    """Advance the whole world by one frame."""
    clear_marks(s.flags)
    height, width = s.cells.shape
    step_region(s, t, move_key, react_key, spawn_key, frame, 0, 0, width, height)
