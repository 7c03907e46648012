"""Compile loaded mods into the dense tables the kernel reads.

Element ids are ``mod:element``. Numeric ids are given here, in a fixed order
(``base:empty`` is 0, then those that most elements react with first, then by
id), and never written into files.
Reactions become rows (:mod:`.reactions`: what each cell of a touching pair
becomes, and the chance per frame) and an n x n table of which rows each
pair reads (2 bytes a pair); densities and archetypes become a displacement
matrix (which element may trade places with which, and how eagerly; 1 byte a
pair). At the most elements, 4,096, the two take 48 MB; at 500, under a
megabyte. Colours are :mod:`.colours`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, NamedTuple, Sequence

import numpy as np

from ..errors import Problem, ProblemsError
from ..engine.hashing import chance_threshold
from ..engine.layout import (  # noqa: F401  (names the other modules take from here too)
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
    CAP_ONE,
    COOLED,
    EXPLOSIVE,
    FLAMMABLE,
    HEATED,
    HELD,
    IGNITES,
    MAX_ELEMENTS,
    SIDES,
    NO_BREAK,
    NO_IMPACT,
    SUBCELL,
    TEMP_ONE,
    temperature_units,
)
from ..formats.behaviour import Behaviour
from ..registry import Registered
from .behaviours import Behaviours, compile_behaviours
from .colours import SCORCH_DARKEN, SCORCHED_SHADES, SHADES, Looks, colour_table  # noqa: F401  (names the other modules take from here too)
from .definitions import Definition, Override, collect_definitions, required_below, resolve_name
from .glow import GLOW_COLOURS, GLOW_FROM, GLOW_MIX, GLOW_STEP  # noqa: F401  (names the other modules take from here too)
from .modset import LoadedMod
from .neighbours import NeighbourTables, compile_neighbours
from .reactions import NO_REACTION, CompiledReaction, PairReaction, by_partners, compile_reactions, element_masks, pair_reaction, reaction_rows  # noqa: F401
from ..formats.modspec import EMPTY_ID, PARTICLE_ID, Element
from ..formats.tomlsource import TomlSource

_NO_LIMIT = 2**62


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
    life_into: np.ndarray  # uint16[n]: what a cell decays into; HELD: what it holds
    reactive: np.ndarray  # int64[n]: partner mask: bit b % 64 set when the element reacts with some b (0: none)
    displace: np.ndarray  # uint8[n, n]: chance (of ALWAYS) that a moving cell of a trades places with a cell of b; 0: never
    displaces: np.ndarray  # int64[n]: mask: bit b % 64 set when a may swap with some b (a first test, like reactive)
    react_pair: np.ndarray  # uint16[n, n]: the reactions (a row of react_group) of a cell of a touching one of b; 0: none
    react_group: np.ndarray  # uint16[g, 4]: per side the neighbour lies on (SIDES), its reaction: a row of the tables below; 0: none
    react_chance: np.ndarray  # uint32[r]: roll threshold per frame of contact (row 0, no reaction: 0)
    react_into_a: np.ndarray  # uint16[r]: what a becomes; STAYS: it stays as it is; from REFERS up: a cell of the pair
    react_into_b: np.ndarray  # uint16[r]: what b becomes; STAYS: it stays as it is
    react_tsum_min: np.ndarray  # int32[r]: lowest T_a + T_b (TEMP_ONE units) at which the pair reacts
    react_tsum_max: np.ndarray  # int32[r]: highest T_a + T_b
    react_heat: np.ndarray  # int32[r]: temperature added to a cell that changes, TEMP_ONE units
    react_push_a: np.ndarray  # int32[r]: a flies off, away from b, at this speed (SUBCELL units), as particle[0]; 0: it stays
    react_push_b: np.ndarray  # int32[r]: b flies off, away from a
    react_holds_a: np.ndarray  # uint16[r]: what a holds afterwards (an element, or a code from REFERS up); KEEPS: unchanged
    react_holds_b: np.ndarray  # uint16[r]: what b holds afterwards
    react_holds: np.ndarray  # uint8[r]: 1 where the row names what a cell holds or was (into_ or holds_ from REFERS up)
    remembers: np.ndarray  # uint8[n]: a cell of it can hold an element (State.carry): particles, and those rules give one
    movers_hold: np.ndarray  # uint8[1]: 1 where a powder, liquid or gas can hold: only then do moves but a particle's carry what cells hold
    shows_held: np.ndarray  # uint8[n]: a cell of it holding an element is drawn as that element (particles, shows_held)
    particle: np.ndarray  # uint16[1]: base:particle, what pushed cells fly as
    # Heat. A cell stores its heat energy, capacity x temperature.
    heat_cap: np.ndarray  # int64[n]: heat capacity, CAP_ONE units
    heat_recip: np.ndarray  # int64[n]: 2**32 / heat_cap, so that temperature = (energy * recip) >> 32
    conductance: np.ndarray  # int64[n]: conductivity x capacity / 4, in 1/256ths of CAP_ONE
    cooling: np.ndarray  # int64[n]: share of the gap to the air's temperature lost per frame, of 256
    temp_start: np.ndarray  # int32[n]: temperature of a new cell, TEMP_ONE units
    thermal: np.ndarray  # uint8[n]: HEATED | COOLED | FLAMMABLE | IGNITES | EXPLOSIVE
    hot_limit: np.ndarray  # int64[n]: energy above which it may become heated_into (past hot_limit + its share of hot_spread)
    heated_into: np.ndarray  # uint16[n]
    hot_spread: np.ndarray  # int64[n]: energy over which cells change, each past its own share (shade / 256)
    hot_latent: np.ndarray  # int64[n]: energy the change takes; -1: it keeps the temperature instead
    cold_limit: np.ndarray  # int64[n]: energy below which it may become cooled_into (past cold_limit - its share of cold_spread)
    cooled_into: np.ndarray  # uint16[n]
    cold_spread: np.ndarray  # int64[n]
    cold_latent: np.ndarray  # int64[n]: energy the change gives; -1: it keeps the temperature instead
    # Fire.
    ignite_limit: np.ndarray  # int64[n]: energy at or above which a flammable cell catches fire
    catch_chance: np.ndarray  # uint32[n]: roll threshold to catch from a touching flame
    burn_frames: np.ndarray  # uint16[n]
    burn_jitter: np.ndarray  # uint16[n]
    burn_limit: np.ndarray  # int64[n]: energy a burning cell heats itself up to
    burn_heat: np.ndarray  # int64[n]: energy a burning cell gains per frame
    flame: np.ndarray  # uint16[n]: what a burning cell gives off (0 = nothing)
    flame_chance: np.ndarray  # uint32[n]
    ash: np.ndarray  # uint16[n]: what a burnt-out cell leaves
    ash_chance: np.ndarray  # uint32[n]
    extinguishes: np.ndarray  # uint8[n]: puts out burning neighbours
    # Explosions.
    resistance: np.ndarray  # int64[n]: explosion resistance, 1/256ths
    blast: np.ndarray  # int64[n, BLAST_COLUMNS]: the element's explosion (radius 0: none)
    # Breaking.
    breaks_into: np.ndarray  # uint16[n]: what a cell becomes where a blast destroys it or a hard landing breaks it; NO_BREAK: none
    impact: np.ndarray  # int32[n]: landing speed (SUBCELL units, less the landed-on cell's) that breaks it, or sets it off; NO_IMPACT: none


@dataclass(frozen=True)
class ElementInfo:
    """One compiled element."""

    index: int
    id: str
    spec: Element
    source: TomlSource
    defined_by: str  # the mod whose definition is in force
    overrides: tuple[str, ...] = ()  # mods whose earlier definitions it replaced
    history: tuple[Override, ...] = ()  # each override, in load order: who changed what

    @property
    def origin(self) -> str:
        """The mod that first defined it."""
        return self.overrides[0] if self.overrides else self.defined_by

    @property
    def mod(self) -> str:
        return self.id.split(":", 1)[0]

    @property
    def name(self) -> str:
        return self.id.split(":", 1)[1]


@dataclass(frozen=True)
class Ruleset:
    """Everything the engine knows about the loaded elements."""

    #: The mods loaded, in load order.
    mods: tuple[LoadedMod, ...]
    #: Every element, by number (0 is ``base:empty``; :attr:`by_id` is by id).
    elements: tuple[ElementInfo, ...]
    #: Every reaction, compiled.
    reactions: tuple[CompiledReaction, ...]
    #: The per-element arrays the kernel reads.
    tables: Tables
    #: Every colour a cell can show, uint8 (colours, 3) RGB: what :attr:`looks` and frames index.
    colours: np.ndarray
    #: Colour indices per element: shades, scorched shades, glow levels.
    looks: "Looks"
    _ids: dict[str, int] = field(default_factory=dict, repr=False)
    #: What loads but may not be what the mods' authors meant: one field patched by two mods that do not require each other.
    warnings: tuple[Problem, ...] = ()
    #: The neighbour-count rules, compiled (None: the mods have none).
    neighbours: NeighbourTables | None = None
    #: The plugin behaviours its elements name; None when none does (its worlds never run them).
    behaviours: Behaviours | None = None

    @property
    def particle(self) -> int:
        """The id of ``base:particle``, what launched cells fly as."""
        return self._ids[PARTICLE_ID]

    @property
    def by_id(self) -> tuple[ElementInfo, ...]:
        """Every element, the empty cell first, then by id: the order to show them in."""
        return self.elements[:1] + tuple(sorted(self.elements[1:], key=lambda e: e.id))

    @property
    def shades(self) -> int:
        """How many colours each element's cells pick from (a cell keeps its pick as it moves)."""
        return self.looks.shades

    def swatch(self, element: int) -> tuple[int, int, int]:
        """The RGB colour that stands for ``element`` (its first shade), for menus and swatches."""
        return tuple(int(c) for c in self.colours[self.looks.normal[element, 0]])

    def index(self, ref: str, within: str | None = None, near: Sequence[str] = ()) -> int:
        """The numeric id of ``ref`` ('sand' or 'sand:sand'); KeyError with a message if unknown.

        With ``within`` (a mod's name), a bare name is looked up as that mod's
        own files would: its own elements first, then those of the mods in ``near``.
        """
        found, message = resolve_name(ref, within, self._ids, near)
        if found is None:
            raise KeyError(message)
        return self._ids[found]


def compile_mods(mods: Sequence[LoadedMod], behaviours: Mapping[str, Registered[Behaviour]] | None = None) -> Ruleset:
    """Compile mods (in load order) into a :class:`Ruleset`, with the plugins' ``behaviours`` (by full
    name) for elements to name; ProblemsError lists every mistake."""
    problems: list[Problem] = []
    warnings: list[Problem] = []
    defs = collect_definitions(mods, problems, warnings)
    for required, archetype in ((EMPTY_ID, "empty"), (PARTICLE_ID, "particle")):
        found = defs.get(required)
        if found is None:
            problems.append(Problem("mods", None, "", f"no element '{required}' is defined"))
        elif found.spec.archetype != archetype:
            problems.append(found.source.problem(found.loc + ("archetype",), f"'{required}' must be '{archetype}'"))
    if problems:
        raise ProblemsError(problems)
    if len(defs) > MAX_ELEMENTS:
        raise ProblemsError([Problem("mods", None, "", f"{len(defs)} elements loaded; at most {MAX_ELEMENTS}")])
    elements = _numbered(defs, [EMPTY_ID] + sorted(i for i in defs if i != EMPTY_ID))
    elements = _numbered(defs, [EMPTY_ID] + by_partners(mods, elements))
    ids = {e.id: e.index for e in elements}
    by_mod = {m.name: m for m in mods}

    below = required_below(mods)

    def resolve(ref: str, mod: LoadedMod, loc: tuple) -> int | None:
        found, message = resolve_name(ref, mod.name, ids, mod.requires)
        if found is None:
            problems.append(mod.source.problem(loc, message))
            return None
        owner = found.split(":", 1)[0]
        if owner != mod.name and owner not in below[mod.name]:  # a mod it requires, or one they require: loaded first
            problems.append(mod.source.problem(loc, f"'{found}' is from mod '{owner}'; add '{owner}' to mod.requires"))
            return None
        return ids[found]

    t = _empty_tables(len(elements))
    for info in elements:
        d = defs[info.id]
        _fill_element(t, info, d, problems)
        mod = by_mod[d.mod]
        if info.spec.lifetime is not None:
            held = info.spec.lifetime.becomes == "@held"
            into = HELD if held else resolve(info.spec.lifetime.becomes, mod, d.loc + ("lifetime", "becomes"))
            t.remembers[info.index] |= held
            if into is not None:
                t.life_frames[info.index] = info.spec.lifetime.frames
                t.life_jitter[info.index] = info.spec.lifetime.jitter
                t.life_into[info.index] = into
        named = lambda ref, *field: resolve(ref, mod, d.loc + field)  # noqa: E731
        _fill_heat(t, info, named)
        if info.index == 0 and any(getattr(info.spec, f) for f in ("heated", "cooled", "flammable", "ignites", "extinguishes")):
            problems.append(d.source.problem(d.loc, "the empty cell cannot change, burn, light or put out fires"))
        carried = getattr(info.spec, "carries", None)
        if carried is not None:
            what = resolve(carried, by_mod[d.mod], d.loc + ("carries",))
            if what is not None and elements[what].spec.archetype == "particle":
                problems.append(d.source.problem(d.loc + ("carries",), f"a particle cannot carry a particle ('{elements[what].id}')"))
            elif what is not None:
                t.carries[info.index] = what
        _fill_breaking(t, info, elements, named, lambda message: problems.append(d.source.problem(d.loc + ("breaks_into",), message)))
    _fill_displacement(t, elements)
    particles = [e.index for e in elements if e.spec.archetype == "particle"]
    t.remembers[particles] = t.shows_held[particles] = 1
    for info in elements:
        if info.spec.shows_held:
            t.remembers[info.index] = t.shows_held[info.index] = 1
    at = lambda i: defs[elements[i].id]  # noqa: E731  (the definition in force of element i)
    behaving = compile_behaviours(
        elements,
        behaviours or {},
        lambda i: lambda field, message: problems.append(at(i).source.problem(at(i).loc + field, message)),
        lambda i: lambda ref, *field: resolve(ref, by_mod[at(i).mod], at(i).loc + field),
    )
    reactions, t = compile_reactions(mods, elements, t, resolve, problems, warnings, below)
    neighbours = compile_neighbours(mods, elements, resolve)
    t = t._replace(particle=np.array([ids[PARTICLE_ID]], np.uint16))
    movers = np.isin(t.archetype, [ARCHETYPE_CODES[k] for k in ("powder", "liquid", "gas")])
    t.movers_hold[0] = (t.remembers[movers] != 0).any()
    problems.extend(_endless_phase_changes(t, elements, defs))
    if problems:
        raise ProblemsError(problems)
    colours, looks = colour_table(elements, t.heat_recip)
    return Ruleset(tuple(mods), elements, reactions, t, colours, looks, ids, tuple(warnings), neighbours=neighbours, behaviours=behaving)


def _numbered(defs: dict[str, "Definition"], order: Sequence[str]) -> tuple[ElementInfo, ...]:
    """The elements of ``defs``, numbered in ``order``."""
    return tuple(
        ElementInfo(i, eid, defs[eid].spec, defs[eid].source, defs[eid].mod, tuple(defs[eid].replaced), tuple(defs[eid].history))
        for i, eid in enumerate(order)
    )


def _fill_element(t: Tables, info: ElementInfo, d: "Definition", problems: list[Problem]) -> None:
    """The per-element parameters of one element."""
    spec, i = info.spec, info.index
    t.archetype[i] = ARCHETYPE_CODES[spec.archetype]
    if spec.archetype == "empty" and info.id != EMPTY_ID:
        problems.append(d.source.problem(d.loc + ("archetype",), f"only '{EMPTY_ID}' may be 'empty'"))
    t.dispersion[i] = getattr(spec, "dispersion", 0)
    t.rest_chance[i] = chance_threshold(getattr(spec, "viscosity", 0.0))
    t.accel[i] = round(abs(getattr(spec, "gravity", 0.0)) * SUBCELL)  # along fall_dir: a powder of negative gravity rises
    t.max_speed[i] = round(getattr(spec, "max_speed", 1.0) * SUBCELL)
    t.friction[i] = round(getattr(spec, "friction", 0.0) * 256)
    t.impact_share[i] = round(getattr(spec, "impact_spread", 0.0) * 256)
    t.knock_chance[i] = chance_threshold(1.0 - getattr(spec, "inertial_resistance", 1.0))
    t.drag_keep[i] = round((1.0 - getattr(spec, "drag", 0.0)) * 256)
    resistance = spec.explosion_resistance
    if resistance is None:
        resistance = DEFAULT_RESISTANCE[spec.archetype]
    t.resistance[i] = round(resistance * 256)


#: explosion_resistance when an element does not give one.
DEFAULT_RESISTANCE = {"empty": 0.0, "gas": 0.0, "particle": 0.0, "powder": 0.5, "liquid": 0.5, "static": 2.0}


def _phase_heat(change, cap: int) -> tuple[int, int]:
    """A phase change's spread and latent heat, in the kernel's energy units (-1: no latent heat)."""
    latent = -1 if change.latent_heat is None else round(change.latent_heat * TEMP_ONE * CAP_ONE)
    return cap * temperature_units(change.spread), latent


def _fill_heat(t: Tables, info: ElementInfo, resolve) -> None:
    """Heat, phase changes, fire and explosions of one element; ``resolve(ref, *field)`` names others."""
    spec, i = info.spec, info.index
    cap = max(1, round(spec.heat_capacity * CAP_ONE))
    t.heat_cap[i] = cap
    t.heat_recip[i] = (1 << 32) // cap + 1
    t.conductance[i] = round(spec.conductivity * cap * 64)  # x 256 / 4: each side of a pair moves < 1/4 of the gap
    t.cooling[i] = round(spec.cooling * 256)
    t.temp_start[i] = temperature_units(spec.temperature)
    if spec.heated is not None and (into := resolve(spec.heated.becomes, "heated", "becomes")) is not None:
        t.thermal[i] |= HEATED
        t.hot_limit[i] = cap * temperature_units(spec.heated.above)
        t.heated_into[i] = into
        t.hot_spread[i], t.hot_latent[i] = _phase_heat(spec.heated, cap)
    if spec.cooled is not None and (into := resolve(spec.cooled.becomes, "cooled", "becomes")) is not None:
        t.thermal[i] |= COOLED
        t.cold_limit[i] = cap * temperature_units(spec.cooled.below)
        t.cooled_into[i] = into
        t.cold_spread[i], t.cold_latent[i] = _phase_heat(spec.cooled, cap)
    if spec.ignites:
        t.thermal[i] |= IGNITES
    t.extinguishes[i] = spec.extinguishes
    fire = spec.flammable
    if fire is not None:
        t.thermal[i] |= FLAMMABLE
        t.ignite_limit[i] = cap * temperature_units(fire.ignites_at)
        t.catch_chance[i] = chance_threshold(fire.catch_chance)
        t.burn_frames[i], t.burn_jitter[i] = fire.burn_time, fire.burn_jitter
        t.burn_limit[i] = cap * temperature_units(fire.burn_temperature)
        t.burn_heat[i] = cap * temperature_units(fire.heat)
        if fire.flame is not None:
            t.flame[i] = resolve(fire.flame, "flammable", "flame") or 0
            t.flame_chance[i] = chance_threshold(fire.flame_chance)
        t.ash[i] = resolve(fire.leaves, "flammable", "leaves") or 0
        t.ash_chance[i] = chance_threshold(fire.leaves_chance)
    if spec.explosion is not None:
        t.thermal[i] |= EXPLOSIVE
        t.blast[i] = blast_row(spec.explosion, resolve(spec.explosion.leaves, "explosion", "leaves") or 0)


def _fill_breaking(t: Tables, info: ElementInfo, elements: Sequence[ElementInfo], resolve, problem) -> None:
    """What a cell of one element breaks into, and the landing speed that breaks it (or sets it off);
    ``resolve(ref, *field)`` names others, ``problem(message)`` reports one at ``breaks_into``."""
    spec, i = info.spec, info.index
    if spec.breaks_into is not None and (into := resolve(spec.breaks_into, "breaks_into")) is not None:
        if i == 0:
            problem("the empty cell cannot break")
        elif into == i:
            problem(f"'{info.id}' cannot break into itself")
        elif elements[into].spec.archetype == "particle":
            problem(f"an element cannot break into a particle ('{elements[into].id}')")
        else:
            t.breaks_into[i] = into
    if spec.breaks_on_impact is not None and (t.breaks_into[i] != NO_BREAK or t.thermal[i] & EXPLOSIVE):
        t.impact[i] = round(spec.breaks_on_impact * SUBCELL)


def blast_row(explosion, leaves: int, x: int = 0, y: int = 0) -> np.ndarray:
    """An explosion (a :class:`~sandmod.formats.modspec.Explosion`) as a row of the kernel's blast table."""
    row = np.zeros(BLAST_COLUMNS, np.int64)
    row[BLAST_X], row[BLAST_Y] = x, y
    row[BLAST_RADIUS] = explosion.radius
    row[BLAST_STRENGTH] = round(explosion.strength * 256)
    row[BLAST_LEAVES] = leaves
    row[BLAST_LEAVES_CHANCE] = chance_threshold(explosion.leaves_chance)
    row[BLAST_FLING] = chance_threshold(explosion.fling)
    row[BLAST_SPEED] = round(explosion.speed * SUBCELL)
    row[BLAST_HEAT] = -(2**31) if explosion.heat is None else temperature_units(explosion.heat)
    row[BLAST_SCORCH] = explosion.scorch
    return row


def _fill_displacement(t: Tables, elements: Sequence[ElementInfo]) -> None:
    """Which way movers fall (+1 falls, -1 rises) and who may trade places with whom, how eagerly.

    Powders and liquids fall (a powder of negative gravity rises); gases rise, or fall if heavier than the air
    (``base:empty``'s density). A mover may trade places with a fluid (liquid
    or gas) lighter than itself when falling, denser when rising, each frame
    by :func:`exchange_chance`, which grows with the gap in their densities.
    A liquid also sinks into a lighter powder, seeping down between its
    grains by that chance divided by one plus the powder's friction: mercury
    ends up under sand. Powders and liquids fall through the air (empty
    cells) freely; a gas at rest starts to rise (or sink) through it by the
    same chance, so that a cloud rises raggedly, not row by row.
    """
    air = elements[0].spec.density
    densities = np.array([getattr(e.spec, "density", np.inf) for e in elements])
    for e in elements:
        kind = e.spec.archetype
        if kind == "powder" and e.spec.gravity < 0:
            t.fall_dir[e.index] = -1
        elif kind in ("powder", "liquid") or (kind == "gas" and e.spec.density > air):
            t.fall_dir[e.index] = 1
        elif kind == "gas":
            t.fall_dir[e.index] = -1
    fluids = np.flatnonzero(np.isin(t.archetype, [ARCHETYPE_CODES[a] for a in ("liquid", "gas")]))
    powders = np.flatnonzero(t.archetype == ARCHETYPE_CODES["powder"])
    for a in range(1, len(elements)):
        if t.fall_dir[a] != 0:
            t.displace[a, fluids] = exchange_chance(densities[a], densities[fluids], int(t.fall_dir[a]))
            t.displace[a, a] = 0
            if t.archetype[a] == ARCHETYPE_CODES["liquid"]:
                seep = exchange_chance(densities[a], densities[powders], 1) / (1.0 + t.friction[powders] / 256)
                t.displace[a, powders] = np.where(seep > 0, np.maximum(1, np.round(seep)), 0)
            gas = t.archetype[a] == ARCHETYPE_CODES["gas"]
            t.displace[a, 0] = exchange_chance(densities[a], air, int(t.fall_dir[a]), INTO_AIR) if gas else ALWAYS
    t.displaces[:] = element_masks(t.displace)


#: Fluids trade places by a chance EAGERNESS times their densities' gap's share of the larger...
EAGERNESS = 2.5
#: ...at most SURE_ENOUGH (of ALWAYS, 0.94): never sure, so that blocks of cells that sink
#: together now and then wait a frame, and no comb of alternating rows forms.
SURE_ENOUGH = 240
#: A gas at rest starts to rise (sink) through the air by a chance INTO_AIR times the gap's share,
#: each cell by a roll of its own: a cloud rises raggedly, not row by row.
INTO_AIR = (1.5, ALWAYS)


def exchange_chance(mover: float, other, fall_dir: int, eagerness: tuple[float, int] = (EAGERNESS, SURE_ENOUGH)):
    """The chance (of ALWAYS) that a mover of density ``mover`` falling (+1) or rising (-1)
    trades places with a fluid of density ``other`` (or each of an array of them) in a frame, rolled once per plume block
    (see :data:`sandmod.engine.layout.PLUME`): ``eagerness`` (a factor and a most) times the
    gap's share of the larger density, at least 1; 0 where it cannot.

    Sand (1600) into water (1000): 0.94; water into oil (850): 0.38; steam (0.6) through the
    air (1.2), with INTO_AIR: 0.75.
    """
    other = np.asarray(other, float)
    gap = (mover - other) * fall_dir
    factor, most = eagerness
    with np.errstate(divide="ignore", invalid="ignore"):
        chance = np.where(gap > 0, np.clip(np.round(factor * ALWAYS * gap / np.maximum(mover, other)), 1, most), 0).astype(np.int64)
    return chance if chance.ndim else int(chance)


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
        remembers=np.zeros(n, np.uint8),
        movers_hold=np.zeros(1, np.uint8),
        shows_held=np.zeros(n, np.uint8),
        reactive=np.zeros(n, np.int64),
        displace=np.zeros((n, n), np.uint8),
        displaces=np.zeros(n, np.int64),
        react_pair=np.zeros((n, n), np.uint16),
        react_group=np.zeros((1, len(SIDES)), np.uint16),
        particle=np.zeros(1, np.uint16),
        **reaction_rows([NO_REACTION]),
        heat_cap=np.ones(n, np.int64),
        heat_recip=np.ones(n, np.int64),
        conductance=np.zeros(n, np.int64),
        cooling=np.zeros(n, np.int64),
        temp_start=np.zeros(n, np.int32),
        thermal=np.zeros(n, np.uint8),
        hot_limit=np.full(n, _NO_LIMIT, np.int64),
        heated_into=np.zeros(n, np.uint16),
        hot_spread=np.zeros(n, np.int64),
        hot_latent=np.full(n, -1, np.int64),
        cold_limit=np.full(n, -_NO_LIMIT, np.int64),
        cooled_into=np.zeros(n, np.uint16),
        cold_spread=np.zeros(n, np.int64),
        cold_latent=np.full(n, -1, np.int64),
        ignite_limit=np.full(n, _NO_LIMIT, np.int64),
        catch_chance=np.zeros(n, np.uint32),
        burn_frames=np.zeros(n, np.uint16),
        burn_jitter=np.zeros(n, np.uint16),
        burn_limit=np.zeros(n, np.int64),
        burn_heat=np.zeros(n, np.int64),
        flame=np.zeros(n, np.uint16),
        flame_chance=np.zeros(n, np.uint32),
        ash=np.zeros(n, np.uint16),
        ash_chance=np.zeros(n, np.uint32),
        extinguishes=np.zeros(n, np.uint8),
        resistance=np.zeros(n, np.int64),
        blast=np.zeros((n, BLAST_COLUMNS), np.int64),
        breaks_into=np.full(n, NO_BREAK, np.uint16),
        impact=np.full(n, NO_IMPACT, np.int32),
    )


def _endless_phase_changes(t: Tables, elements: Sequence[ElementInfo], defs: dict[str, "Definition"]) -> list[Problem]:
    """An element that turns into another when heated, which turns back when cooled, above the first's limit."""
    problems: list[Problem] = []
    for info in elements:
        other = int(t.heated_into[info.index])
        if not (t.thermal[info.index] & HEATED and t.thermal[other] & COOLED and t.cooled_into[other] == info.index):
            continue
        above, below = info.spec.heated.above, elements[other].spec.cooled.below
        if below > above:
            d, other_name = defs[info.id], elements[other].name
            problems.append(
                d.source.problem(
                    d.loc + ("heated", "above"),
                    f"{info.name} turns into {other_name} above {above:g} degrees, but {other_name} turns back "
                    f"below {below:g}: between the two it would change every frame; "
                    f"make {other_name}'s cooled.below at most {above:g}",
                )
            )
    return problems

