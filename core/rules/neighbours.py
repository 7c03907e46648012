"""Neighbour-count rules compiled: per element, the rows of the rules that change its cells, each
with the elements it counts, the counts at which it fires, which of the 8 neighbours it looks at,
what the cell becomes and by what chance. The kernel never reads them: the pass after its step
does (:mod:`sandmod.passes.counts`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple, Sequence

import numpy as np

from ..engine.hashing import chance_threshold
from ..engine.layout import mask_bit
from .modset import LoadedMod
from .reactions import _select

if TYPE_CHECKING:
    from .compiler import ElementInfo

#: The 8 neighbours, by their bit in NeighbourTables.where: (dx, dy) each, y down.
AROUND = ((-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1))
#: The neighbours each ``where`` word names, as bits of AROUND.
_NAMED = {"above": {1}, "below": {6}, "left": {3}, "right": {4}, "sides": {3, 4}, "diagonals": {0, 2, 5, 7}}


class NeighbourTables(NamedTuple):
    """The compiled neighbour rules: rows ``start[e]`` to ``stop[e] - 1`` change cells of element e."""

    start: np.ndarray  # int32[n]
    stop: np.ndarray  # int32[n]
    counted: np.ndarray  # uint8[r, n]: 1 where the row counts a neighbour of that element
    counts: np.ndarray  # uint16[r]: bit k set: it fires with k neighbours counted
    where: np.ndarray  # uint8[r]: the neighbours it looks at, bits of AROUND
    into: np.ndarray  # uint16[r]: what the cell becomes
    chance: np.ndarray  # uint32[r]: roll threshold (hashing.ROLL_BITS)
    mask: int  # the element-mask bits of the elements that matter (changed, but empty cells, and counted): where to look


def compile_neighbours(mods: Sequence[LoadedMod], elements: Sequence[ElementInfo], resolve) -> NeighbourTables | None:
    """The neighbour rules of ``mods``, in load order (of two rules for one element, the first to fire
    applies); None when there are none. ``resolve(ref, mod, loc)`` names an element or notes a problem."""
    n = len(elements)
    rows: dict[int, list[tuple]] = {}
    for mod in mods:
        for number, rule in enumerate(mod.spec.neighbours):
            loc = ("neighbours", number)
            cells = _select(rule.cell, elements, lambda r: resolve(r, mod, loc + ("cell",)))
            counted = _select(rule.count, elements, lambda r: resolve(r, mod, loc + ("count",)))
            into = resolve(rule.becomes, mod, loc + ("becomes",))
            if cells is None or counted is None or into is None:
                continue
            where = sum(1 << k for k in set().union(*(_NAMED[w] for w in rule.where or _NAMED)))
            fires = sum(1 << k for k in set(rule.counts))
            row = (tuple(sorted(counted[0])), fires, where, into, chance_threshold(rule.chance))
            for e in cells[0]:
                rows.setdefault(e, []).append(row)
    if not rows:
        return None
    start, stop = np.zeros(n, np.int32), np.zeros(n, np.int32)
    flat: list[tuple] = []
    for e in sorted(rows):
        start[e] = len(flat)
        flat.extend(rows[e])
        stop[e] = len(flat)
    counted = np.zeros((len(flat), n), np.uint8)
    for r, (which, *_) in enumerate(flat):
        counted[r, list(which)] = 1
    matter = {e for e in rows if e != 0} | {e for which, *_ in flat for e in which}
    mask = 0
    for e in matter:
        mask |= 1 << mask_bit(e)
    return NeighbourTables(
        start, stop, counted,
        np.array([r[1] for r in flat], np.uint16), np.array([r[2] for r in flat], np.uint8),
        np.array([r[3] for r in flat], np.uint16), np.array([r[4] for r in flat], np.uint32),
        int(np.uint64(mask).view(np.int64)),
    )
