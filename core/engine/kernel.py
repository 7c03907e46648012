"""The numba kernel: one frame of the cellular automaton.

The kernel reads only what it is given: the world's arrays (a
:class:`~sandmod.world.world.State`), the compiled :class:`~sandmod.rules.compiler.Tables`,
and per-frame hash keys. Adding or editing a mod changes the tables' contents,
never the compiled code.

Order within a frame: tiles of 64 x 64 cells in four passes by their
parity, the tiles of a pass in parallel (:func:`step`); within a tile, heat
first (:func:`conduct`), then rows bottom-up, the horizontal direction
alternating with the row and the frame (:func:`step_region`). Only the
rows of the awake chunks (32 x 32) that their wake marks name are touched. A
cell is updated once: its lifetime ticks, it may react with a touching
neighbour, and then it moves by its archetype. A cell that moved or changed
this frame is marked and left alone for the rest of the frame.

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
(:func:`sandmod.engine.traversal.line_point`) and stops at the first cell it may not
enter: only the first cell of a move may be a fluid to swap with (the move
ends there), the others must be empty, and a diagonal step needs one of its
two side cells open, so nothing passes through a wall or between two corners.

The per-cell update is written out in one function on purpose: numba counts
references to every array handed to a helper, and at a few hundred million
cells a second that bookkeeping costs more than the physics. Helpers here take
and return plain numbers only, and are plain numba functions, which LLVM
inlines: inlining them in numba first (``inline="always"``) made code no
faster and took a third longer to compile. Only :func:`_wake`, handed
the chunk marks, is inlined by numba, so that no counting comes with it. The
per-cell code reads and writes the world's arrays at :func:`_at`, unsigned
indices, which numba need not wrap around.

That one function holds more values than the CPU has registers, so the
commonest cells (those that stay put, and a straight fall into a fluid) can
also go through a small loop of their own first, compiled as a second
version of :func:`step_region`. It pays where most cells are such (sand
sinking through water), and costs where most are not (cells in flight),
since each cell it hands on to the full update reloads that update's values;
each tile takes it while it pays, and the frames are the same either way.
"""

from __future__ import annotations

import numpy as np

from . import hashing, traversal
from .jit import njit, numba, prange
from .hashing import ROLL_BITS
from .layout import (
    ALWAYS,
    ARCHETYPE_CODES,
    BLAST_COLUMNS,
    BLAST_FLING,
    BLAST_HEAT,
    BLAST_LEAVES,
    BLAST_LEAVES_CHANCE,
    BLAST_RADIUS,
    BLAST_SCORCH,
    BLAST_SPEED,
    BLAST_STRENGTH,
    BLAST_X,
    BLAST_Y,
    BURNING,
    CACHE_LINE,
    CHUNK,
    CHUNK_SHIFT,
    DETONATING,
    EXPLOSIVE,
    FLAMMABLE,
    IGNITES,
    LOOSE,
    MAX_TEMPERATURE,
    MIN_TEMPERATURE,
    MOVED,
    PART,
    REACTED,
    SCORCHED,
    SUBCELL,
    TEMP_ONE,
    TILE,
    TILE_SHIFT,
    WAKE_MARGIN,
    WHOLE,
)
from .prefetch import prefetch

_mix32 = njit(cache=True)(hashing.mix32)
_spawn_state = njit(cache=True)(hashing.spawn_state)
_line_point = njit(cache=True)(traversal.line_point)

STATIC = ARCHETYPE_CODES["static"]
POWDER = ARCHETYPE_CODES["powder"]
LIQUID = ARCHETYPE_CODES["liquid"]
GAS = ARCHETYPE_CODES["gas"]
PARTICLE = ARCHETYPE_CODES["particle"]

DONE = MOVED | REACTED  # flag bits (defined beside world.State) of a cell no other may move this frame
KEPT = LOOSE | BURNING | SCORCHED  # flag bits that travel with a cell
CARRIED = KEPT | REACTED  # and those it takes along when it moves (REACTED until the frame ends)
FRESH = ~(BURNING | SCORCHED)  # a cell turning into another element keeps only these flag bits
T_LOW = int(MIN_TEMPERATURE * TEMP_ONE)
T_HIGH = int(MAX_TEMPERATURE * TEMP_ONE)

# Powder on landing: its impact_share of the landing speed becomes sideways
# speed, and at least MIN_SLIDE; sideways speed below STOP_SPEED comes to rest.
MIN_SLIDE = SUBCELL // 4
STOP_SPEED = SUBCELL // 8
KNOCK_SPEED = SUBCELL // 2  # sideways speed of a grain knocked loose
SALT_KNOCK = 0x27D4EB2F
SALT_ROUND = 0x165667B1
SALT_FIRE = 0x61C88647
SALT_EXCHANGE = 0x3243F6A9
OPEN, SHUT, WAIT = 0, 1, 2  # a move's first cell (see _way_into): go; no; not this frame, try again
LINE_CELLS = CACHE_LINE // 4  # cells in a cache line of the widest array (heat, 4 bytes): a row's lines are asked for this far apart
CACHED_CELLS = 1 << 16  # a world of no more cells (about a megabyte of state) stays in the CPU's cache: nothing to prefetch
EVEN, SWEPT = 1, 2  # marks of conduct's `even`: heat known to be even; being swept whole this frame
HANDED_ON_COST = 4  # step_region's fast loop pays where it hands on fewer than one in this many cells of the rows it updates
FAST_TRIAL = 8  # a tile whose fast loop did not pay tries it again every this many frames (a power of two)


@njit(cache=True)
def _at(y, x):
    """The index of row y, column x of a world-sized (or chunk-sized) array, in bounds (the caller checks).

    Unsigned, so numba leaves out its wrap-around of negative indices: a fifth
    of the per-cell time. A negative index here would read out of bounds, not
    from the far edge, so test coordinates before reading (as every cell read
    does); ``tests/test_bounds.py`` runs busy worlds with bounds checks on.
    """
    return np.uint64(y), np.uint64(x)


@njit(cache=True)
def _mark(cy, cx):
    """The index of chunk (cy, cx)'s entry in ``woken`` or ``stirred`` (each entry on a cache line of its own)."""
    return np.uint64(cy), np.uint64(cx), np.uint64(0)


@njit(cache=True)
def _within(v, limit):
    """0 <= v < limit, in one unsigned comparison (a negative v wraps to a huge one)."""
    return np.uint64(v) < np.uint64(limit)


@njit(cache=True)
def _inside(x, y, width, height):
    """Is cell (x, y) in the world? Two comparisons instead of four."""
    return _within(x, width) and _within(y, height)


@njit(cache=True)
def _cell_key(key, x, y):
    """The hash of cell (x, y) under a frame key."""
    return _mix32(key ^ ((y << 16) | x))


@njit(cache=True)
def _enterable(displaceable, occupant, occupant_flags):
    """May a mover take this place? Only lighter fluids give way, and not twice a frame
    (empty cells excepted: they have nothing to lose)."""
    return displaceable != 0 and (occupant == 0 or (occupant_flags & DONE) == 0)


@njit(cache=True)
def _pass_tiles(p, frame):
    """The parity of the tiles' columns and rows that pass p (0..3) of a frame updates.

    The order of the four passes changes with the frame, so a falling stream
    crosses each seam in step (see :func:`step`)."""
    return (p & 1) ^ ((frame >> 1) & 1), (p >> 1) ^ (frame & 1) ^ 1


@njit(cache=True)
def _pass_of(tx, ty, frame):
    """The pass (0..3) of a frame in which tile (tx, ty) is updated."""
    for p in range(4):
        px, py = _pass_tiles(p, frame)
        if px == (tx & 1) and py == (ty & 1):
            return p
    return -1


@njit(cache=True)
def _unvisited(qx, qy, x, y, forward, x0, y0, x1, y1, frame):
    """Is cell (qx, qy) still to have its turn this frame, while (x, y) has its own in the
    region x0..x1-1, y0..y1-1 (rows bottom-up, each row forward or back)? A cell of another
    tile has it if that tile's pass comes later."""
    if x0 <= qx < x1 and y0 <= qy < y1:
        return qy < y or (qy == y and (qx > x) == forward)
    return _pass_of(qx >> TILE_SHIFT, qy >> TILE_SHIFT, frame) > _pass_of(x0 >> TILE_SHIFT, y0 >> TILE_SHIFT, frame)


@njit(cache=True)
def _restless(f, th, life, energy, cold, hot, ignite):
    """Has a cell's own update work to do this frame: burning, a lifetime, a flame, or a
    phase change or a fire due (its flags, thermal bits, lifetime, heat and limits)?"""
    if (f & BURNING) != 0 or life != 0 or (th & IGNITES) != 0:
        return True
    return th != 0 and (energy < cold or energy > hot or ((th & FLAMMABLE) != 0 and energy >= ignite))


@njit(cache=True)
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
    return OPEN if (_cell_key(roll_key, x, y) >> 24) < threshold else WAIT


@njit(cache=True)
def _cells_moved(speed, roll):
    """A speed in 1/256ths of a cell, rounded to whole cells at random (roll: 0..255), unbiased."""
    return (speed >> 8) + (1 if (speed & 255) > roll else 0)


@njit(cache=True)
def _scaled(value, keep):
    """value * keep / 256, rounded towards zero."""
    return (value * keep) >> 8 if value >= 0 else -((-value * keep) >> 8)


@njit(cache=True)
def _clamped(value, limit):
    return max(-limit, min(limit, value))


@njit(cache=True)
def _temperature(energy, recip):
    """A cell's temperature (TEMP_ONE units) from its heat energy and 2**32 / heat capacity.

    Exact for energies that are whole multiples of the capacity, below zero too.
    """
    return (energy * recip) >> 32 if energy >= 0 else -((-energy * recip) >> 32)


@njit(cache=True)
def _energy(temperature, cap):
    """The heat energy of a cell at ``temperature`` (clamped to the allowed range)."""
    return max(T_LOW, min(T_HIGH, temperature)) * cap


@njit(cache=True)
def _cooling_loss(energy, cap, cooling, ambient):
    """The heat a cell of ``cooling`` (of 256) gains per frame towards the outside's temperature (a loss when warmer)."""
    return _scaled(_energy(ambient, cap) - energy, cooling) if cooling != 0 else 0


@njit(inline="always", cache=True)
def _stirs(heat_a, cap_a, cooling_a, heat_b, cap_b, cooling_b, ambient):
    """Does a swap of cells a and b change the heat field? Not where two cells of one temperature
    trade places and neither cools (see :func:`conduct`)."""
    return (
        heat_a * cap_b != heat_b * cap_a
        or _cooling_loss(heat_a, cap_a, cooling_a, ambient) != 0
        or _cooling_loss(heat_b, cap_b, cooling_b, ambient) != 0
    )


@njit(cache=True)
def _fluid_move_cell(x, y, g, k):
    """The first cell of a liquid's or gas's move k (0: on, 1 and 2: on and to a side, 3 and 4: to a side)."""
    return x + (0, 1, -1, 1, -1)[k], y + (g if k < 3 else 0)


@njit(cache=True)
def _first_row(mark):
    """The first (chunk-local) row a PART wake mark names."""
    return mark & 63


@njit(cache=True)
def _last_row(mark):
    """The last (chunk-local) row a PART wake mark names."""
    return (mark >> 6) & 63


@njit(cache=True)
def _widened(mark, y0, y1):
    """A chunk's wake mark (see :data:`sandmod.world.world.WHOLE`) widened to cover its rows y0..y1 (chunk-local)."""
    if mark == WHOLE:
        return WHOLE
    if mark != 0:
        y0 = min(y0, _first_row(mark))
        y1 = max(y1, _last_row(mark))
    if y0 == 0 and y1 == CHUNK - 1:
        return WHOLE  # quicker to read, and to widen
    return PART | y0 | (y1 << 6)


@njit(cache=True)
def _covers(mark, row):
    """Does a chunk's wake mark cover its (chunk-local) row?"""
    return mark == WHOLE or (mark != 0 and _first_row(mark) <= row <= _last_row(mark))


@njit(cache=True)
def _grown(x0, y0, x1, y1, width, height):
    """The cells x0..x1, y0..y1 and those within WAKE_MARGIN of them, in the world (inclusive)."""
    return max(x0 - WAKE_MARGIN, 0), max(y0 - WAKE_MARGIN, 0), min(x1 + WAKE_MARGIN, width - 1), min(y1 + WAKE_MARGIN, height - 1)


@njit(inline="always", cache=True)  # it takes arrays: called, it made its callers count references to all of theirs
def _wake(woken, stirred, stir, x0, y0, x1, y1):
    """Mark the cells x0..x1, y0..y1 (in the world, inclusive) in the wake marks of their chunks, and stir those chunks if ``stir``."""
    for wy in range(y0 >> CHUNK_SHIFT, (y1 >> CHUNK_SHIFT) + 1):
        oy = wy << CHUNK_SHIFT
        for wx in range(x0 >> CHUNK_SHIFT, (x1 >> CHUNK_SHIFT) + 1):
            woken[_mark(wy, wx)] = _widened(woken[_mark(wy, wx)], max(y0 - oy, 0), min(y1 - oy, CHUNK - 1))
            if stir:
                stirred[_mark(wy, wx)] = 1


@njit(cache=True)
def _bit(e):
    """Element e's bit in the element masks (``reactive``, ``displaces``): bit e % 64."""
    return np.int64(1) << (e & 63)


@njit(inline="always", cache=True)  # it takes an array: see _wake
def _elements_in(cells, x0, y0, x1, y1):
    """The mask (bit e % 64 for element e, as in ``reactive``) of the elements in columns x0..x1-1 of rows y0..y1-1."""
    present = np.int64(0)
    for y in range(y0, y1):
        for x in range(x0, x1):
            present |= _bit(cells[_at(y, x)])
    return present


@njit(cache=True)
def step_region(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, fast):
    """Update the awake cells of rows y0..y1-1 and columns x0..x1-1 (moves may leave the region).

    A row of a chunk is updated when the chunk's mark in ``awake`` (from last
    frame) or ``woken`` (by a change nearby earlier this frame) covers it (see
    :data:`sandmod.world.world.WHOLE`). Every change, and every chance that did not
    come up, widens the ``woken`` marks to the rows within two cells of where
    it happened, and where an element or a heat changed, other than
    by two cells of one temperature trading places, in ``stirred`` too (see
    :func:`conduct`): once per row of a chunk, for a box around that row's
    changes. Explosives that go off are marked DETONATING and
    counted in ``detonations[tile]``, for :func:`take_detonations` after the step.

    ``present`` masks the elements that may be next to a cell being updated:
    those in the rows next to it (across the region and a cell past it) before
    the first update of the row, each element that a cell turns into since,
    and ``also_present`` (-1 in tests: all). Moves bring in nothing new: a mover
    trades places with a cell next to it, or with an empty one past an empty
    one next to it. A cell whose partners, or whose fluid moves' elements, are
    not in the mask skips looking at its neighbours for them (in a world of
    sand and water, every cell does).

    With ``fast`` (a literal: each value is compiled on its own), the cells
    are taken first by a loop of their own that keeps few values, so that
    they stay in registers: cells that stay put (a resting fluid that nothing
    it could displace is next to, a resting grain, a static cell) and a
    straight fall into a fluid below that knocks nothing loose. Each cell
    that needs more gets the full update, which the fast loop then resumes
    after: the same frames either way, but each cell handed on costs the
    full update's values reloaded. Returns how well the fast loop did: the
    cells of the rows updated, less HANDED_ON_COST for each one it handed on
    (above zero: it paid); without ``fast``, 0.
    """
    cells, shade, timer, flags, vx, vy, carry, heat = s.cells, s.shade, s.timer, s.flags, s.vx, s.vy, s.carry, s.heat
    height, width = cells.shape
    archetype, fall_dir, accel, max_speed = t.archetype, t.fall_dir, t.accel, t.max_speed
    friction, impact_share, knock_chance, drag_keep = t.friction, t.impact_share, t.knock_chance, t.drag_keep
    dispersion, rest_chance = t.dispersion, t.rest_chance
    life_frames, life_jitter, life_into = t.life_frames, t.life_jitter, t.life_into
    reactive, displace, displaces = t.reactive, t.displace, t.displaces
    react_chance, react_into_a, react_into_b = t.react_chance, t.react_into_a, t.react_into_b
    react_tsum_min, react_tsum_max, react_heat = t.react_tsum_min, t.react_tsum_max, t.react_heat
    heat_cap, heat_recip, temp_start, thermal, cooling = t.heat_cap, t.heat_recip, t.temp_start, t.thermal, t.cooling
    hot_limit, heated_into, cold_limit, cooled_into = t.hot_limit, t.heated_into, t.cold_limit, t.cooled_into
    ignite_limit, catch_chance, burn_frames, burn_jitter = t.ignite_limit, t.catch_chance, t.burn_frames, t.burn_jitter
    burn_limit, burn_heat, flame, flame_chance = t.burn_limit, t.burn_heat, t.flame, t.flame_chance
    ash, ash_chance, extinguishes = t.ash, t.ash_chance, t.extinguishes
    ambient = int(t.temp_start[0])  # the air's temperature is the world's outside
    knock_key = _mix32(move_key ^ SALT_KNOCK)
    fire_key = _mix32(move_key ^ SALT_FIRE)
    exchange_key = _mix32(move_key ^ SALT_EXCHANGE)
    first_cx = x0 >> CHUNK_SHIFT
    segments = ((x1 - 1) >> CHUNK_SHIFT) - first_cx + 1
    present = also_present
    numba.literally(fast)  # two versions, compiled apart: with and without the fast loop
    visited = 0  # cells of the rows updated, and how many of them the fast loop handed on to the full update
    handed_on = 0
    far = height * width > CACHED_CELLS  # prefetch rows ahead (see below)
    unseen = y1 + 1  # rows from here up are not in `present` yet (rows from here down to the next row to update are)

    for y in range(y1 - 1, y0 - 1, -1):
        cy = y >> CHUNK_SHIFT
        forward = ((frame + y) & 1) == 0
        for j in range(segments):
            cx = first_cx + (j if forward else segments - 1 - j)
            row = y - (cy << CHUNK_SHIFT)
            if not (_covers(awake[_at(cy, cx)], row) or _covers(np.int64(woken[_mark(cy, cx)]), row)):
                continue  # asleep: nothing in this row of the chunk or within two cells of it changed
            if unseen > y - 1:  # the elements of the rows next to this one, across the region and one cell past it
                present |= _elements_in(cells, max(x0 - 1, 0), max(y - 1, 0), min(x1 + 1, width), min(unseen, y + 2, height))
                unseen = max(y - 1, 0)
            sx0 = max(x0, cx << CHUNK_SHIFT)
            sx1 = min(x1, (cx + 1) << CHUNK_SHIFT)
            if far:  # ask for the row two above (at the region's first row, the one above too) while this one is updated:
                # the lines at the segment's two ends in each array, and heat's (four bytes a cell) between
                for ahead in range(max(y - 2, 0), y if y == y1 - 1 else y - 1):
                    for ax in range(sx0 + LINE_CELLS, sx1 - 1, LINE_CELLS):
                        prefetch(heat, ahead, ax)
                    for ax in (sx0, sx1 - 1):
                        prefetch(cells, ahead, ax)
                        prefetch(flags, ahead, ax)
                        prefetch(heat, ahead, ax)
                        prefetch(vx, ahead, ax)
                        prefetch(vy, ahead, ax)
                        prefetch(shade, ahead, ax)
                        prefetch(timer, ahead, ax)
            # The cells the segment's updates changed (or may change later), and those that stirred, as two
            # boxes: woken once, at the segment's end. A box may take in cells no single update did: more
            # waking and stirring, which changes nothing but the work.
            busy_x0, busy_x1, busy_y0, busy_y1 = sx1, sx0 - 1, y, y
            stir_x0, stir_x1, stir_y0, stir_y1 = sx1, sx0 - 1, y, y
            count = sx1 - sx0
            visited += count
            resume = 0  # the fast loop has done the cells before this one
            for i in range(count):
                if fast:
                    # The common cases first, in a loop of their own that holds few values (registers, not the
                    # stack): cells at rest that nothing around them can move, and a straight fall into a fluid.
                    # The first cell that needs more gets the full update below; the loop goes on after it.
                    if i < resume:
                        continue
                    n = i
                    while n < count:
                        x = sx0 + n if forward else sx1 - 1 - n
                        e = cells[_at(y, x)]
                        f = flags[_at(y, x)]
                        if e == 0 or (f & MOVED) != 0:
                            n += 1
                            continue
                        ready = False  # moving, or not calm, or a lifetime, or a partner near: the full update
                        if vx[_at(y, x)] != 0 or vy[_at(y, x)] != 0 or (f & BURNING) != 0 or life_frames[e] != 0 or (reactive[e] & present) != 0:
                            break
                        th = thermal[e]
                        if th != 0 and ((th & (FLAMMABLE | IGNITES)) != 0 or not (cold_limit[e] <= heat[_at(y, x)] <= hot_limit[e])):
                            break
                        ready = True  # only the move is left to decide
                        kind = archetype[e]
                        if kind == LIQUID or kind == GAS:
                            if (displaces[e] & present) != 0:
                                g = fall_dir[e]
                                near = 0
                                for k in range(5):
                                    nx, ny = _fluid_move_cell(x, y, g, k)
                                    if _inside(nx, ny, width, height):
                                        near |= _bit(cells[_at(ny, nx)])
                                if (displaces[e] & near) != 0:
                                    break  # it may displace something next to it
                            n += 1  # at rest, with nothing it could displace where it could go: stays put
                            continue
                        if kind == STATIC:
                            n += 1
                            continue
                        if kind != POWDER:
                            break  # a particle
                        g = fall_dir[e]
                        ty = y + g
                        below = 0
                        opens = False
                        if _within(ty, height):
                            below = cells[_at(ty, x)]
                            opens = _enterable(displace[e, below], below, flags[_at(ty, x)])
                        if not opens:
                            if (f & LOOSE) != 0:
                                break  # on the ground, and loose: it may roll or slide
                            n += 1  # at rest on the ground: stays put
                            continue
                        if below == 0 or ty >= y1 or not (0 < x and x + 1 < width and 0 < y):
                            break  # falling through empty cells, into another tile's cells, or at the world's edge
                        threshold = displace[e, below]
                        if threshold != ALWAYS and (_cell_key(exchange_key, x, y) >> 24) >= threshold:
                            busy_x0, busy_x1 = min(busy_x0, x), max(busy_x1, x)  # it waits for its chance to sink
                            n += 1
                            continue
                        if (flags[_at(y, x - 1)] & flags[_at(y, x + 1)] & flags[_at(y - 1, x - 1)] & flags[_at(y - 1, x + 1)] & flags[_at(ty, x - 1)] & flags[_at(ty, x + 1)] & LOOSE) == 0:
                            break  # it may knock a resting grain loose
                        # Straight into a fluid: one cell, its speed lost, nothing knocked.
                        stirs = _stirs(int(heat[_at(y, x)]), heat_cap[e], cooling[e], int(heat[_at(ty, x)]), heat_cap[below], cooling[below], ambient)
                        cells[_at(y, x)] = below
                        cells[_at(ty, x)] = e
                        shade[_at(y, x)], shade[_at(ty, x)] = shade[_at(ty, x)], shade[_at(y, x)]
                        timer[_at(y, x)], timer[_at(ty, x)] = timer[_at(ty, x)], timer[_at(y, x)]
                        heat[_at(y, x)], heat[_at(ty, x)] = heat[_at(ty, x)], heat[_at(y, x)]
                        vx[_at(y, x)] = vx[_at(ty, x)]
                        vy[_at(y, x)] = vy[_at(ty, x)]
                        flags[_at(y, x)] = MOVED | (flags[_at(ty, x)] & CARRIED)
                        vx[_at(ty, x)] = 0
                        vy[_at(ty, x)] = 0
                        flags[_at(ty, x)] = MOVED | LOOSE | (f & (CARRIED & ~LOOSE))
                        lo, hi = min(y, ty), max(y, ty)
                        busy_x0, busy_x1 = min(busy_x0, x), max(busy_x1, x)
                        busy_y0, busy_y1 = min(busy_y0, lo), max(busy_y1, hi)
                        if stirs:
                            stir_x0, stir_x1 = min(stir_x0, x), max(stir_x1, x)
                            stir_y0, stir_y1 = min(stir_y0, lo), max(stir_y1, hi)
                        n += 1
                    if n == count:
                        break
                    resume = n + 1
                    handed_on += 1
                else:
                    x = sx0 + i if forward else sx1 - 1 - i
                    e = cells[_at(y, x)]
                    if e == 0 or (flags[_at(y, x)] & MOVED) != 0:
                        continue  # its turn is over: it moved, or changed
                    ready = False
                busy = False  # did anything change, or might it on a later frame?
                stir = False  # did an element or a heat change (besides even swaps)?
                bx0 = bx1 = x  # the cells it moved between
                by0 = by1 = y
                for _ in range(1):  # one pass; `break` ends the cell's update
                    if not ready:  # steps 1 to 3 have work to do (the fast loop found so)
                        # 1. Heat and fire: phase changes, catching fire, burning, lighting neighbours.
                        f = flags[_at(y, x)]
                        th = thermal[e]
                        # Calm (the common case): not burning, no flame, its heat between its phase changes.
                        calm = (f & BURNING) == 0 and (
                            th == 0 or ((th & (FLAMMABLE | IGNITES)) == 0 and cold_limit[e] <= heat[_at(y, x)] <= hot_limit[e])
                        )
                        if not calm:
                            energy = int(heat[_at(y, x)])
                            into = e
                            if energy > hot_limit[e]:
                                into = heated_into[e]
                            elif energy < cold_limit[e]:
                                into = cooled_into[e]
                            elif (th & FLAMMABLE) != 0 and (f & BURNING) == 0 and energy >= ignite_limit[e]:
                                f |= BURNING
                                timer[_at(y, x)] = burn_frames[e] + (_cell_key(fire_key, x, y) >> 8) % (burn_jitter[e] + 1)
                            lit = into == e and ((f & BURNING) != 0 or (th & IGNITES) != 0)
                            fh = _cell_key(fire_key ^ 0x5BD1E995, x, y) if lit else 0  # rolls for fire, only where there is fire
                            if into == e and (f & BURNING) != 0:
                                busy = True
                                if (th & EXPLOSIVE) != 0:
                                    # It goes off: frozen for the rest of the frame, then the step's blasts are applied.
                                    flags[_at(y, x)] = f | DETONATING | DONE
                                    detonations[tile] += 1
                                    break
                                else:
                                    out = False
                                    for k in range(4):
                                        nx = x + (1, 0, -1, 0)[k]
                                        ny = y + (0, 1, 0, -1)[k]
                                        if _inside(nx, ny, width, height) and extinguishes[cells[_at(ny, nx)]] != 0:
                                            out = True
                                    if out:  # put out, and cooled to just below catching fire again
                                        f &= ~BURNING
                                        energy = min(energy, ignite_limit[e] - heat_cap[e] * TEMP_ONE)
                                    else:
                                        if energy < burn_limit[e]:
                                            energy = min(energy + burn_heat[e], burn_limit[e])
                                        left = timer[_at(y, x)]
                                        if left <= 1:  # burnt out
                                            into = ash[e] if ((fh >> 8) & 0xFFFFFF) < ash_chance[e] else 0
                                        else:
                                            timer[_at(y, x)] = left - 1
                                            d = fh & 3
                                            nx = x + (1, 0, -1, 0)[d]
                                            ny = y + (0, 1, 0, -1)[d]
                                            product = flame[e]
                                            if product != 0 and _inside(nx, ny, width, height) and cells[_at(ny, nx)] == 0:
                                                if (_cell_key(fire_key ^ 0x68E31DA4, x, y) >> 8) < flame_chance[e]:
                                                    cells[_at(ny, nx)] = product
                                                    present |= _bit(product)
                                                    stir = True
                                                    shade[_at(ny, nx)], timer[_at(ny, nx)] = _spawn_state(
                                                        _cell_key(spawn_key, nx, ny), life_frames[product], life_jitter[product]
                                                    )
                                                    vx[_at(ny, nx)] = vy[_at(ny, nx)] = carry[_at(ny, nx)] = 0
                                                    heat[_at(ny, nx)] = _energy(temp_start[product], heat_cap[product])
                                                    flags[_at(ny, nx)] = MOVED | LOOSE
                            if into == e and ((f & BURNING) != 0 or (th & IGNITES) != 0):
                                # A flame lights the flammable cells it touches, each by its own chance.
                                for k in range(4):
                                    nx = x + (1, 0, -1, 0)[k]
                                    ny = y + (0, 1, 0, -1)[k]
                                    if not _inside(nx, ny, width, height):
                                        continue
                                    n = cells[_at(ny, nx)]
                                    if (thermal[n] & FLAMMABLE) != 0 and (flags[_at(ny, nx)] & BURNING) == 0:
                                        busy = True  # lit now, or maybe on a later frame
                                        if (_mix32(fh ^ (k + 1) * 0x9E3779B9) >> 8) < catch_chance[n]:
                                            flags[_at(ny, nx)] |= BURNING
                                            timer[_at(ny, nx)] = burn_frames[n] + (_cell_key(fire_key, nx, ny) >> 8) % (burn_jitter[n] + 1)
                            if into != e:
                                busy = stir = True
                                cells[_at(y, x)] = into
                                present |= _bit(into)
                                shade[_at(y, x)], timer[_at(y, x)] = _spawn_state(_cell_key(spawn_key, x, y), life_frames[into], life_jitter[into])
                                vx[_at(y, x)] = vy[_at(y, x)] = carry[_at(y, x)] = 0
                                heat[_at(y, x)] = _energy(_temperature(energy, heat_recip[e]), heat_cap[into])
                                flags[_at(y, x)] = (f & FRESH) | MOVED
                                break
                            if energy != heat[_at(y, x)]:
                                heat[_at(y, x)] = energy
                                busy = stir = True
                            if f != flags[_at(y, x)]:
                                flags[_at(y, x)] = f
                                busy = True

                        # 2. Lifetime: count down, and at zero become another element (not while burning).
                        if life_frames[e] != 0 and (f & BURNING) == 0:
                            busy = True
                            left = timer[_at(y, x)]
                            if left <= 1:
                                into = life_into[e]
                                cells[_at(y, x)] = into
                                present |= _bit(into)
                                stir = True
                                shade[_at(y, x)], timer[_at(y, x)] = _spawn_state(_cell_key(spawn_key, x, y), life_frames[into], life_jitter[into])
                                vx[_at(y, x)] = vy[_at(y, x)] = carry[_at(y, x)] = 0
                                heat[_at(y, x)] = _energy(_temperature(int(heat[_at(y, x)]), heat_recip[e]), heat_cap[into])
                                flags[_at(y, x)] = (flags[_at(y, x)] & FRESH) | MOVED
                                break
                            timer[_at(y, x)] = left - 1

                        # 3. Reactions: try each touching neighbour once, in a hashed order. First a cheap
                        # test: does any neighbour's bit show in the element's partner mask?
                        partners = reactive[e] & present
                        if partners != 0 and (flags[_at(y, x)] & REACTED) != 0:
                            partners = 0  # once a frame
                        if partners != 0:
                            near = 0
                            if x + 1 < width:
                                near |= _bit(cells[_at(y, x + 1)])
                            if y + 1 < height:
                                near |= _bit(cells[_at(y + 1, x)])
                            if x > 0:
                                near |= _bit(cells[_at(y, x - 1)])
                            if y > 0:
                                near |= _bit(cells[_at(y - 1, x)])
                            partners &= near
                        if partners != 0:
                            reacted = False
                            start = (_cell_key(move_key, x, y) >> 1) & 3
                            for k in range(4):
                                d = (start + k) & 3
                                nx = x + (1, 0, -1, 0)[d]
                                ny = y + (0, 1, 0, -1)[d]
                                if not _inside(nx, ny, width, height) or (flags[_at(ny, nx)] & REACTED) != 0:
                                    continue
                                b = cells[_at(ny, nx)]
                                threshold = react_chance[e, b]
                                if threshold == 0:
                                    continue
                                # One roll per touching pair and frame, the same whichever cell looks.
                                roll = _mix32(react_key ^ ((min(y, ny) << 16) | min(x, nx)) ^ ((d & 1) << 31)) >> 8
                                ta = _temperature(int(heat[_at(y, x)]), heat_recip[e])
                                tb = _temperature(int(heat[_at(ny, nx)]), heat_recip[b])
                                if ta + tb < react_tsum_min[e, b] or ta + tb > react_tsum_max[e, b]:
                                    continue
                                busy = True  # it reacts now, or may on a later frame
                                if roll >= threshold:
                                    continue
                                into_a = react_into_a[e, b]
                                into_b = react_into_b[e, b]
                                warm = react_heat[e, b]
                                if into_a != e:
                                    cells[_at(y, x)] = into_a
                                    present |= _bit(into_a)
                                    stir = True
                                    shade[_at(y, x)], timer[_at(y, x)] = _spawn_state(_cell_key(spawn_key, x, y), life_frames[into_a], life_jitter[into_a])
                                    vx[_at(y, x)] = vy[_at(y, x)] = carry[_at(y, x)] = 0
                                    heat[_at(y, x)] = _energy(ta + warm, heat_cap[into_a])
                                    flags[_at(y, x)] = (flags[_at(y, x)] & FRESH) | MOVED
                                if into_b != b:
                                    cells[_at(ny, nx)] = into_b
                                    present |= _bit(into_b)
                                    stir = True
                                    shade[_at(ny, nx)], timer[_at(ny, nx)] = _spawn_state(_cell_key(spawn_key, nx, ny), life_frames[into_b], life_jitter[into_b])
                                    vx[_at(ny, nx)] = vy[_at(ny, nx)] = carry[_at(ny, nx)] = 0
                                    heat[_at(ny, nx)] = _energy(tb + warm, heat_cap[into_b])
                                    flags[_at(ny, nx)] = (flags[_at(ny, nx)] & FRESH) | MOVED
                                flags[_at(y, x)] |= REACTED
                                flags[_at(ny, nx)] |= REACTED
                                reacted = into_a != e
                                break
                            if reacted:
                                break  # it became another element; one the reaction left as it was goes on to move

                    # 4. Movement: choose up to four moves to try in order, then walk them.
                    kind = archetype[e]
                    if kind == STATIC:
                        break
                    old_vx = int(vx[_at(y, x)])
                    old_vy = int(vy[_at(y, x)])
                    g = fall_dir[e]
                    ty = y + g  # the cell it falls (rises) into
                    fluid = kind == LIQUID or kind == GAS
                    if fluid and old_vx == 0 and old_vy == 0:
                        # At rest, first a cheap test of its five moves' cells (on, down a side, sideways):
                        # holds none an element it may displace? Then it stays put, as most of a body of liquid does.
                        if (displaces[e] & present) == 0:
                            break  # none is even near
                        near = 0
                        for k in range(5):
                            nx, ny = _fluid_move_cell(x, y, g, k)
                            if _inside(nx, ny, width, height):
                                near |= _bit(cells[_at(ny, nx)])
                        if (displaces[e] & near) == 0:
                            break
                    opens = False
                    free_air = kind != GAS  # it moves into empty cells without a roll (see compiler's exchange_chance)
                    if kind != PARTICLE and _within(ty, height):
                        o = cells[_at(ty, x)]
                        threshold = displace[e, o]
                        opens = o == 0 and free_air  # the commonest case, decided at once
                        if not opens and threshold != 0:
                            way = _way_into(
                                kind, threshold, o, archetype[o], flags[_at(ty, x)], heat[_at(ty, x)], thermal[o], life_frames[o], cold_limit[o],
                                hot_limit[o], ignite_limit[o], False, old_vy != 0, exchange_key, x, y, x, ty, forward, x0, y0, x1, y1, frame,
                            )
                            opens = way == OPEN
                            if way == WAIT:
                                busy = True
                                if kind == POWDER:
                                    break  # a grain waits for its chance to sink (fluids flow aside meanwhile)
                    can_flow = False  # liquids and gases on the ground: is the first cell of any of their moves open?
                    if fluid and not opens and (displaces[e] & present) != 0:
                        for k in range(1, 5):  # the same cells as above, less the one below
                            nx, ny = _fluid_move_cell(x, y, g, k)
                            if _inside(nx, ny, width, height):
                                if _enterable(displace[e, cells[_at(ny, nx)]], cells[_at(ny, nx)], flags[_at(ny, nx)]):
                                    can_flow = True
                                    break
                        if not can_flow and old_vx == 0 and old_vy == 0:
                            break  # at rest, every move shut (by cells done this frame)
                    # Straight into a fluid below: one cell, where its speed is lost anyway; no rolls needed.
                    straight = opens and old_vx == 0 and cells[_at(ty, x)] != 0
                    h = 0 if straight else _cell_key(move_key, x, y)
                    cvx = old_vx
                    cvy = old_vy
                    loose = flags[_at(y, x)] & LOOSE
                    falling = False
                    coasting = False
                    only_empty = kind == PARTICLE
                    tries = 0
                    d0x = d0y = d1x = d1y = d2x = d2y = d3x = d3y = 0
                    if kind == PARTICLE:
                        busy = True  # in flight until it lands
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
                        if straight:
                            falling = True
                            loose = LOOSE
                            d0y = g
                        elif opens:
                            # Falling (rising): speed up, go at least one cell, drift sideways.
                            falling = True
                            r = _mix32(h ^ SALT_ROUND)
                            speed = min(cvy * g + accel[e], max_speed[e])
                            cvy = speed * g
                            d0x = _cells_moved(cvx, (r >> 8) & 255)
                            if kind == GAS and (r & 0x10000) != 0:
                                d0x += 1 if (r & 0x20000) != 0 else -1  # gas wavers as it rises: a plume, not a line
                            d0y = g * max(1, _cells_moved(speed, r & 255))
                            d1y = g  # if the drift is blocked: straight on, one cell
                            tries = 2
                            loose = LOOSE
                        elif g > 0 and cvy > 0 and _within(ty, height) and vy[_at(ty, x)] > 0 and archetype[cells[_at(ty, x)]] != STATIC and (flags[_at(ty, x)] & DONE) == 0:
                            busy = True  # the cell below falls too and has not had its turn (another tile's): wait for it
                            break
                        elif kind == POWDER:
                            if loose == 0:
                                break  # resting: stays put until the cell below opens or it is knocked
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
                            if can_flow and kind == LIQUID and (h >> 8) < rest_chance[e]:
                                busy = True  # viscous liquids often rest; stay awake while it could flow
                            elif can_flow:
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
                    if falling and d0x == 0 and d0y == g:  # one cell straight on, into the cell found open above
                        py = ty
                        used = 0
                        tries = 0
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
                                    way = _way_into(
                                        kind, threshold, o, archetype[o], flags[_at(qy, qx)], heat[_at(qy, qx)], thermal[o], life_frames[o], cold_limit[o],
                                        hot_limit[o], ignite_limit[o], qy == y, old_vy != 0, exchange_key, x, y, qx, qy, forward, x0, y0, x1, y1, frame,
                                    )
                                    if way != OPEN:
                                        busy = busy or way == WAIT
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

                    # Settle the new velocity.
                    entered = cells[_at(py, px)]  # what the mover swaps with (0 when it goes into empty)
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
                            vx[_at(y, x)] = cvx
                            vy[_at(y, x)] = cvy
                            busy = True
                        if kind == POWDER and (flags[_at(y, x)] & LOOSE) != loose:
                            flags[_at(y, x)] ^= LOOSE
                            busy = True
                        busy = busy or (kind == POWDER and loose != 0)  # a loose grain is still in motion
                        break

                    busy = True
                    bx0 = min(x, px)
                    bx1 = max(x, px)
                    by0 = min(y, py)
                    by1 = max(y, py)

                    # Move: swap everything with the cell at the end of the walk.
                    marks = flags[_at(y, x)] & (CARRIED & ~LOOSE)  # what travels with the mover besides LOOSE
                    if px != x or py != y:
                        # Heat stays even where two cells of one temperature trade places and neither cools.
                        stir = stir or _stirs(int(heat[_at(y, x)]), heat_cap[e], cooling[e], int(heat[_at(py, px)]), heat_cap[entered], cooling[entered], ambient)
                        cells[_at(y, x)] = entered
                        cells[_at(py, px)] = e
                        shade[_at(y, x)], shade[_at(py, px)] = shade[_at(py, px)], shade[_at(y, x)]
                        timer[_at(y, x)], timer[_at(py, px)] = timer[_at(py, px)], timer[_at(y, x)]
                        if kind == PARTICLE:  # only particles carry anything, and they only enter empty cells
                            carry[_at(y, x)], carry[_at(py, px)] = carry[_at(py, px)], carry[_at(y, x)]
                        heat[_at(y, x)], heat[_at(py, px)] = heat[_at(py, px)], heat[_at(y, x)]
                        vx[_at(y, x)] = vx[_at(py, px)]
                        vy[_at(y, x)] = vy[_at(py, px)]
                        # Traded up or down, it is done for the frame; traded sideways, a mover above or below may still take its place.
                        flags[_at(y, x)] = (MOVED if py != y or entered == 0 else 0) | (flags[_at(py, px)] & CARRIED)
                    vx[_at(py, px)] = cvx
                    vy[_at(py, px)] = cvy
                    flags[_at(py, px)] = MOVED | loose | marks

                    if kind == PARTICLE:
                        if loose != 0:  # landed: put down what it carries (or vanish), at the particle's temperature
                            into = carry[_at(py, px)]
                            cells[_at(py, px)] = into
                            present |= _bit(into)
                            stir = True
                            carry[_at(py, px)] = 0
                            heat[_at(py, px)] = _energy(_temperature(int(heat[_at(py, px)]), heat_recip[e]), heat_cap[into])
                            if into == 0:
                                vx[_at(py, px)] = vy[_at(py, px)] = 0
                            elif life_frames[e] != 0:  # the particle's own clock ran: start the cargo's
                                _, timer[_at(py, px)] = _spawn_state(_cell_key(spawn_key, px, py), life_frames[into], life_jitter[into])
                        break

                    # A move knocks resting grains loose: those that could follow into the
                    # vacated cell (pushed towards it) and those beside the arrival (pushed away).
                    if not (
                        x > 0
                        and y > 0
                        and px > 0
                        and x + 1 < width
                        and px + 1 < width
                        and (
                            flags[_at(y, x - 1)]
                            & flags[_at(y, x + 1)]
                            & flags[_at(y - 1, x - 1)]
                            & flags[_at(y - 1, x + 1)]
                            & flags[_at(py, px - 1)]
                            & flags[_at(py, px + 1)]
                            & LOOSE
                        )
                        != 0
                    ):  # unless all six are in motion already (the common case)
                        for k in range(6):
                            if k < 4:
                                nx = x + (-1, 1, -1, 1)[k]
                                ny = y - (0, 0, 1, 1)[k]
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
                            if knock_chance[c] != 0:  # only powders have a chance
                                if (_cell_key(knock_key, nx, ny) >> 8) < knock_chance[c]:
                                    flags[_at(ny, nx)] |= LOOSE
                                    vx[_at(ny, nx)] = push * KNOCK_SPEED

                if busy:  # the cells it moved between go in the segment's boxes
                    busy_x0, busy_x1 = min(busy_x0, bx0), max(busy_x1, bx1)
                    busy_y0, busy_y1 = min(busy_y0, by0), max(busy_y1, by1)
                    if stir:
                        stir_x0, stir_x1 = min(stir_x0, bx0), max(stir_x1, bx1)
                        stir_y0, stir_y1 = min(stir_y0, by0), max(stir_y1, by1)
            if busy_x0 <= busy_x1:  # wake every cell within two cells of the box
                wx0, wy0, wx1, wy1 = _grown(busy_x0, busy_y0, busy_x1, busy_y1, width, height)
                _wake(woken, stirred, False, wx0, wy0, wx1, wy1)
            if stir_x0 <= stir_x1:  # and stir the chunks of the cells within two cells of the other
                wx0, wy0, wx1, wy1 = _grown(stir_x0, stir_y0, stir_x1, stir_y1, width, height)
                _wake(woken, stirred, True, wx0, wy0, wx1, wy1)
    return visited - HANDED_ON_COST * handed_on if fast else 0


@njit(cache=True)
def conduct(s, t, frame, awake, woken, even, stirred, x0, y0, x1, y1):
    """Heat flows between touching cells of the awake chunks among rows y0..y1-1 and
    columns x0..x1-1 (and the row below and column right of them), and cells with
    ``cooling`` lose heat to the outside.

    Each touching pair exchanges ``g * (T_a - T_b)`` of energy, where ``g`` is
    the smaller of the two cells' conductance (conductivity x capacity / 4),
    rounded towards zero. One side's temperature then moves by at most a
    quarter of the gap, so the two never swap places and no cell overshoots:
    the scheme is stable for any conductivities. What one cell loses the other
    gains, so conduction alone conserves the total exactly. The sweep runs
    forwards on even frames and backwards on odd ones, so heat has no
    favourite direction. A cell whose heat changes wakes the chunks around it.

    Even heat is skipped. A chunk is marked ``even`` (EVEN) when a whole sweep of
    it (marked SWEPT meanwhile) finds every pair it looks at (right and down,
    any conductance) at exactly one temperature and no cell cooling. Until a change has ``stirred``
    it (see :func:`step_region`; :func:`step` clears the marks of stirred
    chunks), a sweep there would change nothing, so it is left out.
    """
    cells, heat = s.cells, s.heat
    height, width = cells.shape
    heat_cap, heat_recip, conductance, cooling = t.heat_cap, t.heat_recip, t.conductance, t.cooling
    ambient = int(t.temp_start[0])  # the air's temperature is the world's outside
    backwards = (frame & 1) == 1
    far = height * width > CACHED_CELLS  # prefetch the next row (see step_region)
    first_cx = x0 >> CHUNK_SHIFT
    segments = ((x1 - 1) >> CHUNK_SHIFT) - first_cx + 1
    first_cy, end_cy = y0 >> CHUNK_SHIFT, ((y1 - 1) >> CHUNK_SHIFT) + 1
    for cy in range(first_cy, end_cy):
        for cx in range(first_cx, first_cx + segments):
            if (awake[_at(cy, cx)] != 0 or woken[_mark(cy, cx)] != 0) and (even[_at(cy, cx)] != EVEN or stirred[_mark(cy, cx)] != 0):
                even[_at(cy, cx)] = SWEPT  # swept whole: even, unless a pair at two temperatures or a cooling cell stirs it
    for r in range(y1 - y0):
        y = y1 - 1 - r if backwards else y0 + r
        cy = y >> CHUNK_SHIFT
        for j in range(segments):
            cx = first_cx + (segments - 1 - j if backwards else j)
            if awake[_at(cy, cx)] == 0 and woken[_mark(cy, cx)] == 0:
                continue
            if even[_at(cy, cx)] == EVEN and stirred[_mark(cy, cx)] == 0:
                continue  # one temperature throughout, as its last sweep found
            uneven = False
            sx0 = max(x0, cx << CHUNK_SHIFT)
            sx1 = min(x1, (cx + 1) << CHUNK_SHIFT)
            changed_x0, changed_x1 = sx1, sx0 - 1  # the first and last cell of the segment whose heat changed
            ahead = y - 1 if backwards else y + 2  # the row the sweep reads next
            if far and _within(ahead, height):
                for ax in range(sx0, sx1, LINE_CELLS):
                    prefetch(cells, ahead, ax)
                    prefetch(heat, ahead, ax)
            for i in range(sx1 - sx0):
                x = sx1 - 1 - i if backwards else sx0 + i
                e = cells[_at(y, x)]
                energy = int(heat[_at(y, x)])
                changed = False
                loss = _cooling_loss(energy, heat_cap[e], cooling[e], ambient)
                if loss != 0:
                    energy += loss
                    heat[_at(y, x)] = energy
                    changed = True
                g_own = conductance[e]
                for k in range(2):
                    nx = x + 1 - k
                    ny = y + k
                    if nx >= width or ny >= height:
                        continue
                    n = cells[_at(ny, nx)]
                    other = int(heat[_at(ny, nx)])
                    if other * heat_cap[e] == energy * heat_cap[n]:
                        continue  # the common case: the same temperature (E_a / C_a == E_b / C_b)
                    uneven = True
                    g = min(g_own, conductance[n])
                    if g == 0:
                        continue
                    gap = _temperature(energy, heat_recip[e]) - _temperature(other, heat_recip[n])
                    flow = _scaled(gap * g, 1)
                    if flow != 0:
                        energy -= flow
                        heat[_at(y, x)] = energy
                        heat[_at(ny, nx)] = other + flow
                        changed = True
                if changed:
                    changed_x0 = min(changed_x0, x)
                    changed_x1 = max(changed_x1, x)
            if changed_x0 <= changed_x1:  # wake (and stir) the cells next to them and to their partners
                _wake(woken, stirred, True, max(changed_x0 - 1, 0), max(y - 1, 0), min(changed_x1 + 2, width - 1), min(y + 2, height - 1))
            if uneven:
                stirred[_mark(cy, cx)] = 1
    for cy in range(first_cy, end_cy):
        for cx in range(first_cx, first_cx + segments):
            if even[_at(cy, cx)] == SWEPT:
                even[_at(cy, cx)] = EVEN


@njit(cache=True)
def clear_marks(flags, awake):
    """Forget last frame's moved and reacted marks, in the awake chunks (no others have any)."""
    height, width = flags.shape
    chunks_y, chunks_x = awake.shape
    for cy in range(chunks_y):
        for y in range(cy << CHUNK_SHIFT, min((cy + 1) << CHUNK_SHIFT, height)):
            row = flags[y]
            for cx in range(chunks_x):
                if awake[cy, cx] != 0:
                    run = row[cx << CHUNK_SHIFT : min((cx + 1) << CHUNK_SHIFT, width)]
                    run &= np.uint8(KEPT)  # a whole-slice operation: numba vectorises it, a loop it did not


@njit(cache=True)  # called, not inlined: inlined in the serial step it ran 3 to 7% slower (bench --against)
def _update_tile(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tile, also_present, fast_gain, route):
    """Heat, then cells, in tile number ``tile`` (row-major), with or without :func:`step_region`'s fast loop (see :func:`step`)."""
    height, width = s.cells.shape
    tiles_x = (width + TILE - 1) >> TILE_SHIFT
    x0 = (tile % tiles_x) << TILE_SHIFT
    y0 = (tile // tiles_x) << TILE_SHIFT
    x1 = min(x0 + TILE, width)
    y1 = min(y0 + TILE, height)
    conduct(s, t, frame, awake, woken, even, stirred, x0, y0, x1, y1)
    if route > 0 or (route == 0 and (fast_gain[tile] > 0 or ((frame + tile) & (FAST_TRIAL - 1)) == 0)):
        fast_gain[tile] = step_region(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, True)
    else:
        step_region(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, False)


@njit(cache=True, parallel=True)
def update_tiles_at_once(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tiles, count, also_present, fast_gain, route):
    """Update the first ``count`` tiles of ``tiles`` (tile numbers, row-major) on the threads numba
    has, one tile per thread at a time."""
    for k in prange(count):
        _update_tile(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tiles[k], also_present, fast_gain, route)


@njit(cache=True)
def _tiles_of_pass(awake, woken, frame, p, hands, todo, order):
    """The tiles of pass p (0..3) with an awake or woken chunk, into ``order``, dealt out like cards to
    ``hands`` threads (prange gives each thread one run of the list: each run then holds tiles from all
    over the world, not one crowded band of it); returns how many."""
    chunks_y, chunks_x = awake.shape
    tiles_y, tiles_x = (chunks_y + 1) >> 1, (chunks_x + 1) >> 1  # a tile is 2 x 2 chunks
    px, py = _pass_tiles(p, frame)
    count = 0
    for ty in range(py, tiles_y, 2):
        for tx in range(px, tiles_x, 2):
            running = False
            for cy in range(ty * 2, min(ty * 2 + 2, chunks_y)):
                for cx in range(tx * 2, min(tx * 2 + 2, chunks_x)):
                    running = running or awake[cy, cx] != 0 or woken[cy, cx, 0] != 0
            if running:
                todo[count] = ty * tiles_x + tx
                count += 1
    dealt = 0
    for hand in range(hands):
        for k in range(hand, count, hands):
            order[dealt] = todo[k]
            dealt += 1
    return count


@njit(inline="always", cache=True)  # it takes arrays: see _wake
def _step_passes(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route, at_once):
    """:func:`step`, its tiles updated by :func:`update_tiles_at_once` where ``at_once`` (a constant
    in each caller), else one after another here."""
    woken[:] = 0
    stirred[:] = 0
    detonations[:] = 0
    clear_marks(s.flags, awake)
    todo = np.empty(len(detonations), np.int64)
    order = np.empty_like(todo)
    for p in range(4):
        count = _tiles_of_pass(awake, woken, frame, p, hands, todo, order)
        if count == 0:
            continue
        if at_once:
            update_tiles_at_once(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, order, count, also_present, fast_gain, route)
        else:
            for k in range(count):
                _update_tile(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, order[k], also_present, fast_gain, route)
    chunks_y, chunks_x = awake.shape
    for cy in range(chunks_y):
        for cx in range(chunks_x):
            awake[cy, cx] = woken[cy, cx, 0]
            if stirred[cy, cx, 0] != 0:
                even[cy, cx] = 0
    return detonations.sum()


@njit(cache=True)
def step(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route):
    """Advance the world by one frame, on this thread; returns how many explosives went off (see :func:`take_detonations`).

    The world is cut into tiles of 2 x 2 chunks, updated in four passes by
    the parity of their column and row; the tiles of one pass are a tile apart,
    farther than anything one cell does can reach, so they may be updated at
    the same time on as many threads as there are (:func:`step_at_once`), with
    the same result as one after another. Within a tile, heat flows first, then
    the cells move. Only the rows of chunks that ``awake``'s marks name are
    touched; ``awake`` then holds the marks for the next frame. ``even`` marks
    chunks whose heat needs no sweep (see :func:`conduct`). ``hands``, the
    number of threads, only decides which thread takes which tile.
    ``also_present`` is 0, or -1 to look at the neighbours of every cell for
    partners (see :func:`step_region`): tests compare the two. ``fast_gain``
    holds, per tile, how well :func:`step_region`'s fast loop did the last
    time the tile took it: a tile takes it while it pays, and tries it again
    every FAST_TRIAL frames when it did not. ``route`` 1 sends every tile
    through the fast loop and -1 none (tests compare them); 0 chooses so.

    A function of its own, not an argument of one: so that a run on one
    thread never compiles numba's parallel code, nor starts its threads.
    """
    one = np.int64(1)  # not the literal 1: numba would compile what it is passed to a second time for it
    return _step_passes(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, one, also_present, fast_gain, route, False)


@njit(cache=True)
def step_at_once(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route):
    """:func:`step` on ``hands`` of numba's threads (numba's count set to it)."""
    return _step_passes(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route, True)


@njit(cache=True)
def paint_cells(s, ys, xs, element, cargo, vx, vy, only_empty, threshold, chance_key, spawn_key, life_frames, life_jitter, energy, awake, even):
    """:meth:`sandmod.world.world.World.paint_cells` for what is painted every frame: emitters and sprays.

    Each cell ``ys[i]``, ``xs[i]`` (an empty one, with ``only_empty``; a cell
    given twice counts once) whose roll under ``chance_key`` is below
    ``threshold`` becomes a newly born ``element`` carrying ``cargo``: a
    hashed shade and lifetime timer, holding ``energy``; at rest and LOOSE,
    or, where ``vx`` and ``vy`` are given (1/256ths of a cell a frame, one
    per cell; empty: none), in flight at that velocity. The chunks within
    WAKE_MARGIN of it wake, their heat no longer known to be even. Returns
    how many were painted.

    The cells come out as the numpy method's (which builds scenes without
    numba; tests compare the two), without its few dozen array operations a
    call: for a few emitters, most of a small world's frame.
    """
    cells, shade, timer, flags = s.cells, s.shade, s.timer, s.flags
    height, width = cells.shape
    moving = len(vx) > 0
    painted = 0
    for i in range(len(ys)):
        y, x = np.int64(ys[i]), np.int64(xs[i])
        if only_empty and cells[y, x] != 0:
            continue
        if (_cell_key(chance_key, x, y) >> (32 - ROLL_BITS)) >= threshold:
            continue
        shade[y, x], timer[y, x] = _spawn_state(_cell_key(spawn_key, x, y), life_frames, life_jitter)
        cells[y, x] = element
        s.carry[y, x] = cargo
        s.heat[y, x] = energy
        if moving:
            s.vx[y, x], s.vy[y, x], flags[y, x] = vx[i], vy[i], 0
        else:
            s.vx[y, x], s.vy[y, x], flags[y, x] = 0, 0, LOOSE
        for wy in (max(y - WAKE_MARGIN, 0) >> CHUNK_SHIFT, min(y + WAKE_MARGIN, height - 1) >> CHUNK_SHIFT):
            for wx in (max(x - WAKE_MARGIN, 0) >> CHUNK_SHIFT, min(x + WAKE_MARGIN, width - 1) >> CHUNK_SHIFT):
                awake[wy, wx] = WHOLE
                even[wy, wx] = 0
        painted += 1
    return painted


@njit(cache=True)
def take_detonations(s, t, detonations):
    """The blasts of the explosives that went off this step, top to bottom and left to right.

    Their cells are emptied (keeping their temperature); each blast then
    destroys its own centre.
    """
    cells, flags, heat = s.cells, s.flags, s.heat
    height, width = cells.shape
    tiles_y = (height + TILE - 1) >> TILE_SHIFT
    tiles_x = (width + TILE - 1) >> TILE_SHIFT
    rows = np.empty((detonations.sum(), BLAST_COLUMNS), np.int64)
    n = 0
    for ty in range(tiles_y):
        for y in range(ty << TILE_SHIFT, min((ty + 1) << TILE_SHIFT, height)):
            for tx in range(tiles_x):  # row by row across the tiles: the blasts come out in order
                if detonations[ty * tiles_x + tx] == 0:
                    continue
                for x in range(tx << TILE_SHIFT, min((tx + 1) << TILE_SHIFT, width)):
                    if (flags[y, x] & DETONATING) == 0:
                        continue
                    e = cells[y, x]
                    for c in range(BLAST_COLUMNS):  # not a slice: its shape check alone takes seconds to compile
                        rows[n, c] = t.blast[e, c]
                    rows[n, BLAST_X] = x
                    rows[n, BLAST_Y] = y
                    n += 1
                    heat[y, x] = _energy(_temperature(int(heat[y, x]), t.heat_recip[e]), t.heat_cap[0])
                    cells[y, x] = 0
                    flags[y, x] = MOVED
                    s.timer[y, x] = s.vx[y, x] = s.vy[y, x] = s.carry[y, x] = 0
    return rows


@njit(cache=True)
def explode(s, t, blasts, count, key, particle, awake, even):
    """Set off the first ``count`` explosions of ``blasts``, one after another.

    Each blast sends a ray from its centre to every cell on the border of the
    square of side 2 x radius around it (these rays cover every cell of the
    disc). A ray starts with the blast's strength; each cell within the radius
    that resists no more than the ray has left is destroyed and costs the ray
    its resistance per cell of length, so the hole in uniform ground is round.
    A cell that resists more stops the destruction there. The ray then marks a
    fringe of ``scorch`` cells, and stops behind a cell no blast of this
    strength could break. Rays only read the world, so a cell that several rays
    reach is destroyed or scorched once, whatever the order of the rays.
    Destroyed powder and liquid cells may fly off as particles; scorched cells
    darken, with a chance that falls off across the fringe. The chunks a blast
    reaches are marked ``awake``, and lose their ``even`` mark.
    """
    cells, shade, timer, flags, vx, vy, carry, heat = s.cells, s.shade, s.timer, s.flags, s.vx, s.vy, s.carry, s.heat
    height, width = cells.shape
    archetype, resistance, heat_cap, heat_recip = t.archetype, t.resistance, t.heat_cap, t.heat_recip
    life_frames, life_jitter = t.life_frames, t.life_jitter
    for b in range(count):
        cx, cy = blasts[b, BLAST_X], blasts[b, BLAST_Y]
        radius, strength, scorch = blasts[b, BLAST_RADIUS], blasts[b, BLAST_STRENGTH], blasts[b, BLAST_SCORCH]
        reach = radius + scorch
        for wy in range(max(cy - reach - WAKE_MARGIN, 0) >> CHUNK_SHIFT, min((cy + reach + WAKE_MARGIN) >> CHUNK_SHIFT, awake.shape[0] - 1) + 1):
            for wx in range(max(cx - reach - WAKE_MARGIN, 0) >> CHUNK_SHIFT, min((cx + reach + WAKE_MARGIN) >> CHUNK_SHIFT, awake.shape[1] - 1) + 1):
                awake[wy, wx] = WHOLE
                even[wy, wx] = 0
        # 0: untouched; 1: destroyed; 2 + d: fringe cell d cells past the destruction (the nearest ray's d).
        mark = np.zeros((2 * reach + 1, 2 * reach + 1), np.int16)
        if _inside(cx, cy, width, height):
            mark[reach, reach] = 1
        for r in range(8 * radius):
            side = r // (2 * radius)
            o = r % (2 * radius)
            if side == 0:
                bx, by = o - radius, -radius
            elif side == 1:
                bx, by = radius, o - radius
            elif side == 2:
                bx, by = radius - o, radius
            else:
                bx, by = -radius, radius - o
            minor = min(abs(bx), abs(by))
            step_len = int(np.floor(256.0 * np.sqrt(float(radius * radius + minor * minor)) / radius + 0.5))
            left = strength
            destroying = True
            past = 0
            for k in range(1, reach + 1):
                qx, qy = _line_point(cx, cy, bx, by, radius, k)
                if not _inside(qx, qy, width, height):
                    break
                ox = qx - cx
                oy = qy - cy
                c = cells[qy, qx]
                if destroying:
                    if ox * ox + oy * oy <= radius * radius and resistance[c] <= left:
                        left -= (resistance[c] * step_len) >> 8
                        mark[oy + reach, ox + reach] = 1
                        continue
                    destroying = False
                if past >= scorch:
                    break
                m = mark[oy + reach, ox + reach]
                if c != 0 and m != 1 and (m == 0 or m > 2 + past):
                    mark[oy + reach, ox + reach] = 2 + past
                past += 1
                if resistance[c] > strength:
                    break  # an unbreakable wall: nothing behind it is touched

        leaves, leaves_chance, fling = blasts[b, BLAST_LEAVES], blasts[b, BLAST_LEAVES_CHANCE], blasts[b, BLAST_FLING]
        speed, hot = blasts[b, BLAST_SPEED], blasts[b, BLAST_HEAT]
        blast_key = _mix32(key ^ (b * 0x9E3779B9))
        for my in range(2 * reach + 1):
            for mx in range(2 * reach + 1):
                m = mark[my, mx]
                if m == 0:
                    continue
                ox = mx - reach
                oy = my - reach
                qx = cx + ox
                qy = cy + oy
                c = cells[qy, qx]
                h = _cell_key(blast_key, qx, qy)
                roll = h >> 8
                warmth = max(_temperature(int(heat[qy, qx]), heat_recip[c]), hot)
                if m == 1:
                    kind = archetype[c]
                    if (kind == POWDER or kind == LIQUID) and roll < fling:
                        # It flies off, away from the centre, fastest near it.
                        dist = np.sqrt(float(ox * ox + oy * oy))
                        if dist == 0.0:
                            angle = (h & 255) * (2.0 * np.pi / 256.0)
                            dx, dy = np.cos(angle), np.sin(angle)
                        else:
                            dx, dy = ox / dist, oy / dist
                        v = speed * (1.0 - dist / (radius + 1.0)) * (0.6 + 0.4 * ((h & 255) / 256.0))
                        cells[qy, qx] = particle
                        carry[qy, qx] = c
                        vx[qy, qx] = int(np.floor(dx * v + 0.5))
                        vy[qy, qx] = int(np.floor(dy * v + 0.5))
                        flags[qy, qx] = 0
                        heat[qy, qx] = _energy(warmth, heat_cap[particle])
                    else:
                        into = leaves if (_mix32(h) >> 8) < leaves_chance else 0
                        cells[qy, qx] = into
                        shade[qy, qx], timer[qy, qx] = _spawn_state(h, life_frames[into], life_jitter[into])
                        vx[qy, qx] = vy[qy, qx] = carry[qy, qx] = 0
                        flags[qy, qx] = LOOSE
                        heat[qy, qx] = _energy(warmth, heat_cap[into])
                elif roll % (scorch + 1) < scorch - (m - 2):  # scorched: chance (scorch - d) / (scorch + 1)
                    flags[qy, qx] |= SCORCHED
                    heat[qy, qx] = _energy(warmth, heat_cap[c])
