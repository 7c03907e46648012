"""The facts the kernel is compiled with: the cell's flag bits, chunks and tiles, fixed-point
units, archetype codes and the encodings of the compiled tables.

The engine package's files (this module among them) name the compiled kernels' cache folder
(:mod:`sandmod.engine.kernelcache`): an edit anywhere else never compiles them anew.
"""

from __future__ import annotations

#: The movement archetypes, by their codes in ``Tables.archetype`` (their order is the code).
ARCHETYPES = ("empty", "static", "powder", "liquid", "gas", "particle")
ARCHETYPE_CODES = {name: code for code, name in enumerate(ARCHETYPES)}

#: Fastest any cell may move, in cells per frame. Bounded so that chunks updated
#: in parallel never reach into each other's cells.
MAX_SPEED = 16
#: Temperatures are in degrees Celsius, within these bounds.
MIN_TEMPERATURE = -273.0
MAX_TEMPERATURE = 9999.0

#: Velocities are fixed-point: this many units make one cell per frame.
SUBCELL = 256
#: Temperatures are fixed-point: this many units make one degree Celsius.
TEMP_ONE = 16


def temperature_units(celsius: float) -> int:
    """Degrees Celsius in the kernel's fixed point."""
    return round(celsius * TEMP_ONE)


#: Heat capacities are fixed-point: this many units make a heat_capacity of 1.
CAP_ONE = 256
#: Columns of a blast row (Tables.blast, and the world's queue of explosions).
BLAST_X, BLAST_Y, BLAST_RADIUS, BLAST_STRENGTH, BLAST_LEAVES, BLAST_LEAVES_CHANCE = range(6)
BLAST_FLING, BLAST_SPEED, BLAST_HEAT, BLAST_SCORCH = range(6, 10)
BLAST_COLUMNS = 10
#: Bits of Tables.thermal: what the kernel checks about a cell's heat each frame.
HEATED, COOLED, FLAMMABLE, IGNITES, EXPLOSIVE = 1, 2, 4, 8, 16
#: Tables.displace: the chance of an exchange in 1/255ths; ALWAYS needs no roll.
ALWAYS = 255
#: Tables.react_into_a/b: the cell stays the element it is (a reaction row serves every pair it matches).
STAYS = 0xFFFF
#: Tables.react_into_a/b and react_holds_a/b: a cell of the pair rather than an element: what the
#: first (A) or second (B) cell was before the reaction (WAS_), or what it held (HELD_). Every code
#: from REFERS up is one of these (or STAYS, or KEEPS); element ids are below MAX_ELEMENTS.
WAS_A, WAS_B, HELD_A, HELD_B = 0xFFF0, 0xFFF1, 0xFFF2, 0xFFF3
REFERS = 0xFFF0
#: Tables.react_holds_a/b: what the cell holds stays as it is.
KEEPS = 0xFFFF
#: Tables.life_into: the cell becomes what it holds.
HELD = HELD_A
#: Where a neighbour lies, by the kernel's numbers for it (Tables.react_group's columns): x + 1, y + 1, x - 1, y - 1.
SIDES = ("right", "below", "left", "above")
#: Tables.breaks_into: the element names nothing to break into (a blast destroys its cells as any other's).
NO_BREAK = 0xFFFF
#: Tables.impact: no landing breaks it (faster than any cell moves).
NO_IMPACT = 1 << 30
#: Most elements loaded at once: ids and what a particle carries are uint16, below STAYS.
MAX_ELEMENTS = 4096
#: The element masks (Tables.reactive and displaces, the elements present in a region): elements
#: 0..UNIQUE_BITS-1 have a bit each; the others share the rest, element e bit UNIQUE_BITS + e %
#: UNIQUE_BITS (see :func:`mask_bit`). The compiler numbers first the elements that most others
#: react with, so that with thousands loaded a mask still tells the common partners apart exactly.
UNIQUE_BITS = 32


def mask_bit(e):
    """Element e's bit in the element masks (a number or a numpy array of them)."""
    return e & (UNIQUE_BITS - 1) | UNIQUE_BITS if e >= UNIQUE_BITS else e

# Bits of State.flags. New cells start loose; the kernel clears MOVED and REACTED each frame;
# the others travel with the cell and are dropped when it turns into another element.
MOVED = 1  # moved or changed this frame
REACTED = 2  # reacted this frame
LOOSE = 4  # a powder grain in motion (free-falling); cleared when it comes to rest
BURNING = 8  # on fire: the timer counts down the burning time
SCORCHED = 16  # darkened by a blast
DETONATING = 32  # an explosive going off this frame (its blast comes after the step)

# Exchanges between fluids are rolled per plume block (PLUME columns by PLUME_RUN rows), not
# per cell: the cells of a block sink or rise together (plumes and fingers, not static). A
# faller that sinks into a fluid takes the fallers above it in its run of PLUME_RUN rows down
# with it, and the fluid rises to the run's top, so no comb of alternating rows forms. The
# grid of blocks and each column's runs shift every frame.
PLUME_SHIFT = 2
PLUME = 1 << PLUME_SHIFT
PLUME_RUN_SHIFT = 4
PLUME_RUN = 1 << PLUME_RUN_SHIFT

# Sleeping chunks and parallel tiles. The world is cut into chunks of CHUNK x CHUNK
# cells; a chunk is updated only while something in it or within WAKE_MARGIN cells
# of it changes. Tiles of 2 x 2 chunks are updated in four passes, the tiles of
# one pass in parallel: no cell's update reaches further than REACH cells (its
# fastest move plus a neighbour), so tiles a tile apart never touch the same cells.
CHUNK_SHIFT = 5
CHUNK = 1 << CHUNK_SHIFT
TILE_SHIFT = CHUNK_SHIFT + 1
TILE = 1 << TILE_SHIFT
WAKE_MARGIN = 2
REACH = MAX_SPEED + 1
# A chunk's wake mark (World.awake, and the kernel's scratch of chunks woken during a
# step): 0 asleep; WHOLE: every row; else PART | y0 | y1 << 6: only the rows y0..y1
# (chunk-local, inclusive), those within WAKE_MARGIN of a change. Marks only widen.
WHOLE = 1
PART = 1 << 15
assert 2 * (REACH + WAKE_MARGIN) < TILE, "tiles of one pass must not reach each other's chunks"

CACHE_LINE = 64  # bytes
LINE_CELLS = CACHE_LINE // 4  # cells in a cache line of the widest array (heat, 4 bytes): a row's lines are asked for this far apart
CACHED_CELLS = 1 << 16  # a world of no more cells (about a megabyte of state) stays in the CPU's cache: nothing to prefetch
