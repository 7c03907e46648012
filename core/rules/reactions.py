"""Reactions compiled: which of them applies to each touching pair of elements, on which side, as
rows of the tables the kernel reads (one a side of each reaction, whatever its selectors match),
and the checks on them (ties between mods, chains that never settle).

Of two reactions on a pair, the more specific wins (names over tags over wildcards), then the
one with the higher ``priority``, then the one of the mod loaded later: a warning where neither
mod requires the other, an error within one mod.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple, Sequence

import numpy as np

from ..engine.hashing import chance_threshold
from ..engine.layout import HELD_A, HELD_B, KEEPS, MAX_TEMPERATURE, MIN_TEMPERATURE, REFERS, SIDES, STAYS, SUBCELL, WAS_A, WAS_B, mask_bit, temperature_units
from ..errors import Problem
from ..formats.modspec import Reaction
from .definitions import resolve_name
from .modset import LoadedMod

if TYPE_CHECKING:
    from .compiler import ElementInfo, Tables


@dataclass(frozen=True)
class CompiledReaction:
    """A reaction with its selectors resolved, for listing."""

    mod: str
    spec: Reaction
    a: tuple[str, ...]
    b: tuple[str, ...]


def by_partners(mods: Sequence[LoadedMod], elements: Sequence[ElementInfo]) -> list[str]:
    """The ids but the empty cell's, those that the most elements react with first (then by id): the
    first take the element masks' own bits (:data:`~sandmod.engine.layout.UNIQUE_BITS`)."""
    ids = {e.id: e.index for e in elements}
    partners = np.zeros(len(elements), np.int64)
    for mod in mods:
        for reaction in mod.spec.reactions:
            sides = [_select(selector, elements, lambda r: ids.get(resolve_name(r, mod.name, ids, mod.requires)[0]))
                     for selector in (reaction.a, reaction.b)]
            if None not in sides:
                (side_a, _), (side_b, _) = sides
                partners[list(side_a)] += len(side_b)
                partners[list(side_b)] += len(side_a)
    return [e.id for e in sorted(elements[1:], key=lambda e: (-partners[e.index], e.id))]


def _select(selector: str, elements: Sequence[ElementInfo], resolve_one) -> tuple[set[int], int] | None:
    """The element indices a selector matches, and how specific it is (3 name, 2 tag, 1 broad)."""
    negate = selector.startswith("!")
    term = selector[1:] if negate else selector
    non_empty = {e.index for e in elements if e.index != 0}
    if term == "*":
        matched, score = set(non_empty), 1
    elif term.startswith("#"):
        matched, score = {e.index for e in elements if term[1:] in e.spec.tags}, 2
    else:
        index = resolve_one(term)
        if index is None:
            return None
        matched, score = {index}, 3
    return (non_empty - matched, 1) if negate else (matched, score)


def compile_reactions(mods, elements, t: Tables, resolve, problems, warnings, below) -> tuple[tuple[CompiledReaction, ...], Tables]:
    """Fill the pair table and make the reaction rows it points to (one per reaction and side: a
    row serves every pair a reaction matches). Of two reactions on a pair, the more specific wins
    (names over tags over wildcards), then the one with the higher ``priority``, then the one of
    the mod loaded later: a warning where neither mod requires the other, an error within one mod."""
    # (a, b, side b lies on) -> ((specificity, priority), mod, reaction number, outcome, row): the outcome
    # (a becomes, b becomes, threshold, lowest and highest T sum, heat, a's push, b's push) with
    # elements, the row the same with STAYS for a cell that stays
    winner: dict[tuple[int, int, int], tuple[tuple[int, int], LoadedMod, int, tuple, tuple]] = {}
    reported: set[tuple[str, int, str, int]] = set()  # ties already named, by both reactions
    compiled: list[CompiledReaction] = []

    def claim(pair, outcome, row, rank, mod, number) -> None:
        held = winner.get(pair)
        if held is not None and (held[0] > rank or (held[0] == rank and held[3] == outcome)):
            return
        if held is not None and held[0] == rank:  # a tie: the later mod's wins; within a mod, an error
            tie = (mod.name, number, held[1].name, held[2])
            if held[1].name == mod.name or held[1].name not in below[mod.name]:
                if tie not in reported:
                    reported.add(tie)
                    _report_tie(elements, pair, mod, number, held, problems if held[1].name == mod.name else warnings)
                if held[1].name == mod.name:
                    return
        winner[pair] = (rank, mod, number, outcome, row)

    for mod in mods:
        for number, reaction in enumerate(mod.spec.reactions):
            loc = ("reactions", number)
            side_a = _select(reaction.a, elements, lambda r: resolve(r, mod, loc + ("a",)))
            side_b = _select(reaction.b, elements, lambda r: resolve(r, mod, loc + ("b",)))
            named = {field: product(getattr(reaction, field), lambda r, f=field: resolve(r, mod, loc + (f,)))
                     for field in ("a_becomes", "b_becomes", "a_holds", "b_holds")}
            if side_a is None or side_b is None or None in named.values():
                continue
            (set_a, score_a), (set_b, score_b) = side_a, side_b
            into_a, into_b = (None if named[f] == STAYS else named[f] for f in ("a_becomes", "b_becomes"))
            holds_a, holds_b = named["a_holds"], named["b_holds"]
            _can_hold(t, set_a, into_a, holds_a)
            _can_hold(t, set_b, into_b, holds_b)
            threshold = chance_threshold(reaction.chance)
            low = -(2**31) if reaction.min_temperature is None else 2 * temperature_units(reaction.min_temperature)
            high = 2**31 - 1 if reaction.max_temperature is None else 2 * temperature_units(reaction.max_temperature)
            rest = (threshold, low, high, temperature_units(reaction.heat))
            first, second = (STAYS if into is None else into for into in (into_a, into_b))
            push = round((reaction.push or 0) * SUBCELL)
            refers = int(any(c >= REFERS and c != STAYS for c in (first, second)) or (holds_a, holds_b) != (KEEPS, KEEPS))
            forward = (first, second, *rest, 0, push, holds_a, holds_b, refers)
            backward = (*map(_swapped, (second, first)), *rest, push, 0, *map(_swapped, (holds_b, holds_a)), refers)
            rank = (score_a + score_b, reaction.priority)
            sides = _sides(reaction.where)
            for i in sorted(set_a):
                for j in sorted(set_b):
                    out_i = i if into_a is None else into_a
                    out_j = j if into_b is None else into_b
                    for d in sides:
                        claim((i, j, d), (out_i, out_j, *rest, 0, push, *forward[-3:]), forward, rank, mod, number)
                        opposite = (d + 2) % len(SIDES)  # the same contact, seen from the other cell
                        if i != j or opposite not in sides:  # (of one element: whichever looks first is a)
                            claim((j, i, opposite), (out_j, out_i, *rest, push, 0, *backward[-3:]), backward, rank, mod, number)
            compiled.append(
                CompiledReaction(
                    mod.name, reaction, tuple(elements[i].id for i in sorted(set_a)), tuple(elements[j].id for j in sorted(set_b))
                )
            )
    rows, groups, sided = {NO_REACTION: 0}, {(0,) * len(SIDES): 0}, {}
    for (i, j, d), (*_, row) in winner.items():
        sided.setdefault((i, j), [0] * len(SIDES))[d] = rows.setdefault(row, len(rows))
    for pair, group in sided.items():
        t.react_pair[pair] = groups.setdefault(tuple(group), len(groups))
    t.reactive[:] = element_masks(t.react_pair)
    problems.extend(_endless_reactions({key[:2]: held for key, held in winner.items()}, elements))
    return tuple(compiled), t._replace(**reaction_rows(list(rows)), react_group=np.array(list(groups), np.uint16))


def _sides(where: list[str] | None) -> list[int]:
    """The kernel's numbers of the sides (:data:`SIDES`) a reaction's b cell may lie on, seen from a."""
    named = {side for w in where or SIDES for side in (("left", "right") if w == "sides" else (w,))}
    return [d for d, side in enumerate(SIDES) if side in named]


#: Row 0 of the reaction tables: what a pair without a reaction reads.
NO_REACTION = (STAYS, STAYS, 0, -(2**31), 2**31 - 1, 0, 0, 0, KEEPS, KEEPS, 0)
#: The words for a cell of the pair in a_becomes, b_becomes, a_holds and b_holds, by the kernel's codes.
CELL_WORDS = {"@a": WAS_A, "@b": WAS_B, "@a.held": HELD_A, "@b.held": HELD_B}


def product(written: str | None, resolve) -> int | None:
    """A reaction's ``*_becomes`` or ``*_holds`` as the kernel reads it: STAYS (KEEPS) where left out, a
    code from REFERS up for a cell of the pair, or an element's id (None: unknown, a problem noted)."""
    if written is None:
        return STAYS
    return CELL_WORDS[written] if written.startswith("@") else resolve(written)


def _swapped(code: int) -> int:
    """A code seen from the other cell of the pair: what names the first cell names the second."""
    pairs = {WAS_A: WAS_B, WAS_B: WAS_A, HELD_A: HELD_B, HELD_B: HELD_A}
    return pairs.get(code, code)


def _can_hold(t: Tables, cells: set[int], into: int | None, holds: int) -> None:
    """A reaction gives the cells of ``cells`` something to hold: what they are afterwards can hold
    (``Tables.remembers``); afterwards is ``into`` unless that is left out or names a cell of the pair."""
    if holds == KEEPS:
        return
    if into is None:
        t.remembers[sorted(cells)] = 1
    elif into < REFERS:
        t.remembers[into] = 1


class PairReaction(NamedTuple):
    """What a touching pair does, read from the tables (:func:`pair_reaction`)."""

    chance: int  # roll threshold per frame of contact
    into_a: int  # what a becomes (itself where it stays)
    into_b: int
    tsum_min: int  # lowest T_a + T_b, TEMP_ONE units
    tsum_max: int
    heat: int  # temperature added to a cell that changes, TEMP_ONE units
    push_a: int  # speed a flies off at, SUBCELL units (0: it stays)
    push_b: int
    holds_a: int  # what a holds afterwards (KEEPS: unchanged; from REFERS up: a cell of the pair)
    holds_b: int


def pair_reaction(t: Tables, a: int, b: int, side: str | None = None) -> PairReaction | None:
    """The reaction of a cell of element ``a`` touching one of ``b`` on ``side`` (one of :data:`SIDES`;
    None: the first side it reacts on), or None."""
    rows = [int(r) for r in t.react_group[t.react_pair[a, b]]]
    row = rows[SIDES.index(side)] if side is not None else next((r for r in rows if r), 0)
    if row == 0:
        return None
    into_a, into_b = (int(t.react_into_a[row]), int(t.react_into_b[row]))
    return PairReaction(int(t.react_chance[row]), a if into_a == STAYS else into_a, b if into_b == STAYS else into_b,
                        int(t.react_tsum_min[row]), int(t.react_tsum_max[row]), int(t.react_heat[row]),
                        int(t.react_push_a[row]), int(t.react_push_b[row]), int(t.react_holds_a[row]), int(t.react_holds_b[row]))


def reaction_rows(rows: Sequence[tuple]) -> dict[str, np.ndarray]:
    """The react_ tables (but react_pair and react_group) of these rows: (a becomes, b becomes, threshold,
    lowest and highest T sum, heat, a's push, b's push, a holds, b holds, whether it names a cell's
    memory) each, STAYS for a cell that stays, KEEPS for what a cell holds left as it is."""
    columns = list(zip(*rows))
    names_types = (("react_into_a", np.uint16), ("react_into_b", np.uint16), ("react_chance", np.uint32),
                   ("react_tsum_min", np.int32), ("react_tsum_max", np.int32), ("react_heat", np.int32),
                   ("react_push_a", np.int32), ("react_push_b", np.int32), ("react_holds_a", np.uint16),
                   ("react_holds_b", np.uint16), ("react_holds", np.uint8))
    return {name: np.array(column, kind) for (name, kind), column in zip(names_types, columns)}


def _report_tie(elements, pair, mod, number, held, into: list[Problem]) -> None:
    """Name two reactions that match ``pair`` as specifically, at one priority: an error within a mod,
    a warning between two (the later one's applies)."""
    earlier = held[1].source.problem(("reactions", held[2]), "")
    what = f"{elements[pair[0]].id} + {elements[pair[1]].id} also reacts differently at {earlier.file}:{earlier.line} ({earlier.path})"
    if held[1].name == mod.name:
        into.append(mod.source.problem(("reactions", number), f"{what}; make one selector more specific, or give one a higher priority"))
    else:
        into.append(mod.source.problem(("reactions", number), f"{what}, as specific and of the same priority: this one applies, "
                                       f"{mod.name} being loaded after {held[1].name} (a higher priority on one would say which)"))


def element_masks(pairs: np.ndarray) -> np.ndarray:
    """Per element ``a``, the bits (:func:`~sandmod.engine.layout.mask_bit`) of the elements ``b`` with
    ``pairs[a, b] > 0`` (those it reacts with, or may swap with): a cheap first test of a cell's
    neighbours, never missing a partner."""
    bits = np.zeros(pairs.shape[0], np.uint64)
    for b in np.flatnonzero((pairs > 0).any(axis=0)):
        bits[pairs[:, b] > 0] |= np.uint64(1) << np.uint64(mask_bit(int(b)))
    return bits.view(np.int64)


def _endless_reactions(winner: dict, elements: Sequence[ElementInfo]) -> list[Problem]:
    """Touching pairs that react into a pair that reacts back, and so on round, at any temperature,
    with cells that can never part: they change forever. A chain is left alone where a cell in it can
    move away (any archetype but static) or changes by itself (a lifetime), or where a reaction in
    it happens only in a range of temperatures narrower than every temperature there is."""
    every = (2 * temperature_units(MIN_TEMPERATURE), 2 * temperature_units(MAX_TEMPERATURE))

    def stuck(e: int) -> bool:
        return elements[e].spec.archetype == "static" and elements[e].spec.lifetime is None

    always = {
        pair: (first, second)
        for pair, (_, _, _, (first, second, _, low, high, *_), _) in winner.items()
        if low <= every[0] and high >= every[1] and (first, second) != pair and max(first, second) < REFERS
        and all(stuck(e) for e in (*pair, first, second))
    }
    problems: list[Problem] = []
    reported: set = set()
    for start in sorted(always):
        path, pair = [start], always[start]
        while pair in always and pair not in path and (pair[1], pair[0]) not in path:
            path.append(pair)
            pair = always[pair]
        if (pair in path or (pair[1], pair[0]) in path) and not reported & set(path):
            reported.update(path)
            reported.update((b, a) for a, b in path)  # the same contacts, seen from the other cell
            _, mod, number, *_ = winner[start]
            steps = " -> ".join(f"{elements[a].name} + {elements[b].name}" for a, b in [*path, pair])
            problems.append(
                mod.source.problem(
                    ("reactions", number),
                    f"these reactions never settle: {steps}; touching cells that cannot move would change forever "
                    "(give one of them a temperature range, a lifetime to an element in it, or end the chain)",
                )
            )
    return problems
