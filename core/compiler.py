"""Compile loaded mods into the dense tables the kernel reads.

Element ids are ``mod:element``. Numeric ids are given here, in a fixed order
(``base:empty`` is 0, then the ids sorted), and never written into files.
Reactions become an n x n interaction matrix (what each cell of a touching
pair becomes, and the chance per frame); densities and archetypes become a
displacement matrix (which element may swap into which).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field
from typing import NamedTuple, Sequence

import numpy as np

from .errors import Problem, ProblemsError
from .hashing import chance_threshold
from .modset import BASE_MOD, LoadedMod
from .modspec import EMPTY_ID, PARTICLE_ID, Element, Reaction
from .tomlsource import TomlSource

#: Archetype codes as the kernel knows them.
ARCHETYPE_CODES = {"empty": 0, "static": 1, "powder": 2, "liquid": 3, "gas": 4, "particle": 5}
#: Velocities are fixed-point: this many units make one cell per frame.
SUBCELL = 256
#: Most elements a ruleset may hold (palette renders use 256 colours).
MAX_ELEMENTS = 256


class Tables(NamedTuple):
    """Per-element parameters and pair matrices, indexed by numeric element id."""

    archetype: np.ndarray  # uint8[n]: ARCHETYPE_CODES
    fall_dir: np.ndarray  # int8[n]: +1 falls, -1 rises, 0 stays (particles fly by accel)
    accel: np.ndarray  # int32[n]: gravity along fall_dir (particles: downwards), SUBCELL units
    max_speed: np.ndarray  # int32[n]: terminal speed, SUBCELL units
    friction: np.ndarray  # int32[n]: friction coefficient, of 256: braking = friction * accel
    impact_share: np.ndarray  # int32[n]: share of landing speed turned sideways, of 256
    knock_chance: np.ndarray  # uint32[n]: roll threshold for a knock to loosen a resting grain
    drag_keep: np.ndarray  # int32[n]: particle speed kept per frame, of 256
    carries: np.ndarray  # uint16[n]: what a spawned particle element carries (0 = nothing)
    dispersion: np.ndarray  # uint8[n]: cells sideways per frame (liquids, gases)
    rest_chance: np.ndarray  # uint32[n]: roll threshold to rest a frame (viscosity)
    life_frames: np.ndarray  # uint16[n]: frames before decay, 0 = forever
    life_jitter: np.ndarray  # uint16[n]: extra frames, chosen per cell
    life_into: np.ndarray  # uint16[n]: what a cell decays into
    reactive: np.ndarray  # uint8[n]: 1 if any reaction involves the element
    displace: np.ndarray  # uint8[n, n]: a moving cell of a may swap with a cell of b
    react_chance: np.ndarray  # uint32[n, n]: roll threshold per frame of contact
    react_into_a: np.ndarray  # uint16[n, n]: what a becomes
    react_into_b: np.ndarray  # uint16[n, n]: what b becomes


@dataclass(frozen=True)
class ElementInfo:
    """One compiled element."""

    index: int
    id: str
    spec: Element
    source: TomlSource
    defined_by: str  # the mod whose definition is in force
    overrides: tuple[str, ...] = ()  # mods whose earlier definitions it replaced

    @property
    def mod(self) -> str:
        return self.id.split(":", 1)[0]

    @property
    def name(self) -> str:
        return self.id.split(":", 1)[1]


@dataclass(frozen=True)
class CompiledReaction:
    """A reaction with its selectors resolved, for listing."""

    mod: str
    spec: Reaction
    a: tuple[str, ...]
    b: tuple[str, ...]


@dataclass(frozen=True)
class Ruleset:
    """Everything the engine knows about the loaded elements."""

    mods: tuple[LoadedMod, ...]
    elements: tuple[ElementInfo, ...]
    reactions: tuple[CompiledReaction, ...]
    tables: Tables
    palette: bytes  # 768 bytes, 256 RGB triples
    color_lut: np.ndarray  # uint8[n, shades]: palette index per element and shade bucket
    _ids: dict[str, int] = field(default_factory=dict, repr=False)

    @property
    def particle(self) -> int:
        """The id of ``base:particle``, what launched cells fly as."""
        return self._ids[PARTICLE_ID]

    @property
    def shades(self) -> int:
        return self.color_lut.shape[1]

    def index(self, ref: str) -> int:
        """The numeric id of ``ref`` ('sand' or 'sand:sand'); KeyError with a message if unknown."""
        found, message = _resolve(ref, None, self._ids)
        if found is None:
            raise KeyError(message)
        return self._ids[found]


def compile_mods(mods: Sequence[LoadedMod]) -> Ruleset:
    """Compile mods (in load order) into a :class:`Ruleset`; ProblemsError lists every mistake."""
    problems: list[Problem] = []
    defs = _collect_elements(mods, problems)
    for required, archetype in ((EMPTY_ID, "empty"), (PARTICLE_ID, "particle")):
        found = defs.get(required)
        if found is None:
            problems.append(Problem("mods", None, "", f"no element '{required}' is defined"))
        elif found.spec.archetype != archetype:
            problems.append(found.source.problem(found.loc + ("archetype",), f"'{required}' must be '{archetype}'"))
    if problems:
        raise ProblemsError(problems)
    order = [EMPTY_ID] + sorted(i for i in defs if i != EMPTY_ID)
    if len(order) > MAX_ELEMENTS:
        raise ProblemsError([Problem("mods", None, "", f"{len(order)} elements loaded; at most {MAX_ELEMENTS}")])
    ids = {element_id: i for i, element_id in enumerate(order)}
    elements = tuple(
        ElementInfo(i, eid, defs[eid].spec, defs[eid].source, defs[eid].mod, tuple(defs[eid].replaced))
        for i, eid in enumerate(order)
    )
    by_mod = {m.name: m for m in mods}

    def resolve(ref: str, mod: LoadedMod, loc: tuple) -> int | None:
        found, message = _resolve(ref, mod.name, ids)
        if found is None:
            problems.append(mod.source.problem(loc, message))
            return None
        owner = found.split(":", 1)[0]
        if owner not in (mod.name, BASE_MOD) and owner not in mod.spec.mod.requires:
            problems.append(mod.source.problem(loc, f"'{found}' is from mod '{owner}'; add '{owner}' to mod.requires"))
            return None
        return ids[found]

    t = _empty_tables(len(order))
    for info in elements:
        d = defs[info.id]
        _fill_element(t, info, d, problems)
        if info.spec.lifetime is not None:
            into = resolve(info.spec.lifetime.becomes, by_mod[d.mod], d.loc + ("lifetime", "becomes"))
            if into is not None:
                t.life_frames[info.index] = info.spec.lifetime.frames
                t.life_jitter[info.index] = info.spec.lifetime.jitter
                t.life_into[info.index] = into
        carried = getattr(info.spec, "carries", None)
        if carried is not None:
            what = resolve(carried, by_mod[d.mod], d.loc + ("carries",))
            if what is not None and elements[what].spec.archetype == "particle":
                problems.append(d.source.problem(d.loc + ("carries",), f"a particle cannot carry a particle ('{elements[what].id}')"))
            elif what is not None:
                t.carries[info.index] = what
    _fill_displacement(t, elements)
    reactions = _compile_reactions(mods, elements, t, resolve, problems)
    if problems:
        raise ProblemsError(problems)
    palette, lut = _palette(elements)
    return Ruleset(tuple(mods), elements, reactions, t, palette, lut, ids)


def _fill_element(t: Tables, info: ElementInfo, d: "_Definition", problems: list[Problem]) -> None:
    """The per-element parameters of one element."""
    spec, i = info.spec, info.index
    t.archetype[i] = ARCHETYPE_CODES[spec.archetype]
    if spec.archetype == "empty" and info.id != EMPTY_ID:
        problems.append(d.source.problem(d.loc + ("archetype",), f"only '{EMPTY_ID}' may be 'empty'"))
    t.dispersion[i] = getattr(spec, "dispersion", 0)
    t.rest_chance[i] = chance_threshold(getattr(spec, "viscosity", 0.0))
    t.accel[i] = round(getattr(spec, "gravity", 0.0) * SUBCELL)
    t.max_speed[i] = round(getattr(spec, "max_speed", 1.0) * SUBCELL)
    t.friction[i] = round(getattr(spec, "friction", 0.0) * 256)
    t.impact_share[i] = round(getattr(spec, "impact_spread", 0.0) * 256)
    t.knock_chance[i] = chance_threshold(1.0 - getattr(spec, "inertial_resistance", 1.0))
    t.drag_keep[i] = round((1.0 - getattr(spec, "drag", 0.0)) * 256)


def _fill_displacement(t: Tables, elements: Sequence[ElementInfo]) -> None:
    """Which way movers fall (+1 falls, -1 rises) and who may swap into whom.

    Powders and liquids fall; gases rise, or fall if heavier than the air
    (``base:empty``'s density). A mover may swap with a fluid (empty, liquid,
    gas) lighter than itself when falling, denser when rising.
    """
    air = elements[0].spec.density
    densities = np.array([getattr(e.spec, "density", np.inf) for e in elements])
    for e in elements:
        kind = e.spec.archetype
        if kind in ("powder", "liquid") or (kind == "gas" and e.spec.density > air):
            t.fall_dir[e.index] = 1
        elif kind == "gas":
            t.fall_dir[e.index] = -1
    fluid = np.isin(t.archetype, [ARCHETYPE_CODES[a] for a in ("empty", "liquid", "gas")])
    for a in range(1, len(elements)):
        if t.fall_dir[a] != 0:
            lighter = densities < densities[a] if t.fall_dir[a] > 0 else densities > densities[a]
            t.displace[a] = fluid & lighter
            t.displace[a, a] = 0
            t.displace[a, 0] = 1  # every mover moves into empty cells


@dataclass
class _Definition:
    spec: Element
    source: TomlSource
    mod: str
    loc: tuple
    replaced: list[str] = field(default_factory=list)


def _collect_elements(mods: Sequence[LoadedMod], problems: list[Problem]) -> dict[str, _Definition]:
    defs: dict[str, _Definition] = {}
    for mod in mods:
        for key, spec in mod.spec.elements.items():
            loc = ("elements", key)
            element_id = key if ":" in key else f"{mod.name}:{key}"
            previous = defs.get(element_id)
            foreign = element_id.split(":", 1)[0] != mod.name
            if previous is None:
                if spec.override or foreign:
                    what = "nothing to override" if spec.override else "an element of another mod needs override = true"
                    problems.append(mod.source.problem(loc, f"'{element_id}' is not defined by any loaded mod ({what})"))
                    continue
                defs[element_id] = _Definition(spec, mod.source, mod.name, loc)
            elif not spec.override:
                problems.append(
                    mod.source.problem(
                        loc, f"'{element_id}' is already defined by {previous.source.name}; set override = true to replace it"
                    )
                )
            else:
                defs[element_id] = _Definition(spec, mod.source, mod.name, loc, previous.replaced + [previous.mod])
    return defs


def _resolve(ref: str, mod: str | None, ids: dict[str, int]) -> tuple[str | None, str]:
    """Resolve an element reference; returns (id, "") or (None, message)."""
    if ":" in ref:
        if ref in ids:
            return ref, ""
        candidates = list(ids)
    else:
        if mod is not None and f"{mod}:{ref}" in ids:
            return f"{mod}:{ref}", ""
        matches = [i for i in ids if i.split(":", 1)[1] == ref]
        if len(matches) == 1:
            return matches[0], ""
        if matches:
            return None, f"'{ref}' is ambiguous; write one of: {', '.join(sorted(matches))}"
        candidates = sorted({i.split(":", 1)[1] for i in ids})
    close = difflib.get_close_matches(ref, candidates, n=1)
    return None, f"unknown element '{ref}'" + (f" (did you mean '{close[0]}'?)" if close else "")


def _empty_tables(n: int) -> Tables:
    return Tables(
        archetype=np.zeros(n, np.uint8),
        fall_dir=np.zeros(n, np.int8),
        accel=np.zeros(n, np.int32),
        max_speed=np.zeros(n, np.int32),
        friction=np.zeros(n, np.int32),
        impact_share=np.zeros(n, np.int32),
        knock_chance=np.zeros(n, np.uint32),
        drag_keep=np.zeros(n, np.int32),
        carries=np.zeros(n, np.uint16),
        dispersion=np.zeros(n, np.uint8),
        rest_chance=np.zeros(n, np.uint32),
        life_frames=np.zeros(n, np.uint16),
        life_jitter=np.zeros(n, np.uint16),
        life_into=np.zeros(n, np.uint16),
        reactive=np.zeros(n, np.uint8),
        displace=np.zeros((n, n), np.uint8),
        react_chance=np.zeros((n, n), np.uint32),
        react_into_a=np.zeros((n, n), np.uint16),
        react_into_b=np.zeros((n, n), np.uint16),
    )


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


def _compile_reactions(mods, elements, t: Tables, resolve, problems) -> tuple[CompiledReaction, ...]:
    """Fill the interaction matrix; the more specific of two reactions on a pair wins."""
    # pair -> (score, mod, reaction number, (what a becomes, what b becomes, threshold))
    winner: dict[tuple[int, int], tuple[int, LoadedMod, int, tuple[int, int, int]]] = {}
    reported: set[tuple[str, int, str, int]] = set()  # conflicts already named, by both reactions
    compiled: list[CompiledReaction] = []

    def claim(pair, outcome, score, mod, number) -> None:
        held = winner.get(pair)
        if held is not None and (held[0] > score or (held[0] == score and held[3] == outcome)):
            return
        if held is not None and held[0] == score:
            conflict = (mod.name, number, held[1].name, held[2])
            if conflict not in reported:
                reported.add(conflict)
                earlier = held[1].source.problem(("reactions", held[2]), "")
                problems.append(
                    mod.source.problem(
                        ("reactions", number),
                        f"{elements[pair[0]].id} + {elements[pair[1]].id} also reacts differently at "
                        f"{earlier.file}:{earlier.line} ({earlier.path}); make one selector more specific",
                    )
                )
            return
        winner[pair] = (score, mod, number, outcome)

    for mod in mods:
        for number, reaction in enumerate(mod.spec.reactions):
            loc = ("reactions", number)
            side_a = _select(reaction.a, elements, lambda r: resolve(r, mod, loc + ("a",)))
            side_b = _select(reaction.b, elements, lambda r: resolve(r, mod, loc + ("b",)))
            into_a = None if reaction.a_becomes is None else resolve(reaction.a_becomes, mod, loc + ("a_becomes",))
            into_b = None if reaction.b_becomes is None else resolve(reaction.b_becomes, mod, loc + ("b_becomes",))
            if side_a is None or side_b is None or (reaction.a_becomes and into_a is None) or (reaction.b_becomes and into_b is None):
                continue
            (set_a, score_a), (set_b, score_b) = side_a, side_b
            threshold = chance_threshold(reaction.chance)
            for i in sorted(set_a):
                for j in sorted(set_b):
                    out_i = i if into_a is None else into_a
                    out_j = j if into_b is None else into_b
                    claim((i, j), (out_i, out_j, threshold), score_a + score_b, mod, number)
                    if i != j:  # the same contact, seen from the other cell
                        claim((j, i), (out_j, out_i, threshold), score_a + score_b, mod, number)
            compiled.append(
                CompiledReaction(
                    mod.name, reaction, tuple(elements[i].id for i in sorted(set_a)), tuple(elements[j].id for j in sorted(set_b))
                )
            )
    for pair, (_, _, _, (first, second, threshold)) in winner.items():
        t.react_into_a[pair], t.react_into_b[pair], t.react_chance[pair] = first, second, threshold
    t.reactive[:] = (t.react_chance > 0).any(axis=1)
    return tuple(compiled)


def _hex_rgb(color: str) -> tuple[int, int, int]:
    return int(color[1:3], 16), int(color[3:5], 16), int(color[5:7], 16)


def _palette(elements: Sequence[ElementInfo]) -> tuple[bytes, np.ndarray]:
    """One shared 256-colour palette: each element gets ``shades`` entries."""
    shades = max(1, min(8, 256 // len(elements)))
    palette = np.zeros((256, 3), np.uint8)
    lut = np.zeros((len(elements), shades), np.uint8)
    for info in elements:
        colors = [_hex_rgb(c) for c in info.spec.color]
        levels = -(-shades // len(colors))
        for j in range(shades):
            rgb = np.array(colors[j % len(colors)], float)
            v = ((j // len(colors)) + 0.5) / levels  # spread across (0, 1)
            factor = 1.0 + info.spec.shade * (2.0 * v - 1.0)
            entry = info.index * shades + j
            palette[entry] = np.clip(np.round(rgb * factor), 0, 255)
            lut[info.index, j] = entry
    return palette.tobytes(), lut
