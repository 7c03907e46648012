"""The numba kernel: one frame of the cellular automaton.

The kernel reads only what it is given: the world's arrays (a
:class:`~sandmod.world.world.State`), the compiled
:class:`~sandmod.rules.compiler.Tables`, and per-frame hash keys. Adding or
editing a mod changes the tables' contents, never the compiled code.

Order within a frame: tiles of 64 x 64 cells in four passes by their
parity, the tiles of a pass in parallel (:func:`step`); within a tile, heat
first (:func:`~.heat.conduct`), then rows bottom-up, the horizontal direction
alternating with the row and the frame (:func:`step_region`). Only the
rows of the awake chunks (32 x 32) that their wake marks name are touched
(:mod:`.chunks`). A cell is updated once, in four phases, each a function
of its own: its heat and fire (:func:`.fire.heat_and_fire`), its lifetime
(:func:`.reactions.lifetime`), a reaction with a touching neighbour
(:func:`.reactions.react`), and then movement by its archetype
(:func:`.moves.move`). A cell that moved or changed this frame is marked and
left alone for the rest of the frame. Every change of a cell's element goes
through :func:`.cells.become`, every move through :func:`.cells.swap`.

The phases take arrays, so numba inlines them (see :mod:`.jit`): the per-cell
update is compiled as one function, and LLVM sees it whole. It holds more
values than the CPU has registers, so the commonest cells (those that stay
put, and a straight fall into a fluid) can also go through a small loop of
their own first (:func:`_fast_cells`), compiled as a second version of
:func:`step_region`. It pays where most cells are such (sand sinking through
water), and costs where most are not (cells in flight), since each cell it
hands on to the full update reloads that update's values; each tile takes it
while it pays, and the frames are the same either way.

The per-cell code reads and writes the world's arrays at :func:`.cells._at`,
unsigned indices, which numba need not wrap around.
"""

from __future__ import annotations

import numpy as np

from .blasts import explode, take_detonations  # noqa: F401  (the kernel's whole interface is here)
from .cells import CARRIED, GAS, LIQUID, MOVED, POWDER, STATIC, _at, _bit, _enterable, _inside, _mix32, _plume_roll, _within
from .chunks import _covers, _grown, _mark, _pass_tiles, _wake, clear_marks
from .fire import heat_and_fire
from .heat import conduct
from .jit import called, compiled, copied, inlined, parallel, prange, quick
from .layout import ALWAYS, BURNING, CACHED_CELLS, CHUNK_SHIFT, FLAMMABLE, IGNITES, LINE_CELLS, LOOSE, TILE, TILE_SHIFT
from .moves import knock, may_flow, move, sink_run, slump, slump_side
from .paint import paint_cells  # noqa: F401
from .prefetch import prefetch
from .reactions import lifetime, react

SALT_KNOCK = 0x27D4EB2F
SALT_FIRE = 0x61C88647
SALT_EXCHANGE = 0x3243F6A9
HANDED_ON_COST = 4  # step_region's fast loop pays where it hands on fewer than one in this many cells of the rows it updates
FAST_TRIAL = 8  # a tile whose fast loop did not pay tries it again every this many frames (a power of two)


@inlined
def _elements_in(cells, x0, y0, x1, y1):
    """The mask (bit e % 64 for element e, as in ``reactive``) of the elements in columns x0..x1-1 of rows y0..y1-1."""
    present = np.int64(0)
    for y in range(y0, y1):
        for x in range(x0, x1):
            present |= _bit(cells[_at(y, x)])
    return present


@inlined
def _prefetch_rows(s, y, y1, sx0, sx1):
    """Ask for the row two above (at the region's first row, the one above too) while this one is
    updated: the lines at the segment's two ends in each array, and heat's (four bytes a cell) between."""
    for ahead in range(max(y - 2, 0), y if y == y1 - 1 else y - 1):
        for ax in range(sx0 + LINE_CELLS, sx1 - 1, LINE_CELLS):
            prefetch(s.heat, ahead, ax)
        for ax in (sx0, sx1 - 1):
            prefetch(s.cells, ahead, ax)
            prefetch(s.flags, ahead, ax)
            prefetch(s.heat, ahead, ax)
            prefetch(s.vx, ahead, ax)
            prefetch(s.vy, ahead, ax)
            prefetch(s.shade, ahead, ax)
            prefetch(s.timer, ahead, ax)


@compiled
def _box_with(box, x0, x1, y0, y1):
    """The box (x0, x1, y0, y1, inclusive) grown to take in another."""
    return min(box[0], x0), max(box[1], x1), min(box[2], y0), max(box[3], y1)


@inlined
def _boxed_in(cells, displace, e, x, y, ty):
    """Is a grain of element e at (x, y) shut in: does each of the cells its moves start with (below,
    diagonally below and beside it, ``ty`` the row below) lie outside the world or hold an element
    it cannot enter? Then no roll can move it."""
    height, width = cells.shape
    for k in range(5):
        nx = x + (0, -1, 1, -1, 1)[k]
        ny = ty if k < 3 else y
        if _inside(nx, ny, width, height):
            o = cells[_at(ny, nx)]
            if o == 0 or displace[e, o] != 0:
                return False
    return True


@inlined
def _fast_cells(s, t, y, sx0, sx1, n, forward, present, exchange_key, knock_key, ambient, x0, y0, x1, y1, frame, busy_box, stir_box):
    """The fast loop: the cells of row y's segment sx0..sx1-1 from its ``n``-th on (in the row's
    direction) that need little, in a loop that holds few values (registers, not the stack): cells
    at rest that nothing around them can move (a resting fluid that nothing it could displace is
    next to, a resting grain, a static cell), a loose grain shut in where it is (it comes to rest,
    see :func:`_boxed_in`), a resting grain's slump into a fluid diagonally below it
    (:func:`~.moves.slump`), and a straight sink into a fluid by a grain at rest, with the run
    behind it (:func:`~.moves.sink_run`). Stops at the first cell that needs more. Returns how far
    it got (the segment's length when done), that cell and its element, whether only its move is
    left to decide (``ready``), and the boxes of the cells it changed and stirred."""
    cells, flags, heat, vx, vy = s.cells, s.flags, s.heat, s.vx, s.vy
    height, width = cells.shape
    count = sx1 - sx0
    x = sx0
    e = cells[_at(y, x)]
    ready = False
    while n < count:
        x = sx0 + n if forward else sx1 - 1 - n
        e = cells[_at(y, x)]
        f = flags[_at(y, x)]
        if e == 0 or (f & MOVED) != 0:
            n += 1
            continue
        ready = False  # falling, or not calm, or a lifetime, or a partner near: the full update
        if vy[_at(y, x)] != 0 or (f & BURNING) != 0 or t.life_frames[e] != 0 or (t.reactive[e] & present) != 0:
            break
        sliding = vx[_at(y, x)] != 0
        th = t.thermal[e]
        if th != 0 and ((th & (FLAMMABLE | IGNITES)) != 0 or not (t.cold_limit[e] <= heat[_at(y, x)] <= t.hot_limit[e])):
            break
        ready = True  # only the move is left to decide
        kind = t.archetype[e]
        if sliding and kind != POWDER:
            break  # moving: the full update
        if kind == LIQUID or kind == GAS:
            if (t.displaces[e] & present) != 0 and may_flow(cells, t.displace, e, x, y, t.fall_dir[e]):
                break  # it may displace something next to it
            n += 1  # at rest, with nothing it could displace where it could go: stays put
            continue
        if kind == STATIC:
            n += 1
            continue
        if kind != POWDER:
            break  # a particle
        ty = y + t.fall_dir[e]
        below = 0
        opens = False
        if _within(ty, height):
            below = cells[_at(ty, x)]
            opens = _enterable(t.displace[e, below], below, flags[_at(ty, x)])
        if not opens:
            if (f & LOOSE) == 0 and not sliding:
                side = slump_side(cells, t.displace, e, x, y, ty, 1 if forward else -1)
                if side != 0:  # at rest beside a fluid diagonally below: it slumps into it, as the full update would
                    busy, stir, moved = slump(s, t, e, x, y, ty, side, exchange_key, knock_key, forward, x0, y0, x1, y1, frame, ambient)
                    if busy:
                        busy_box = _box_with(busy_box, min(x, x + side * moved), max(x, x + side * moved), y, ty if moved else y)
                    if stir:
                        stir_box = _box_with(stir_box, min(x, x + side), max(x, x + side), y, ty)
                n += 1  # at rest on the ground: stays put
                continue
            if not _boxed_in(cells, t.displace, e, x, y, ty):
                break  # on the ground, and loose: it may roll or slide
            # Every cell it could roll, slide or sink into holds what it cannot enter: whatever its
            # rolls, it comes to rest where it is, as the full update (move, settle) would leave it.
            vx[_at(y, x)] = 0
            flags[_at(y, x)] = f & ~LOOSE
            busy_box = _box_with(busy_box, x, x, y, y)
            n += 1
            continue
        if sliding:
            break  # falling with a sideways speed: the full update
        if below == 0 or ty >= y1 or not (0 < x and x + 1 < width and 0 < y):
            break  # falling through empty cells, into another tile's cells, or at the world's edge
        threshold = t.displace[e, below]
        if threshold != ALWAYS and (_plume_roll(exchange_key, x, y) >> 24) >= threshold:
            busy_box = _box_with(busy_box, x, x, y, y)  # it waits for its chance to sink
            n += 1
            continue
        # Straight into a fluid: one cell, its speed lost, with the run behind it.
        ry, stir = sink_run(s, t, x, y, ty - y, exchange_key, ambient)  # the grains above it follow
        vx[_at(ty, x)] = 0
        vy[_at(ty, x)] = 0
        flags[_at(ty, x)] = MOVED | LOOSE | (f & CARRIED)  # sinking: it may slide where it lands
        if ry == y:  # nothing followed it: the grains diagonally above may, if knocked loose
            knock(s, t, x, y, x, ty, 2 * y - ty, knock_key, 2, 4)
        busy_box = _box_with(busy_box, x, x, ry, ty)
        if stir:
            stir_box = _box_with(stir_box, x, x, ry, ty)
        n += 1
    return n, x, e, ready, busy_box, stir_box


@inlined
def _update_cell(s, t, x, y, e, ready, present, keys, detonations, tile, forward, x0, y0, x1, y1, frame, ambient):
    """The full update of cell (x, y), of element e, in its four phases; with ``ready`` (the fast
    loop found it calm, with no lifetime and no partner near), the move only. Returns whether
    anything changed or may (busy), whether an element or a heat changed (stir), the mask of
    elements present with those it made, and where the cell ended up."""
    move_key, react_key, spawn_key, fire_key, exchange_key, knock_key = keys
    busy = stir = False
    if not ready:
        done, busy, stir, born = heat_and_fire(s, t, x, y, e, fire_key, spawn_key, detonations, tile)
        present |= born
        if done:
            return busy, stir, present, x, y, y
        done, b, st, born = lifetime(s, t, x, y, e, spawn_key)
        busy, stir, present = busy or b, stir or st, present | born
        if done:
            return busy, stir, present, x, y, y
        done, b, st, born = react(s, t, x, y, e, present, move_key, react_key, spawn_key)
        busy, stir, present = busy or b, stir or st, present | born
        if done:
            return busy, stir, present, x, y, y
    b, st, born, px, py, ry = move(s, t, x, y, e, present, move_key, exchange_key, knock_key, spawn_key, forward, x0, y0, x1, y1, frame, ambient)
    return busy or b, stir or st, present | born, px, py, ry


@inlined
def step_region(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen, fast):
    """Update the awake cells of rows y0..y1-1 and columns x0..x1-1 (moves may leave the region).

    A row of a chunk is updated when the chunk's mark in ``awake`` (from last
    frame) or ``woken`` (by a change nearby earlier this frame) covers it (see
    :data:`sandmod.engine.layout.WHOLE`). Every change, and every chance that did not
    come up, widens the ``woken`` marks to the rows within two cells of where
    it happened, and where an element or a heat changed, other than
    by two cells of one temperature trading places, in ``stirred`` too (see
    :func:`~.heat.conduct`): once per row of a chunk, for a box around that row's
    changes. Explosives that go off are marked DETONATING and
    counted in ``detonations[tile]``, for :func:`~.blasts.take_detonations` after the step.

    ``present`` masks the elements that may be next to a cell being updated:
    those in the rows next to it (across the region and a cell past it) before
    the first update of the row, each element that a cell turns into since,
    and ``also_present`` (-1 in tests: all). Moves bring in nothing new: a mover
    trades places with a cell next to it, or with an empty one past an empty
    one next to it. A cell whose partners, or whose fluid moves' elements, are
    not in the mask skips looking at its neighbours for them (in a world of
    sand and water, every cell does).

    With ``fast`` True (:func:`step_region_fast`; None: :func:`step_region_full`, its other compiled
    version), the cells are taken first by :func:`_fast_cells`; each cell that needs more gets the
    full update, and the fast loop resumes after it: the same frames either
    way. Returns how well the fast loop did: the cells of the rows updated,
    less HANDED_ON_COST for each one it handed on (above zero: it paid);
    without ``fast``, 0. (None, not False: numba drops a branch on ``is None`` before it types the
    function, so the version without never compiles the fast loop.)
    """
    cells = s.cells
    height, width = cells.shape
    ambient = int(t.temp_start[0])  # the air's temperature is the world's outside
    keys = (move_key, react_key, spawn_key, _mix32(move_key ^ SALT_FIRE), _mix32(move_key ^ SALT_EXCHANGE), _mix32(move_key ^ SALT_KNOCK))
    first_cx = x0 >> CHUNK_SHIFT
    segments = ((x1 - 1) >> CHUNK_SHIFT) - first_cx + 1
    present = also_present
    visited = 0  # cells of the rows updated, and how many of them the fast loop handed on to the full update
    handed_on = 0
    far = height * width > CACHED_CELLS  # prefetch rows ahead
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
            if far:
                _prefetch_rows(s, y, y1, sx0, sx1)
            # The cells the segment's updates changed (or may change later), and those that stirred, as two
            # boxes (x0, x1, y0, y1): woken once, at the segment's end. A box may take in cells no single update
            # did: more waking and stirring, which changes nothing but the work.
            busy_box = stir_box = (sx1, sx0 - 1, y, y)
            count = sx1 - sx0
            visited += count
            n = np.int64(0)  # not the literal 0: numba would compile _fast_cells for it too, while it types the loop
            while n < count:
                if fast is not None:
                    n, x, e, ready, busy_box, stir_box = _fast_cells(s, t, y, sx0, sx1, n, forward, present, keys[4], keys[5], ambient, x0, y0, x1, y1, frame, busy_box, stir_box)
                    if n == count:
                        break
                    handed_on += 1
                else:
                    x = sx0 + n if forward else sx1 - 1 - n
                    e = cells[_at(y, x)]
                    ready = False
                    if e == 0 or (s.flags[_at(y, x)] & MOVED) != 0:
                        n += 1
                        continue  # its turn is over: it moved, or changed
                busy, stir, present, px, py, ry = _update_cell(s, t, x, y, e, ready, present, keys, detonations, tile, forward, x0, y0, x1, y1, frame, ambient)
                if busy:  # the cells it moved between go in the segment's boxes
                    busy_box = _box_with(busy_box, min(x, px), max(x, px), min(y, py, ry), max(y, py, ry))
                    if stir:
                        stir_box = _box_with(stir_box, min(x, px), max(x, px), min(y, py, ry), max(y, py, ry))
                n += 1
            if busy_box[0] <= busy_box[1]:  # wake every cell within two cells of the box
                wx0, wy0, wx1, wy1 = _grown(busy_box[0], busy_box[2], busy_box[1], busy_box[3], width, height)
                _wake(woken, stirred, False, wx0, wy0, wx1, wy1)
            if stir_box[0] <= stir_box[1]:  # and stir the chunks of the cells within two cells of the other
                wx0, wy0, wx1, wy1 = _grown(stir_box[0], stir_box[2], stir_box[1], stir_box[3], width, height)
                _wake(woken, stirred, True, wx0, wy0, wx1, wy1)
    seen[tile] = present
    return visited - HANDED_ON_COST * handed_on if fast is not None else 0


@inlined
def step_region_fast(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen):
    """:func:`step_region` with its fast loop."""
    return step_region(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen, True)


@inlined
def step_region_full(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen):
    """:func:`step_region` without its fast loop: every cell gets the full update."""
    return step_region(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen, None)


@called
def step_region_full_by_name(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen):
    """:func:`step_region_full`, compiled on its own and called by name: the quick step's update (:func:`step_soon`)."""
    return step_region(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen, None)


@compiled  # called, not inlined: inlined in the serial step it ran 3 to 7% slower (bench --against)
def _update_tile(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tile, also_present, fast_gain, route, seen):
    """Heat, then cells, in tile number ``tile`` (row-major), with or without :func:`step_region`'s fast loop (see :func:`step`)."""
    _update_tile_with(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tile, also_present, fast_gain, route, seen, False)


@inlined  # into step_soon, which so compiles in less time
def _update_tile_soon(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tile, also_present, fast_gain, route, seen):
    """:func:`_update_tile`, calling the update's versions by name (:func:`step_soon`)."""
    _update_tile_with(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tile, also_present, fast_gain, route, seen, True)


@copied
def _update_tile_with(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tile, also_present, fast_gain, route, seen, by_name):
    """:func:`_update_tile`, its update's versions inlined, or called by name where ``by_name`` (a constant in each caller)."""
    height, width = s.cells.shape
    tiles_x = (width + TILE - 1) >> TILE_SHIFT
    x0 = (tile % tiles_x) << TILE_SHIFT
    y0 = (tile // tiles_x) << TILE_SHIFT
    x1 = min(x0 + TILE, width)
    y1 = min(y0 + TILE, height)
    conduct(s, t, frame, awake, woken, even, stirred, x0, y0, x1, y1)
    fast = route > 0 or (route == 0 and (fast_gain[tile] > 0 or ((frame + tile) & (FAST_TRIAL - 1)) == 0))
    if by_name:  # without the fast loop, whatever the route: the same frames, and one version fewer to compile first
        step_region_full_by_name(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen)
    elif fast:
        fast_gain[tile] = step_region_fast(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen)
    else:
        step_region_full(s, t, move_key, react_key, spawn_key, frame, awake, woken, stirred, detonations, tile, x0, y0, x1, y1, also_present, seen)


@parallel
def update_tiles_at_once(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tiles, count, also_present, fast_gain, route, seen):
    """Update the first ``count`` tiles of ``tiles`` (tile numbers, row-major) on the threads numba
    has, one tile per thread at a time."""
    for k in prange(count):
        _update_tile(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, tiles[k], also_present, fast_gain, route, seen)


@compiled
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


@copied
def _step_passes(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route, seen, at_once, by_name):
    """:func:`step`, its tiles updated by :func:`update_tiles_at_once` where ``at_once`` (a constant
    in each caller), else one after another here, by :func:`_update_tile_soon` where ``by_name`` (a constant too)."""
    woken[:] = 0
    stirred[:] = 0
    detonations[:] = 0
    seen[:] = 0
    clear_marks(s.flags, awake)
    todo = np.empty(len(detonations), np.int64)
    order = np.empty_like(todo)
    for p in range(4):
        count = _tiles_of_pass(awake, woken, frame, p, hands, todo, order)
        if count == 0:
            continue
        if at_once:
            update_tiles_at_once(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, order, count, also_present, fast_gain, route, seen)
        else:
            for k in range(count):
                if by_name:
                    _update_tile_soon(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, order[k], also_present, fast_gain, route, seen)
                else:
                    _update_tile(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, order[k], also_present, fast_gain, route, seen)
    chunks_y, chunks_x = awake.shape
    for cy in range(chunks_y):
        for cx in range(chunks_x):
            awake[cy, cx] = woken[cy, cx, 0]
            if stirred[cy, cx, 0] != 0:
                even[cy, cx] = 0
    return detonations.sum()


@compiled
def step(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route, seen):
    """Advance the world by one frame, on this thread; returns how many explosives went off (see :func:`~.blasts.take_detonations`).

    The world is cut into tiles of 2 x 2 chunks, updated in four passes by
    the parity of their column and row; the tiles of one pass are a tile apart,
    farther than anything one cell does can reach, so they may be updated at
    the same time on as many threads as there are (:func:`step_at_once`), with
    the same result as one after another. Within a tile, heat flows first, then
    the cells move. Only the rows of chunks that ``awake``'s marks name are
    touched; ``awake`` then holds the marks for the next frame. ``even`` marks
    chunks whose heat needs no sweep (see :func:`~.heat.conduct`). ``hands``, the
    number of threads, only decides which thread takes which tile.
    ``also_present`` is 0, or -1 to look at the neighbours of every cell for
    partners (see :func:`step_region`): tests compare the two. ``fast_gain``
    holds, per tile, how well :func:`step_region`'s fast loop did the last
    time the tile took it: a tile takes it while it pays, and tries it again
    every FAST_TRIAL frames when it did not. ``route`` 1 sends every tile
    through the fast loop and -1 none (tests compare them); 0 chooses so.
    ``seen`` gets, per tile, the mask of the elements in the rows updated (0:
    none updated), for the passes after the step (:mod:`sandmod.passes`).

    A function of its own, not an argument of one: so that a run on one
    thread never compiles numba's parallel code, nor starts its threads.
    """
    one = np.int64(1)  # not the literal 1: numba would compile what it is passed to a second time for it
    return _step_passes(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, one, also_present, fast_gain, route, seen, False, False)


@quick
def step_soon(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route, seen):
    """:func:`step`, the same frames, compiled in seconds and run slower: it calls the update without its fast
    loop, compiled on its own, by name (:func:`step_region_full_by_name`), rather than optimizing both the update's
    versions again as part of itself. A first run steps with it while :func:`step` compiles."""
    one = np.int64(1)
    return _step_passes(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, one, also_present, fast_gain, route, seen, False, True)


@compiled
def step_at_once(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route, seen):
    """:func:`step` on ``hands`` of numba's threads (numba's count set to it)."""
    return _step_passes(s, t, move_key, react_key, spawn_key, frame, awake, woken, even, stirred, detonations, hands, also_present, fast_gain, route, seen, True, False)
