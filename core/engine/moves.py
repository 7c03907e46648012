"""Phase 4 of a cell's update, movement: the archetypes' moves, the walk along the line traversal,
the new velocity, and what a move does to its neighbours.

Movers (powders, liquids, gases) carry a velocity in 1/256ths of a cell per
frame. While the cell below (above, for rising gases) is open they fall,
accelerating by their gravity up to their terminal speed, and drift by their
sideways speed (:func:`falling_moves`). On the ground a loose powder grain
turns its landing speed into sideways speed, rolls or slides, and loses speed
to friction until it rests (:func:`powder_moves`); a resting grain moves
again when the cell below opens or a moving neighbour knocks it loose
(:func:`knock`). Liquids and gases on the ground flow sideways up to their
dispersion (:func:`fluid_moves`). Particles fly by their velocity through
empty cells and put down what they carry where they hit something
(:func:`particle_moves`, :func:`land`).

Every move of more than one cell walks the line traversal (:func:`walk`) and
stops at the first cell it may not enter: only the first cell of a move may
be a fluid to swap with (the move ends there), the others must be empty, and
a diagonal step needs one of its two side cells open, so nothing passes
through a wall or between two corners.

A new archetype takes a code in :data:`sandmod.engine.layout.ARCHETYPES`, a
chooser of moves here, and a branch for it in :func:`move`.
"""

from __future__ import annotations

import numpy as np

from .cells import (
    DONE,
    GAS,
    LIQUID,
    MOVED,
    PARTICLE,
    POWDER,
    STATIC,
    CARRIED,
    _at,
    _bit,
    _cell_key,
    _cells_moved,
    _clamped,
    _energy,
    _enterable,
    _inside,
    _line_point,
    _mix32,
    _plume_roll,
    _run_end,
    _scaled,
    _spawn_state,
    _temperature,
    _within,
    become,
    swap,
)
from .chunks import _unvisited
from .heat import _cooling_loss, stirs
from .jit import compiled, in_place, inlined
from .layout import ALWAYS, BURNING, EXPLOSIVE, FLAMMABLE, IGNITES, LOOSE, SUBCELL

# Powder on landing: its impact_share of the landing speed becomes sideways
# speed, and at least MIN_SLIDE; sideways speed below STOP_SPEED comes to rest.
MIN_SLIDE = SUBCELL // 4
STOP_SPEED = SUBCELL // 8
KNOCK_SPEED = SUBCELL // 2  # sideways speed of a grain knocked loose
SALT_ROUND = 0x165667B1
SALT_WAVER = 0x7A3B9C5D
OPEN, SHUT, WAIT = 0, 1, 2  # a move's first cell (see _way_into): go; no; not this frame, try again


@compiled
def _restless(f, th, life, energy, cold, hot, ignite):
    """Has a cell's own update work to do this frame: burning, a lifetime, a flame, or a
    phase change or a fire due (its flags, thermal bits, lifetime, heat and limits)?"""
    if (f & BURNING) != 0 or life != 0 or (th & IGNITES) != 0:
        return True
    return th != 0 and (energy < cold or energy > hot or ((th & FLAMMABLE) != 0 and energy >= ignite))


@compiled
def _way_into(kind, threshold, o, o_kind, o_flags, o_energy, o_thermal, o_life, o_cold, o_hot, o_ignite, level, moving, roll_key, x, y, qx, qy, forward, x0, y0, x1, y1, frame):
    """May a mover of archetype ``kind`` at (x, y), on its turn, go into (qx, qy), the first cell of a move,
    which holds ``o`` (its archetype, flags, heat energy, thermal bits, lifetime and heat limits)?

    OPEN, SHUT, or WAIT: not this frame, but maybe on a later one (its region
    stays awake). ``threshold`` is the mover's chance against ``o``
    (``Tables.displace``, not 0); one roll a frame under ``roll_key`` decides
    it for every move of the mover, so they agree. Into an empty cell: yes,
    but a gas at rest (not ``moving``) starts to rise or sink through the air
    only by the chance. Into a fluid: not one done this frame; ``level``
    (sideways), a liquid or gas trades places only with its own kind, and
    freely (one flowing into the other would move neither up nor down); not
    one still to have its own update this frame with work in it (no cell is
    moved out of its heat, fire or lifetime); up or down, by the chance.
    """
    fluid = kind == LIQUID or kind == GAS
    if o == 0:
        if threshold == ALWAYS or moving or level:
            return OPEN
    else:
        if (o_flags & DONE) != 0 or (level and fluid and o_kind != kind):
            return SHUT
        if _unvisited(qx, qy, x, y, forward, x0, y0, x1, y1, frame) and _restless(o_flags, o_thermal, o_life, o_energy, o_cold, o_hot, o_ignite):
            return WAIT
        if threshold == ALWAYS or (level and fluid):
            return OPEN
    roll = _cell_key(roll_key, x, y) if o == 0 else _plume_roll(roll_key, x, y)  # a gas leaves its rest by a roll of its own
    return OPEN if (roll >> 24) < threshold else WAIT


@inlined
def _way_into_cell(s, t, kind, threshold, qx, qy, level, moving, roll_key, x, y, forward, x0, y0, x1, y1, frame):
    """:func:`_way_into` for the cell at (qx, qy), read from the world and the tables."""
    o = s.cells[_at(qy, qx)]
    return _way_into(
        kind, threshold, o, t.archetype[o], s.flags[_at(qy, qx)], s.heat[_at(qy, qx)], t.thermal[o], t.life_frames[o], t.cold_limit[o],
        t.hot_limit[o], t.ignite_limit[o], level, moving, roll_key, x, y, qx, qy, forward, x0, y0, x1, y1, frame,
    )


@compiled
def _fluid_move_cell(x, y, g, k):
    """The first cell of a liquid's or gas's move k (0: on, 1 and 2: on and to a side, 3 and 4: to a side)."""
    return x + (0, 1, -1, 1, -1)[k], y + (g if k < 3 else 0)


@inlined
def may_flow(cells, displace, e, x, y, g):
    """Does a first cell of one of a liquid's or gas's five moves hold an element it may displace
    (the air too)? Read from the table, not the masks: with many elements loaded every bit of a
    fluid's mask is set, and a resting pool would never be let be."""
    height, width = cells.shape
    for k in range(5):
        nx, ny = _fluid_move_cell(x, y, g, k)
        if _inside(nx, ny, width, height) and displace[e, cells[_at(ny, nx)]] != 0:
            return True
    return False


@inlined
def slump_side(cells, displace, e, x, y, ty, first):
    """A grain of element e resting at (x, y) that cannot fall into (x, ty): the side (-1 or 1,
    ``first`` looked at first) where a fluid it sinks into lies diagonally below it, past a side
    cell it may also enter (empty, or such a fluid); 0 where there is none. In the air a grain at
    rest stays put until knocked (its inertial resistance); in a liquid it slumps, so a column of
    grains standing in water falls into a heap, and the water passes down beside it."""
    height, width = cells.shape
    if not _within(ty, height):
        return 0
    side = first
    for _ in range(2):
        nx = x + side
        if _within(nx, width):
            o = cells[_at(ty, nx)]
            if o != 0 and displace[e, o] != 0 and displace[e, cells[_at(y, nx)]] != 0:
                return side
        side = -side
    return 0


@inlined
def slump(s, t, e, x, y, ty, side, exchange_key, knock_key, forward, x0, y0, x1, y1, frame, ambient):
    """The grain of element e resting at (x, y) slumps into the fluid diagonally below it on
    ``side`` (see :func:`slump_side`), by its chance to trade places with it (as a move's first
    cell: :func:`_way_into`), and arrives at rest; the grains diagonally above the cell it left
    may be knocked loose. Returns (busy, stir, moved): whether anything changed or may, whether
    the heat field changed, and whether it went."""
    qx = x + side
    o = s.cells[_at(ty, qx)]
    way = _way_into_cell(s, t, POWDER, t.displace[e, o], qx, ty, False, False, exchange_key, x, y, forward, x0, y0, x1, y1, frame)
    if way != OPEN:
        return way == WAIT, False, False
    marks = s.flags[_at(y, x)] & (CARRIED & ~LOOSE)
    stir = stirs(int(s.heat[_at(y, x)]), t.heat_cap[e], t.cooling[e], int(s.heat[_at(ty, qx)]), t.heat_cap[o], t.cooling[o], ambient)
    swap(s, x, y, qx, ty, t.movers_hold[0] != 0 and (t.remembers[e] | t.remembers[o]) != 0)
    s.vx[_at(ty, qx)] = 0
    s.vy[_at(ty, qx)] = 0
    s.flags[_at(ty, qx)] = MOVED | marks
    knock(s, t, x, y, qx, ty, 2 * y - ty, knock_key, 2, 4)
    return True, stir, True


@compiled
def particle_moves(h, accel, keep, max_speed, cvx, cvy):
    """A particle in flight: gravity, drag (``keep`` of 256 kept), its speed clamped; the move is
    its velocity rounded to cells. Returns the move (dx, dy) and the new velocity."""
    r = _mix32(h ^ SALT_ROUND)  # rolls for rounding speeds to cells
    cvy += accel
    if keep != 256:
        cvx = _scaled(cvx, keep)
        cvy = _scaled(cvy, keep)
    cvx = _clamped(cvx, max_speed)
    cvy = _clamped(cvy, max_speed)
    return _cells_moved(cvx, r & 255), _cells_moved(cvy, (r >> 8) & 255), cvx, cvy


@compiled
def falling_moves(h, waver, kind, g, accel, max_speed, cvx, cvy):
    """Falling (rising): speed up, go at least one cell, drift sideways. A gas wavers as it rises,
    by ``waver``, a roll shared by the cells of its plume block (see :data:`~.layout.PLUME`): a
    cloud billows in puffs, neither a line nor static; a waver is one diagonal step, so that the
    gas behind it can follow (see :func:`follow_run`). Returns the first move (dx, dy) and the new
    vertical velocity; the second move, if the drift is blocked, is straight on, one cell."""
    r = _mix32(h ^ SALT_ROUND)
    speed = min(cvy * g + accel, max_speed)
    dx = _cells_moved(cvx, (r >> 8) & 255)
    dy = g * max(1, _cells_moved(speed, r & 255))
    if kind == GAS and (waver & 0x10000) != 0:
        dx += 1 if (waver & 0x20000) != 0 else -1
        dy = g
    return dx, dy, speed * g


@compiled
def powder_moves(h, g, impact_share, max_speed, cvx, cvy):
    """A loose grain on the ground: landing turns its speed sideways, and it rolls down a slope,
    slides along the ground, or rolls down the other side. Returns (tries, d0x, d0y, d1x, d2x,
    d2y, vx, coasting): coasting, too slow to cross a cell this frame, it tries the first only."""
    u = abs(cvx)
    side = (1 if cvx > 0 else -1) if cvx != 0 else (1 if h & 1 else -1)
    impact = cvy * g
    if impact > 0 or u == 0:  # landing, or freshly placed
        u = min(max(u + ((impact * impact_share) >> 8), MIN_SLIDE), max_speed)
    if u < STOP_SPEED:
        return 0, 0, 0, 0, 0, 0, side * u, False
    slide = _cells_moved(u, _mix32(h ^ SALT_ROUND) & 255)
    coasting = slide == 0
    return (1 if coasting else 3), side, g, side * slide, -side, g, side * u, coasting


@compiled
def fluid_moves(h, kind, g, can_flow, rest_chance, dispersion):
    """A liquid or gas on the ground: down a side, else flow sideways up to its dispersion; a viscous
    liquid often rests. Returns (tries, d0x, d0y, d1x, d1y, d2x, d3x, busy)."""
    if can_flow and kind == LIQUID and (h >> 8) < rest_chance:
        return 0, 0, 0, 0, 0, 0, 0, True  # it rests; it stays awake while it could flow
    if not can_flow:
        return 0, 0, 0, 0, 0, 0, 0, False
    side = 1 if h & 1 else -1
    reach = int(dispersion)
    return (4 if reach > 0 else 2), side, g, -side, g, side * reach, -side * reach, False


@inlined
def walk(s, t, x, y, e, kind, g, tries, d0x, d0y, d1x, d1y, d2x, d2y, d3x, d3y, moving, exchange_key, forward, x0, y0, x1, y1, frame):
    """Walk each of the ``tries`` moves along the line traversal; the first that gets anywhere wins.
    Returns where it got (px, py), whether it hit something, which move it used (-1: none), and
    whether a cell in its way may open on a later frame."""
    cells, displace, archetype = s.cells, t.displace, t.archetype
    height, width = cells.shape
    fluid = kind == LIQUID or kind == GAS
    free_air = kind != GAS
    only_empty = kind == PARTICLE
    px = x
    py = y
    hit = False
    used = -1
    waits = False
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
            if not _inside(qx, qy, width, height):
                hit = True
                break
            o = cells[_at(qy, qx)]
            if k == 1 and not only_empty and (o != 0 or not free_air):
                threshold = displace[e, o]
                if threshold == 0:
                    break
                if not (o == 0 and threshold == ALWAYS):
                    way = _way_into_cell(s, t, kind, threshold, qx, qy, qy == y, moving, exchange_key, x, y, forward, x0, y0, x1, y1, frame)
                    if way != OPEN:
                        waits = waits or way == WAIT
                        break
            elif o != 0:
                hit = archetype[o] != PARTICLE  # particles in a swarm wait for each other
                break
            if qx != px and qy != py:  # a diagonal step: one of its side cells must be open
                c1 = cells[_at(py, qx)]
                c2 = cells[_at(qy, px)]
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
            if dy == 0 and fluid and _within(qy + g, height) and cells[_at(qy + g, qx)] == 0:
                break  # flowing sideways over a drop: it falls from here
        if px != x or py != y:
            used = a
            break
    return px, py, hit, used, waits


@compiled
def settle(kind, falling, coasting, hit, tries, used, entered, x, y, px, py, cvx, cvy, loose, accel, friction, max_speed):
    """The mover's velocity and LOOSE bit after its walk: a particle that hit something (or stopped)
    lands; a fall into a fluid is slowed to a crawl, a blocked drift stops; friction brakes a grain
    every frame of contact, rolling down a step gains speed, and a slow grain comes to rest."""
    if kind == PARTICLE:
        if hit or (tries == 0 and cvx == 0 and cvy == 0):
            loose = LOOSE  # it lands: what it carries takes its place, moving as it flew
    elif falling:
        if entered != 0:
            cvx = cvy = 0
        elif used == 1:
            cvx = 0
    elif kind == POWDER:
        u = abs(cvx) - _scaled(accel, friction) + (accel if py != y else 0)
        if (used < 0 and not coasting) or u < STOP_SPEED or entered != 0:
            loose = 0  # at rest (it may have moved this frame)
            cvx = 0
        else:
            cvx = (1 if (px > x or (px == x and cvx > 0)) else -1) * min(u, max_speed)
    return cvx, cvy, loose


@inlined
def land(s, t, x, y, e, spawn_key):
    """A particle landed at (x, y): what it carries takes its place (or nothing), at the particle's
    temperature, moving as it flew; where the particle's own clock ran, the cargo's starts.
    Returns the cargo's bit."""
    into = s.carry[_at(y, x)]
    s.cells[_at(y, x)] = into
    s.carry[_at(y, x)] = 0
    s.heat[_at(y, x)] = _energy(_temperature(int(s.heat[_at(y, x)]), t.heat_recip[e]), t.heat_cap[into])
    if into == 0:
        s.vx[_at(y, x)] = s.vy[_at(y, x)] = 0
    elif t.life_frames[e] != 0:
        _, s.timer[_at(y, x)] = _spawn_state(_cell_key(spawn_key, x, y), t.life_frames[into], t.life_jitter[into])
    return _bit(into)


@inlined
def _impact_speed(s, x, ty, g, vy):
    """How hard a mover falling at ``vy`` (along g) lands on the cell at (x, ty): its speed less that of
    the cell, where that falls the same way too; the world's edge stands still."""
    if not _within(ty, s.cells.shape[0]):
        return vy * g
    return vy * g - max(int(s.vy[_at(ty, x)]) * g, 0)


@inlined
def lands_hard(s, t, e, x, ty, g, vy):
    """Does a mover of element e at speed ``vy`` land on the cell at (x, ty), one it can never enter (or
    the world's edge), fast enough to break it or itself (``Tables.impact``)? (Plunging into a fluid
    it may enter, only the fluid can break: see :func:`move`.)"""
    if not _within(ty, s.cells.shape[0]):
        return vy * g >= t.impact[e]
    o = s.cells[_at(ty, x)]
    if t.displace[e, o] != 0:
        return False  # it will sink into it: no landing
    speed = _impact_speed(s, x, ty, g, vy)
    return speed >= t.impact[e] or speed >= t.impact[o]


@in_place  # rare (a hard landing): called, not copied into the cell update, which compiles faster so
def shatter(s, t, x, y, c, spawn_key):
    """The cell at (x, y), of element c, is struck hard enough to break: an explosive is lit (it goes off
    on its own turn, :func:`~.fire.heat_and_fire`), anything else becomes its ``breaks_into``, at its
    temperature, loose and done for the frame. Returns the bit of what it became (0 when lit)."""
    if (t.thermal[c] & EXPLOSIVE) != 0:
        s.flags[_at(y, x)] |= BURNING
        return np.int64(0)
    warmth = _temperature(int(s.heat[_at(y, x)]), t.heat_recip[c])
    return become(s, t, x, y, t.breaks_into[c], warmth, MOVED | LOOSE, _cell_key(spawn_key, x, y))


@in_place  # rare (a hard landing): called, not copied into the cell update, which compiles faster so
def smash(s, t, x, y, e, ty, g, vy, spawn_key):
    """A mover of element e at (x, y) landed hard on the cell at (x, ty) (see :func:`lands_hard`): each of
    the two the landing speed reaches breaks (:func:`shatter`). A mover that stays whole keeps its speed,
    to fall on where what it broke gives way. Returns the bits of what they broke into."""
    speed = _impact_speed(s, x, ty, g, vy)
    born = np.int64(0)
    if _within(ty, s.cells.shape[0]) and speed >= t.impact[s.cells[_at(ty, x)]]:
        born |= shatter(s, t, x, ty, s.cells[_at(ty, x)], spawn_key)
    if speed >= t.impact[e]:
        born |= shatter(s, t, x, y, e, spawn_key)
    return born


@inlined
def knock(s, t, x, y, px, py, back, knock_key, first, last):
    """A move from (x, y) to (px, py) knocks resting grains loose, each by its chance: those that
    could follow into the vacated cell (pushed towards it) and those beside the arrival (pushed
    away); of these six (beside the vacated cell, diagonally above it, beside the arrival) the
    ``first`` to the ``last`` - 1. A grain that sinks into a fluid with nothing following it
    knocks only the two diagonally above the cell it left (the fluid damps the rest): so a heap
    under water slumps. ``back``: the row of grains that could follow into the vacated cell, the
    one above it (below it, where a grain that falls upwards left it)."""
    cells, flags = s.cells, s.flags
    height, width = cells.shape
    if (
        x > 0
        and _within(back, height)
        and px > 0
        and x + 1 < width
        and px + 1 < width
        and (
            flags[_at(y, x - 1)] & flags[_at(y, x + 1)] & flags[_at(back, x - 1)] & flags[_at(back, x + 1)]
            & flags[_at(py, px - 1)] & flags[_at(py, px + 1)] & LOOSE
        )
        != 0
    ):
        return  # all six are in motion already (the common case)
    for k in range(first, last):
        if k < 4:
            nx = x + (-1, 1, -1, 1)[k]
            ny = (y, y, back, back)[k]
            push = (1, -1, 1, -1)[k]
        else:
            nx = px + (-1, 1)[k - 4]
            ny = py
            push = (-1, 1)[k - 4]
        if not _inside(nx, ny, width, height):
            continue
        if (flags[_at(ny, nx)] & LOOSE) != 0:
            continue  # already in motion (fluids stay loose)
        c = cells[_at(ny, nx)]
        if t.knock_chance[c] != 0:  # only powders have a chance
            if (_cell_key(knock_key, nx, ny) >> 8) < t.knock_chance[c]:
                flags[_at(ny, nx)] |= LOOSE
                s.vx[_at(ny, nx)] = push * KNOCK_SPEED


@inlined
def _run_last(s, t, x, y, g, fluid, run_key):
    """The last row, from y going against g, of the movers behind row y in its run of rows (see
    :data:`~.layout.PLUME_RUN`) that could move into ``fluid`` too: y where none could. The run
    stops at a cell done this frame or with work of its own due."""
    cells, flags, heat = s.cells, s.flags, s.heat
    end = min(max(_run_end(run_key, x, y, g), 0), cells.shape[0] - 1)
    fy = y
    while fy != end:
        ny = fy - g
        c = cells[_at(ny, x)]
        f = flags[_at(ny, x)]
        if t.fall_dir[c] != g or t.displace[c, fluid] == 0 or (f & DONE) != 0:
            break
        if _restless(f, t.thermal[c], t.life_frames[c], heat[_at(ny, x)], t.cold_limit[c], t.hot_limit[c], t.ignite_limit[c]):
            break
        fy = ny
    return fy


@inlined
def _shift_run(s, t, x, hole, last, g, lead, carried_vy, ambient):
    """Each cell of column x from row ``hole`` - g back to row ``last`` moves a cell along g, and
    what row ``hole`` held goes to row ``last``. The cell from row ``lead`` keeps its velocity and
    flags (the caller's to set); the others are carried along, at rest but for ``carried_vy``. Returns whether the heat
    field changed (cells of another temperature traded places, or one of them cools: see
    :func:`~.heat.stirs`)."""
    cells, flags, heat, shade, timer, vx, vy = s.cells, s.flags, s.heat, s.shade, s.timer, s.vx, s.vy
    fluid = cells[_at(hole, x)]
    f_heat, f_cap, f_flags = int(heat[_at(hole, x)]), t.heat_cap[fluid], flags[_at(hole, x)]
    f_shade, f_timer, f_vx, f_vy = shade[_at(hole, x)], timer[_at(hole, x)], vx[_at(hole, x)], vy[_at(hole, x)]
    stir = _cooling_loss(f_heat, f_cap, t.cooling[fluid], ambient) != 0
    r = hole
    while r != last:  # each mover from the lead back a cell along g, into row r
        q = r - g
        c = cells[_at(q, x)]
        h = int(heat[_at(q, x)])
        stir = stir or h * f_cap != f_heat * t.heat_cap[c] or _cooling_loss(h, t.heat_cap[c], t.cooling[c], ambient) != 0
        cells[_at(r, x)] = c
        heat[_at(r, x)] = h
        shade[_at(r, x)] = shade[_at(q, x)]
        timer[_at(r, x)] = timer[_at(q, x)]
        if q != lead:  # a follower: carried along
            vx[_at(r, x)] = 0
            vy[_at(r, x)] = carried_vy
            flags[_at(r, x)] = MOVED | (flags[_at(q, x)] & CARRIED)
        r = q
    cells[_at(last, x)] = fluid
    heat[_at(last, x)] = f_heat
    shade[_at(last, x)] = f_shade
    timer[_at(last, x)] = f_timer
    vx[_at(last, x)] = f_vx
    vy[_at(last, x)] = f_vy
    flags[_at(last, x)] = MOVED | (f_flags & CARRIED)
    if t.movers_hold[0] != 0:  # cells that hold an element take it along (where a powder, liquid or gas can hold)
        _shift_held(s.carry, x, hole, last, g)
    return stir


@compiled
def _shift_held(carry, x, hole, last, g):
    """What the cells of column x hold, shifted as :func:`_shift_run` shifted them."""
    f_carry = carry[_at(hole, x)]
    r = hole
    while r != last:
        carry[_at(r, x)] = carry[_at(r - g, x)]
        r -= g
    carry[_at(last, x)] = f_carry


@inlined
def sink_run(s, t, x, y, g, run_key, ambient):
    """The faller at (x, y) sinks into the fluid below it (rises into the one above, for g = -1),
    and the fallers behind it in its run of rows (:func:`_run_last`) that could sink into that
    fluid too follow it, a cell each: the fluid rises through them to the run's end, in one turn
    of the column. So a body of sand sinks into water as a whole, the water rising through it in
    channels, with no comb of alternating rows. The followers are left at rest, as they were;
    the lead's velocity and flags are the caller's to set. Returns the row the fluid ended at,
    and whether the heat field changed (see :func:`_shift_run`)."""
    fy = _run_last(s, t, x, y, g, s.cells[_at(y + g, x)], run_key)
    return fy, _shift_run(s, t, x, y + g, fy, g, y, 0, ambient)


@inlined
def follow_run(s, t, x, y, g, k, vy, run_key, ambient):
    """A gas has just risen (sunk) out of (x, y), ``k`` cells straight on (1: it wavered): the gases
    behind it in its run of rows that could move into what took its place follow it as far, as
    the fallers behind a faller do (see :func:`sink_run`), at its velocity ``vy``. So a cloud rises
    as a body, with no comb of alternating rows. Returns the last row of the run, and whether the heat field changed."""
    fy = _run_last(s, t, x, y, g, s.cells[_at(y, x)], run_key)
    if fy == y:
        return y, False
    stir = False
    for j in range(k):  # a row at a time: each pass moves the run into the next cell the lead left
        stir = _shift_run(s, t, x, y + g * j, fy + g * j, g, -1, vy, ambient) or stir
    return fy, stir


@inlined
def move(s, t, x, y, e, present, move_key, exchange_key, knock_key, spawn_key, forward, x0, y0, x1, y1, frame, ambient):
    """Phase 4: choose up to four moves by the archetype, walk them, settle the velocity, and swap.
    A mover that lands hard (:func:`lands_hard`), or plunges hard into a fluid that breaks, breaks
    what the speed reaches (:func:`smash`, :func:`shatter`) instead, and stays put this frame.
    Returns (busy, stir, born, px, py, ry): as the other phases' (see :mod:`.fire`), where the
    mover ended up, and the farthest row a run that followed it reached (y where none did)."""
    cells, vx, vy, flags = s.cells, s.vx, s.vy, s.flags
    height, width = cells.shape
    kind = t.archetype[e]
    if kind == STATIC:
        return False, False, np.int64(0), x, y, y
    old_vx = int(vx[_at(y, x)])
    old_vy = int(vy[_at(y, x)])
    g = t.fall_dir[e]
    ty = y + g  # the cell it falls (rises) into
    fluid = kind == LIQUID or kind == GAS
    displaces = t.displaces[e]
    if fluid and old_vx == 0 and old_vy == 0:
        # At rest, first a cheap test of its five moves' cells: holds none an element it may displace?
        # Then it stays put, as most of a body of liquid does.
        if (displaces & present) == 0 or not may_flow(cells, t.displace, e, x, y, g):
            return False, False, np.int64(0), x, y, y
    busy = False
    opens = False
    plunge = False  # into a fluid below, fast enough to break it (see lands_hard)
    if kind != PARTICLE and _within(ty, height):
        o = cells[_at(ty, x)]
        threshold = t.displace[e, o]
        opens = o == 0 and kind != GAS  # the commonest case, decided at once (a gas rises through air by a roll)
        if not opens and threshold != 0:
            way = _way_into_cell(s, t, kind, threshold, x, ty, False, old_vy != 0, exchange_key, x, y, forward, x0, y0, x1, y1, frame)
            opens = way == OPEN
            plunge = opens and g * old_vy > 0 and o != 0 and _impact_speed(s, x, ty, g, old_vy) >= t.impact[o]
            if way == WAIT:
                busy = True
                if kind == POWDER:
                    return busy, False, np.int64(0), x, y, y  # a grain waits for its chance to sink (fluids flow aside meanwhile)
    can_flow = False  # liquids and gases on the ground: is the first cell of any of their moves open?
    if fluid and not opens and (displaces & present) != 0:
        for k in range(1, 5):  # the cells may_flow looks at, less the one below
            nx, ny = _fluid_move_cell(x, y, g, k)
            if _inside(nx, ny, width, height) and _enterable(t.displace[e, cells[_at(ny, nx)]], cells[_at(ny, nx)], flags[_at(ny, nx)]):
                can_flow = True
                break
        if not can_flow and old_vx == 0 and old_vy == 0:
            return busy, False, np.int64(0), x, y, y  # at rest, every move shut (by cells done this frame)
    # Straight into a fluid below: one cell, where its speed is lost anyway; no rolls needed.
    straight = opens and old_vx == 0 and cells[_at(ty, x)] != 0
    h = 0 if straight else _cell_key(move_key, x, y)
    cvx, cvy = old_vx, old_vy
    loose = flags[_at(y, x)] & LOOSE
    falling = coasting = False
    tries = d0x = d0y = d1x = d1y = d2x = d2y = d3x = d3y = 0
    if kind == PARTICLE:
        busy = True  # in flight until it lands
        loose = 0  # set when it lands
        d0x, d0y, cvx, cvy = particle_moves(h, t.accel[e], t.drag_keep[e], t.max_speed[e], cvx, cvy)
        tries = 1 if d0x != 0 or d0y != 0 else 0
    elif plunge:  # the fluid breaks (an explosive is lit) instead of giving way; the mover keeps its speed
        return True, True, shatter(s, t, x, ty, cells[_at(ty, x)], spawn_key), x, y, y
    elif opens:
        falling = True
        loose = LOOSE
        if straight:
            d0y = g
        else:
            waver = _plume_roll(_mix32(move_key ^ SALT_WAVER), x, y) if kind == GAS else 0
            d0x, d0y, cvy = falling_moves(h, waver, kind, g, t.accel[e], t.max_speed[e], cvx, cvy)
            d1y = g  # if the drift is blocked: straight on, one cell
            tries = 2
    elif (g > 0 or kind == POWDER) and g * cvy > 0 and _within(ty, height) and g * vy[_at(ty, x)] > 0 and t.archetype[cells[_at(ty, x)]] != STATIC and (flags[_at(ty, x)] & DONE) == 0:
        # The cell ahead falls too and has not had its turn (another tile's, or, for a grain that falls
        # upwards, a row the sweep reaches later): wait for it.
        return True, False, np.int64(0), x, y, y
    elif kind == GAS and _within(ty, height) and vy[_at(ty, x)] != 0 and t.fall_dir[cells[_at(ty, x)]] == g and t.archetype[cells[_at(ty, x)]] == GAS and (flags[_at(ty, x)] & DONE) == 0:
        return True, False, np.int64(0), x, y, y  # the gas ahead rises (sinks) and has yet to move: wait to follow it (follow_run)
    elif g * old_vy > 0 and lands_hard(s, t, e, x, ty, g, old_vy):  # a landing (rare), and a hard one (rarer)
        return True, True, smash(s, t, x, y, e, ty, g, old_vy, spawn_key), x, y, y
    elif kind == POWDER:
        if loose == 0:  # resting: stays put until the cell below opens or it is knocked, or slumps into a fluid
            side = slump_side(cells, t.displace, e, x, y, ty, 1 if forward else -1)
            if side == 0:
                return busy, False, np.int64(0), x, y, y
            b, stir, moved = slump(s, t, e, x, y, ty, side, exchange_key, knock_key, forward, x0, y0, x1, y1, frame, ambient)
            return busy or b, stir, np.int64(0), x + side * moved, ty if moved else y, y
        tries, d0x, d0y, d1x, d2x, d2y, cvx, coasting = powder_moves(h, g, t.impact_share[e], t.max_speed[e], cvx, cvy)
        cvy = 0
    else:
        cvx = cvy = 0
        tries, d0x, d0y, d1x, d1y, d2x, d3x, rests = fluid_moves(h, kind, g, can_flow, t.rest_chance[e], t.dispersion[e])
        busy = busy or rests

    if falling and d0x == 0 and d0y == g:  # one cell straight on, into the cell found open above
        px, py, hit, used = x, ty, False, 0
    else:
        px, py, hit, used, waits = walk(s, t, x, y, e, kind, g, tries, d0x, d0y, d1x, d1y, d2x, d2y, d3x, d3y, old_vy != 0, exchange_key, forward, x0, y0, x1, y1, frame)
        busy = busy or waits
    entered = cells[_at(py, px)]  # what the mover swaps with (0 when it goes into empty)
    cvx, cvy, loose = settle(kind, falling, coasting, hit, tries, used, entered, x, y, px, py, cvx, cvy, loose, t.accel[e], t.friction[e], t.max_speed[e])

    if used < 0 and not (kind == PARTICLE and loose != 0):  # it stays: only its velocity and LOOSE bit change
        if cvx != old_vx or cvy != old_vy:
            vx[_at(y, x)] = cvx
            vy[_at(y, x)] = cvy
            busy = True
        if kind == POWDER and (flags[_at(y, x)] & LOOSE) != loose:
            flags[_at(y, x)] ^= LOOSE
            busy = True
        return busy or (kind == POWDER and loose != 0), False, np.int64(0), x, y, y  # a loose grain is still in motion

    stir = False
    born = np.int64(0)
    marks = flags[_at(y, x)] & (CARRIED & ~LOOSE)  # what travels with the mover besides LOOSE
    ry = y
    if entered != 0 and px == x and py == ty:  # sank straight into a fluid: the run behind it follows
        ry, stir = sink_run(s, t, x, y, g, exchange_key, ambient)
    elif px != x or py != y:
        # Heat stays even where two cells of one temperature trade places and neither cools.
        stir = stirs(int(s.heat[_at(y, x)]), t.heat_cap[e], t.cooling[e], int(s.heat[_at(py, px)]), t.heat_cap[entered], t.cooling[entered], ambient)
        swap(s, x, y, px, py, kind == PARTICLE or (t.movers_hold[0] != 0 and (t.remembers[e] | t.remembers[entered]) != 0))
        if (kind == GAS or g < 0) and py != y:  # a gas rose (sank), a grain rose: the cells behind it follow
            ry, followed = follow_run(s, t, x, y, g, abs(py - y) if px == x else 1, cvy, exchange_key, ambient)
            stir = stir or followed
    vx[_at(py, px)] = cvx
    vy[_at(py, px)] = cvy
    flags[_at(py, px)] = MOVED | loose | marks
    if kind == PARTICLE:
        if loose != 0:  # landed
            born = land(s, t, px, py, e, spawn_key)
            stir = True
    elif entered == 0:
        knock(s, t, x, y, px, py, y - g if kind == POWDER else y - 1, knock_key, 0, 6)
    elif ry == y:  # sank, and no run followed it into the cell it left
        knock(s, t, x, y, px, py, y - g if kind == POWDER else y - 1, knock_key, 2, 4)
    return True, stir, born, px, py, ry
