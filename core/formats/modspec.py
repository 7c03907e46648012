"""The mod format: pydantic models that validate a mod file and document it.

A mod is one TOML file::

    [mod]
    name = "lava"
    version = "1.0.0"
    requires = ["water"]

    [elements.lava]
    archetype = "liquid"
    color = ["#ff6a00", "#ff9a1f"]
    density = 3100
    dispersion = 1
    viscosity = 0.7

    [[reactions]]
    a = "lava"
    b = "water"
    a_becomes = "stone"
    b_becomes = "steam"
    chance = 0.5

Each element picks an ``archetype``; each archetype accepts only its own
parameters. Element names, tags and mod names are lower-case identifiers.
"""

from __future__ import annotations

import re
import textwrap
from typing import Annotated, Literal, Union

from packaging.specifiers import InvalidSpecifier, SpecifierSet
from packaging.version import InvalidVersion, Version
from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, PrivateAttr, field_validator, model_validator
from pydantic_core import PydanticCustomError

from ..engine.layout import ARCHETYPES, MAX_SPEED, MAX_TEMPERATURE, MIN_TEMPERATURE  # noqa: F401  (taken from here too)
from .behaviour import FULL_NAME as BEHAVIOUR_NAME
from .validation import PATTERN_HINTS

NAME = r"[a-z][a-z0-9_]*"
MOD_NAME = r"[a-z][a-z0-9_-]*"
ELEMENT_REF = rf"(?:{MOD_NAME}:)?{NAME}"
SELECTOR = rf"!?(?:\*|#{NAME}|{ELEMENT_REF})"

ElementName = Annotated[str, Field(pattern=rf"^{ELEMENT_REF}$")]
#: What a reaction's cell becomes or holds: an element, or what one of the pair was ('@a', '@b') or held ('@a.held').
CELL_REF = r"@[ab](?:\.held)?"
Product = Annotated[str, Field(pattern=rf"^(?:{ELEMENT_REF}|{CELL_REF})$")]
ModName = Annotated[str, Field(pattern=rf"^{MOD_NAME}$")]
Tag = Annotated[str, Field(pattern=rf"^{NAME}$")]
HexColor = Annotated[
    str,
    Field(pattern=r"^#[0-9a-fA-F]{6}$", description="A colour as #rrggbb."),
]

#: The menu section (in ``sandmod play``) of an element that names no ``category``: by its archetype.
ARCHETYPE_CATEGORIES = {"empty": "empty", "static": "solids", "powder": "powders", "liquid": "liquids", "gas": "gases", "particle": "particles"}
_CATEGORY = (
    "Which section of the element menu in 'sandmod play' shows it: a lower-case name ('explosives', 'life'); "
    "without it, by its archetype: " + ", ".join(f"{a} '{c}'" for a, c in ARCHETYPE_CATEGORIES.items() if a != "empty") + "."
)

EMPTY_ID = "base:empty"
#: The particle element a launched cell becomes (it carries the cell's element).
PARTICLE_ID = "base:particle"
#: Largest explosion radius, in cells.
MAX_BLAST_RADIUS = 32


_REQUIREMENT = re.compile(rf"\s*({MOD_NAME})\s*(.*?)\s*")  # a mod's name, then its version range


def _requirement(text: str) -> str:
    """A mod's name and an optional version range in the standard (PEP 440) spelling: 'water',
    'water>=2.0,<3', 'water~=2.1', 'water==2.*'."""
    found = _REQUIREMENT.fullmatch(text)
    if found is None:
        raise ValueError(f"must be a mod name, maybe with versions: 'water' or 'water>=2.0,<3' (got {text!r})")
    try:
        SpecifierSet(found.group(2))
    except InvalidSpecifier:
        raise ValueError(f"{found.group(2)!r} is not a version range like '>=2.0,<3', '~=2.1' or '==2.*'") from None
    return text


def _version(text: str) -> str:
    try:
        Version(text)
    except InvalidVersion:
        raise ValueError(f"must be a version like '1.2.0' or '2.0.0rc1' (got {text!r})") from None
    return text


Requirement = Annotated[str, AfterValidator(_requirement)]


def version_matches(version: str, versions: SpecifierSet) -> bool:
    """Whether ``version`` lies in the range ``versions``: as pip decides, so a pre-release
    (2.0.0rc1) meets only a range that names a pre-release."""
    return versions.contains(Version(version))


def _as_list(value: object) -> object:
    return [value] if isinstance(value, str) else value


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ModInfo(_Strict):
    """The ``[mod]`` table: who this mod is and what it builds on."""

    name: ModName = Field(description="The mod's name; element ids inside it are 'NAME:element'.", examples=["snow"])
    version: Annotated[str, AfterValidator(_version)] = Field(
        "0.1.0", description="The mod's version, e.g. '1.2.0' (the standard, PEP 440: '2.0.0rc1' is a pre-release)."
    )
    description: str = Field("", max_length=2000, description="One or two sentences for 'sandmod list'.", examples=["Snow: light white flakes that pile up steeply."])
    requires: list[Requirement] = Field(
        default_factory=list,
        description="Mods whose elements this mod names, loaded first; a version range may follow "
        "the name, as pip writes them: 'water>=2.0,<3', 'water~=2.1', 'water==2.*'.",
    )

    def requirements(self) -> list[tuple[str, SpecifierSet]]:
        """``requires`` parsed: each mod's name and the range of its versions that will do."""
        parsed = []
        for text in self.requires:
            found = _REQUIREMENT.fullmatch(text)
            parsed.append((found.group(1), SpecifierSet(found.group(2))))
        return parsed

    @property
    def required_names(self) -> list[str]:
        return [name for name, _ in self.requirements()]


class Lifetime(_Strict):
    """After ``frames`` frames (plus up to ``jitter`` more) a cell becomes another element."""

    frames: int = Field(ge=1, le=60000, description="Frames a cell lives before it turns into 'becomes'.", examples=[120])
    jitter: int = Field(0, ge=0, le=5000, description="Up to this many extra frames, chosen per cell.")
    becomes: Annotated[str, Field(pattern=rf"^(?:{ELEMENT_REF}|@held)$")] = Field(
        description="The element a cell turns into when its time is up; '@held': what the cell holds (a spark gives back "
        "the metal it ran in), nothing if it holds nothing.",
        examples=["ash", "@held"],
    )


Temperature = Annotated[float, Field(ge=MIN_TEMPERATURE, le=MAX_TEMPERATURE)]


_LATENT = (
    "Heat the change takes from the cell (gives it, when cooled), in degrees times heat capacity: with it the "
    "change keeps the cell's heat, less (plus) this, and the new element's temperature follows from its own heat "
    "capacity; without it the change keeps the temperature. Water boiling into steam takes it, steam condensing "
    "gives it back, so neither flickers at the boiling point."
)
_SPREAD = (
    "Degrees past the point over which the change grows likely: a cell past the point changes each frame by a "
    "chance that grows with how far past it is, up to one half at the spread's end, rolled for small blocks of "
    "cells together, so that a layer heated evenly boils in bubbles, not as one sheet. 0: at once."
)


class Heated(_Strict):
    """Hotter than ``above`` degrees, the element turns into another, keeping its temperature (or, with a
    ``latent_heat``, its heat less that)."""

    above: Temperature = Field(description="Degrees Celsius; hotter than this, it changes.")
    becomes: ElementName = Field(description="The element it turns into (water: 'steam').")
    latent_heat: float | None = Field(None, ge=0.0, le=1e6, description=_LATENT)
    spread: float = Field(0.0, ge=0.0, le=1000.0, description=_SPREAD, examples=[10])


class Cooled(_Strict):
    """Colder than ``below`` degrees, the element turns into another, keeping its temperature (or, with a
    ``latent_heat``, its heat plus that)."""

    below: Temperature = Field(description="Degrees Celsius; colder than this, it changes.")
    becomes: ElementName = Field(description="The element it turns into (lava: 'basalt').")
    latent_heat: float | None = Field(None, ge=0.0, le=1e6, description=_LATENT)
    spread: float = Field(0.0, ge=0.0, le=1000.0, description=_SPREAD, examples=[20])


class Melts(BaseModel):
    """The element's molten form, made from it (as Sandboxels' generated forms are): ``molten_NAME``,
    a liquid with the element's fields that a liquid has, its colours glowing, 100 degrees above the
    point when placed; the element melts into it above ``above`` and it sets back below. Any element
    field given here too replaces the one the form would get (``density``, ``color``, ...)."""

    model_config = ConfigDict(extra="allow", frozen=True)

    above: Temperature = Field(description="Degrees Celsius; hotter than this, the element melts.", examples=[1538])


class Freezes(BaseModel):
    """The element's frozen form, made from it: ``frozen_NAME``, a static solid with the element's fields
    that one has, its colours paler, 20 degrees below the point when placed; the element freezes into it
    below ``below`` and it thaws back above. Any element field given here too replaces the one it would get."""

    model_config = ConfigDict(extra="allow", frozen=True)

    below: Temperature = Field(description="Degrees Celsius; colder than this, the element freezes.", examples=[-10])


class Flammable(_Strict):
    """How an element catches fire and burns (or, with an ``explosion``, blows up)."""

    ignites_at: Temperature = Field(description="It catches fire at or above this temperature, in degrees Celsius.")
    catch_chance: float = Field(
        0.05, ge=0.0, le=1.0, description="Chance per frame that a touching flame (fire, lava, a burning cell) lights it."
    )
    burn_time: int = Field(120, ge=1, le=60000, description="Frames it burns before it is used up.")
    burn_jitter: int = Field(0, ge=0, le=5000, description="Up to this many extra frames of burning, chosen per cell.")
    burn_temperature: Temperature = Field(
        700.0, description="While burning it heats itself by 'heat' degrees a frame up to this temperature."
    )
    heat: float = Field(20.0, ge=0.0, le=1000.0, description="Degrees a burning cell gains each frame (up to burn_temperature).", examples=[30])
    flame: ElementName | None = Field(
        None, description="What a burning cell gives off into the empty cells it touches, e.g. 'fire'."
    )
    flame_chance: float = Field(0.2, ge=0.0, le=1.0, description="Chance per frame of giving off a flame into an empty neighbour.")
    leaves: ElementName = Field(EMPTY_ID, description="What a burnt-out cell becomes, e.g. 'ash' (default: nothing).", examples=["ash"])
    leaves_chance: float = Field(1.0, ge=0.0, le=1.0, description="Chance that a burnt-out cell leaves that (else nothing).", examples=[0.5])

    @model_validator(mode="after")
    def _heats_to_burn(self) -> "Flammable":
        if self.burn_temperature < self.ignites_at:
            raise ValueError("burn_temperature must be at least ignites_at, or the fire would go out at once")
        return self


class Explosion(_Strict):
    """A blast: rays from the centre destroy what they can afford to, out to ``radius``.

    Each ray starts with ``strength`` and pays every cell's
    ``explosion_resistance`` (per cell of length) to destroy it; a cell that
    resists more than the ray has left stops the ray. Past the destruction a
    fringe of ``scorch`` cells is darkened, less and less often.
    """

    radius: int = Field(ge=1, le=MAX_BLAST_RADIUS, description=f"Reach in cells (1 to {MAX_BLAST_RADIUS}).")
    strength: float = Field(gt=0.0, le=100000.0, description="What a ray can spend on destroying cells (stone resists 2 a cell).")
    leaves: ElementName = Field(EMPTY_ID, description="What destroyed cells become, e.g. 'fire' for a flash (default: nothing).", examples=["fire"])
    leaves_chance: float = Field(1.0, ge=0.0, le=1.0, description="Chance that a destroyed cell becomes 'leaves' (else nothing).", examples=[0.3])
    fling: float = Field(0.5, ge=0.0, le=1.0, description="Share of destroyed powder and liquid cells that fly off as particles.", examples=[0.8])
    speed: float = Field(6.0, gt=0.0, le=MAX_SPEED, description="Speed of flung cells, in cells per frame, at the centre.", examples=[10])
    heat: Temperature | None = Field(
        None, description="Destroyed and scorched cells are heated to at least this temperature (may light what is near).",
        examples=[800],
    )
    scorch: int = Field(3, ge=0, le=MAX_BLAST_RADIUS, description="Width in cells of the darkened fringe past the destruction.", examples=[5])


class _ElementBase(_Strict):
    description: str = Field("", max_length=2000, description="What the element is, for 'sandmod list'.", examples=["Falls in flakes and piles up steeply."])
    color: Annotated[list[HexColor], BeforeValidator(_as_list)] = Field(
        description="Display colour ('#rrggbb'), or a list of up to 8 that each cell picks one of.",
        json_schema_extra={"anyOf": [{"type": "string"}, {"type": "array"}]},
    )
    shade: float = Field(
        0.06,
        ge=0.0,
        le=0.5,
        description="Per-cell brightness variation (0 = flat colour, 0.5 = very grainy).",
    )
    tags: list[Tag] = Field(default_factory=list, description="Tags that reaction selectors ('#tag') match.")
    category: Tag | None = Field(None, description=_CATEGORY, examples=["explosives"])
    hidden: bool = Field(
        False,
        description="Leave it out of the element menu in 'sandmod play' (a search there still finds it): for intermediate forms a player need not paint.",
        examples=[True],
    )
    lifetime: Lifetime | None = Field(None, description="Turn into another element after a while.")
    shows_held: bool = Field(
        False,
        description="Drawn in the colours of the element each cell holds (see the reactions how-to, \"Cells that "
        "remember\"), its own where it holds nothing: a dye's stain, a clone showing what it copies.",
        examples=[True],
    )
    override: bool = Field(
        False,
        description="Set to replace an element another mod defines (the key is then 'mod:element').",
    )
    like: ElementName | None = Field(
        None,
        description="Start from this element's fields ('sand', or another mod's as 'mod:name', defined before): "
        "those given here replace them; the archetype may be left out.",
        examples=["sand:sand"],
    )
    temperature: Temperature = Field(20.0, description="Temperature of a newly placed cell, in degrees Celsius.", examples=[-5])
    heat_capacity: float = Field(
        1.0, ge=0.05, le=10.0, description="Heat it takes to warm a cell by one degree, relative to stone (water 4)."
    )
    conductivity: float = Field(
        0.2, ge=0.0, le=1.0, description="How fast heat passes through it: 0 insulates, 1 evens out fastest."
    )
    cooling: float = Field(
        0.0, ge=0.0, le=0.5, description="Share of its difference from the air's temperature lost each frame (heat leaving the world)."
    )
    heated: Heated | None = Field(None, description="What it becomes above a temperature (water boils to steam).")
    cooled: Cooled | None = Field(None, description="What it becomes below a temperature (lava sets into basalt).")
    melts: Melts | None = Field(None, description="Make its molten form too, and melt into it (instead of 'heated').", examples=[{"above": 1538}])
    freezes: Freezes | None = Field(None, description="Make its frozen form too, and freeze into it (instead of 'cooled').", examples=[{"below": 0}])
    flammable: Flammable | None = Field(None, description="How it catches fire and burns.")
    explosion: Explosion | None = Field(
        None, description="It explodes instead of burning when lit or hot (needs 'flammable' to say when)."
    )
    explosion_resistance: float | None = Field(
        None,
        ge=0.0,
        le=1e6,
        description="What a blast ray must spend to destroy a cell; more than the ray has left stops it. "
        "Default: 0 for empty, gases and particles, 0.5 for powders and liquids, 2 for static solids.",
    )
    breaks_into: ElementName | None = Field(
        None,
        description="What a cell of it becomes when it breaks: where a blast would destroy it, it is left as this "
        "instead (flung, if a powder or liquid, as destroyed cells are), and so where it lands, or is landed on, at "
        "'breaks_on_impact'. Stone breaks into 'rubble', glass into 'shards'. Without it, a blast destroys the cell.",
        examples=["shards"],
    )
    breaks_on_impact: float | None = Field(
        None,
        gt=0.0,
        le=MAX_SPEED,
        description="A landing speed in cells per frame: a cell of it that lands this fast or faster on what it cannot "
        "sink into (or on the world's edge), or that a moving cell lands on this hard (less the speed it falls at "
        "itself), breaks into 'breaks_into', or, an explosive, goes off. A fall from rest at gravity 0.2 reaches 2.5 "
        "after about 20 cells, 3 after about 26 (nitroglycerin: 2.5; glass: 3). Without it, no landing breaks it.",
        examples=[3],
    )
    ignites: bool = Field(False, description="It lights flammable cells it touches (fire, lava).")
    extinguishes: bool = Field(False, description="It puts out burning cells it touches (water).")
    behaviour: str | None = Field(
        None,
        pattern=BEHAVIOUR_NAME,
        description="A compiled per-cell behaviour a plugin gives (its 'register_behaviours' hook), as 'PLUGIN:name': "
        "run once a frame for each cell of the element, after the kernel's step, for what data cannot say "
        "(a vine that branches, an ant that digs). An unknown name is a mistake that names those installed.",
        examples=["garden:grow"],
    )
    behaviour_args: dict[Annotated[str, Field(pattern=rf"^{NAME}$")], float | bool | str] = Field(
        default_factory=dict,
        description="The behaviour's arguments, by the names its plugin declares: numbers, true or false, or "
        "element names (each read by the behaviour as the element's id).",
        examples=[{"into": "vine", "chance": 0.05}],
    )

    @model_validator(mode="after")
    def _consistent_heat(self):
        if self.heated is not None and self.cooled is not None and self.cooled.below >= self.heated.above:
            raise ValueError("cooled.below must be colder than heated.above")
        if (self.melts is not None and self.heated is not None) or (self.freezes is not None and self.cooled is not None):
            raise ValueError("give 'melts' or 'heated', 'freezes' or 'cooled': not both")
        if self.explosion is not None and self.flammable is None:
            raise ValueError("an explosive element needs 'flammable' (ignites_at, catch_chance) to say when it goes off")
        return self

    @field_validator("breaks_on_impact")
    @classmethod
    def _breaks_into_something(cls, value: float | None, info) -> float | None:
        if value is not None and info.data.get("breaks_into") is None and info.data.get("explosion") is None:
            raise ValueError("an element that breaks on impact needs 'breaks_into' (what it breaks into) or an 'explosion' (it goes off)")
        return value

    @property
    def menu_category(self) -> str:
        """The menu section it is shown in: its ``category``, else its archetype's."""
        return self.category or ARCHETYPE_CATEGORIES[self.archetype]

    @field_validator("color")
    @classmethod
    def _one_to_eight_colors(cls, value: list[str]) -> list[str]:
        if not 1 <= len(value) <= 8:
            raise ValueError("give between 1 and 8 colours")
        return value


_DENSITY = Field(
    gt=0,
    le=100000,
    description="Mass per volume in kg/m3 (air 1.2, water 1000, sand 1600); heavier sinks through lighter.",
)
_DISPERSION = Field(
    ge=1,
    le=16,
    description="How many cells sideways the element may flow in one frame.",
)


def _gravity(default: float, ge: float = 0.0, also: str = "", **more) -> object:
    return Field(
        default,
        **more,
        ge=ge,
        le=2.0,
        description=f"Acceleration while falling (gases: while rising), in cells per frame per frame{also}.",
    )


def _max_speed(default: float, **more) -> object:
    return Field(
        default,
        **more,
        ge=1.0,
        le=MAX_SPEED,
        description=f"Terminal speed in cells per frame (1 to {MAX_SPEED}); a mover always goes at least 1.",
    )


class EmptyElement(_ElementBase):
    """The void between things (only ``base:empty``); its density is the air's."""

    archetype: Literal["empty"]
    density: float = Field(1.2, gt=0, le=100000, description="Density of the air, for what rises and sinks.")


class StaticElement(_ElementBase):
    """A solid that never moves: walls, stone, metal."""

    archetype: Literal["static"]


class PowderElement(_ElementBase):
    """Falls faster and faster, slides off slopes, piles up and sinks through lighter fluids.

    A grain that lands turns part of its speed into sideways speed, which
    ``friction`` wears down on every frame of contact. A grain that came to
    rest stays put until the cell below empties or a moving neighbour knocks
    it loose, which ``inertial_resistance`` makes less likely.
    """

    archetype: Literal["powder"]
    density: float = _DENSITY
    gravity: float = _gravity(0.2, ge=-2.0, also="; negative: it falls upwards and piles on ceilings", examples=[0.1])
    max_speed: float = _max_speed(8.0, examples=[4])
    friction: float = Field(
        0.6,
        ge=0.0,
        le=4.0,
        description=(
            "Friction coefficient: each frame on the ground a grain loses friction x gravity of sideways speed "
            "(rolling down a step gains gravity), so piles settle at or a little below atan(friction), "
            "never above 45 degrees: sand (0.6) about 32, coal (1.6) about 41."
        ),
    )
    impact_spread: float = Field(
        0.25,
        ge=0.0,
        le=1.0,
        description="Share of its landing speed a grain turns into sideways speed (0 = lands dead, 1 = all of it).",
        examples=[0.5],
    )
    inertial_resistance: float = Field(
        0.1,
        ge=0.0,
        le=1.0,
        description="Chance that a resting grain stays put when a moving neighbour knocks it (1 = never crumbles).",
    )


class LiquidElement(_ElementBase):
    """Falls faster and faster, then flows sideways up to ``dispersion`` cells a frame."""

    archetype: Literal["liquid"]
    density: float = _DENSITY
    dispersion: int = _DISPERSION
    viscosity: float = Field(
        0.0,
        ge=0.0,
        lt=1.0,
        description="Chance per frame that the liquid does not flow (0 = runny, 0.9 = treacle); it still falls.",
    )
    gravity: float = _gravity(0.2, examples=[0.3])
    max_speed: float = _max_speed(8.0, examples=[6])


class GasElement(_ElementBase):
    """Rises through denser fluids (or sinks, if heavier than air) and spreads sideways."""

    archetype: Literal["gas"]
    density: float = _DENSITY
    dispersion: int = _DISPERSION
    gravity: float = _gravity(0.02, examples=[0.05])
    max_speed: float = _max_speed(2.0, examples=[3])


class ParticleElement(_ElementBase):
    """A free-flying cell: it moves by its velocity through empty cells only, and when
    it hits anything it puts down the element it carries where it stopped (or vanishes,
    carrying nothing). Launched cells and world sprays fly as particles."""

    archetype: Literal["particle"]
    gravity: float = Field(
        0.15,
        ge=-2.0,
        le=2.0,
        description="Downward acceleration in cells per frame per frame (negative: it rises, like embers).",
    )
    max_speed: float = _max_speed(float(MAX_SPEED), examples=[12])
    drag: float = Field(0.0, ge=0.0, le=0.5, description="Share of its speed a particle loses per frame in flight.", examples=[0.05])
    carries: ElementName | None = Field(
        None, description="What a spawned particle of this element carries and puts down (nothing if left out).",
        examples=["sand"],
    )


Element = Annotated[
    Union[EmptyElement, StaticElement, PowderElement, LiquidElement, GasElement, ParticleElement],
    Field(discriminator="archetype"),
]


class PatchedElement(BaseModel):
    """An element with a patch applied, checked whole (see :func:`.validation.validate_changed`)."""

    element: Element


class Reaction(_Strict):
    """When a cell matching ``a`` touches one matching ``b``, they may turn into other elements.

    Selectors: an element (``water``, ``base:stone``), a tag (``#metal``), any
    non-empty element (``*``), or a negation of one of those (``!#acid_proof``).
    """

    a: str = Field(pattern=rf"^{SELECTOR}$", description="Selector for the first cell.")
    b: str = Field(pattern=rf"^{SELECTOR}$", description="Selector for the neighbouring cell.")
    a_becomes: Product | None = Field(
        None, description="What the first cell becomes (unchanged if left out): an element, or '@b' (what the second cell "
        "was), '@a.held' or '@b.held' (what the first or second cell holds; nothing if it holds nothing).",
        examples=["fire", "@b.held"],
    )
    b_becomes: Product | None = Field(
        None, description="What the second cell becomes (unchanged if left out); as 'a_becomes' ('@a': what the first was).",
        examples=["@a.held"],
    )
    a_holds: Product | None = Field(
        None, description="What the first cell holds afterwards (unchanged if left out): an element ('empty': nothing), "
        "'@a' or '@b' (what the first or second cell was), '@a.held' or '@b.held'. A clone learns what touches it with "
        "'@b'; see the reactions how-to, \"Cells that remember\".",
        examples=["@b"],
    )
    b_holds: Product | None = Field(
        None, description="What the second cell holds afterwards; as 'a_holds'. A virus keeps what it ate with '@b'.",
        examples=["@b"],
    )
    chance: float = Field(gt=0.0, le=1.0, description="Chance per frame that a touching pair reacts.")
    min_temperature: Temperature | None = Field(
        None, description="It happens only when the pair's mean temperature is at least this (degrees Celsius).",
        examples=[100],
    )
    max_temperature: Temperature | None = Field(
        None, description="It happens only when the pair's mean temperature is at most this (degrees Celsius).",
        examples=[0],
    )
    heat: float = Field(
        0.0,
        ge=-10000.0,
        le=10000.0,
        description="Degrees added to each cell that changes: positive releases heat, negative absorbs it.",
        examples=[50],
    )
    priority: int = Field(
        0,
        ge=-1000,
        le=1000,
        description="Of two reactions that match a pair as specifically, the one with the higher priority applies "
        "(then the one of the mod loaded later; see the reactions how-to).",
        examples=[1],
    )
    where: list[Literal["above", "below", "left", "right", "sides"]] | None = Field(
        None,
        min_length=1,
        description="The sides of the first cell the second may lie on ('sides': left and right); every side if left "
        "out. A tap fills only the cell below it; a seed grows only upwards.",
        examples=[["below"]],
    )
    push: float | None = Field(
        None,
        gt=0.0,
        le=MAX_SPEED,
        description="The second cell flies off, away from the first, at this speed (cells per frame), as a particle "
        "carrying what it is (then becomes): a fan. A static cell, an empty one or a particle is not pushed.",
        examples=[2.5],
    )

    @model_validator(mode="after")
    def _changes_something(self) -> "Reaction":
        if all(v is None for v in (self.a_becomes, self.b_becomes, self.a_holds, self.b_holds, self.push)):
            raise ValueError("a reaction needs a_becomes, b_becomes, a_holds, b_holds or push")
        if self.min_temperature is not None and self.max_temperature is not None and self.min_temperature > self.max_temperature:
            raise ValueError("min_temperature must not be above max_temperature")
        return self


#: Which of a cell's 8 neighbours a neighbour rule counts, by name.
NEIGHBOURHOOD = ("above", "below", "left", "right", "sides", "diagonals")


class NeighbourRule(_Strict):
    """A cell changes by how many of its 8 neighbours match a selector: Conway's Life is two rules
    (an empty cell with 3 'life' around becomes 'life'; a 'life' cell with fewer than 2 or more than
    3 becomes empty). Every rule of a frame reads the cells as that frame's movement and reactions
    left them, and they change together, after them."""

    cell: str = Field(pattern=rf"^{SELECTOR}$", description="Selector for the cells the rule changes ('empty' too).", examples=["empty"])
    count: str = Field(pattern=rf"^{SELECTOR}$", description="Selector for the neighbours counted.", examples=["life"])
    counts: list[Annotated[int, Field(ge=0, le=8)]] = Field(
        min_length=1, description="The numbers of matching neighbours at which it changes (0 to 8).", examples=[[3]]
    )
    becomes: ElementName = Field(description="What the cell becomes.", examples=["life"])
    chance: float = Field(1.0, gt=0.0, le=1.0, description="Chance per frame that a cell it matches changes.", examples=[0.05])
    where: list[Literal[NEIGHBOURHOOD]] | None = Field(
        None,
        min_length=1,
        description="Which neighbours are counted: 'above', 'below', 'left', 'right' (the cell on that side), 'sides' (left "
        "and right), 'diagonals' (the four corners); all 8 if left out. A crystal grows only from one below it.",
        examples=[["below"]],
    )

    @model_validator(mode="after")
    def _not_everywhere(self) -> "NeighbourRule":
        if self.cell in ("empty", "base:empty") and 0 in self.counts:
            raise ValueError("an empty cell with none of them around would change everywhere; leave 0 out of counts")
        return self


TEST_NAME = r"[a-z0-9][a-z0-9_-]*"
#: What a test's legend maps '.' to unless it says otherwise.
DEFAULT_LEGEND = {".": "empty"}
#: The character that matches any cell in an expected grid, unless a test picks another.
DEFAULT_WILDCARD = "?"


class Placed(_Strict):
    """A legend entry that also sets the temperature of the cells it paints."""

    element: ElementName = Field(description="The element painted where the character is.", examples=["water"])
    temperature: Temperature = Field(description="Their temperature, in degrees Celsius.", examples=[40])


class Bounds(_Strict):
    """A closed range; either end may be left out."""

    min: float | None = Field(None, description="Lowest allowed value.", examples=[100])
    max: float | None = Field(None, description="Highest allowed value.", examples=[400])

    @model_validator(mode="after")
    def _ordered(self) -> "Bounds":
        if self.min is None and self.max is None:
            raise ValueError("give min, max or both")
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError("min must not be above max")
        return self


Count = Annotated[
    Union[Annotated[int, Field(ge=0)], Annotated[list[Annotated[int, Field(ge=0)]], Field(min_length=2, max_length=2)]],
    Field(description="An exact number of cells, or [fewest, most]."),
]


class ModTest(_Strict):
    """An interaction test: a small scene drawn as text, run for some frames, then checked.

    ``scene`` has one character per cell and one line per row (leading and
    trailing blank lines and the common indentation are ignored); ``legend``
    says which element each character is ('.' is empty unless you say
    otherwise). The world's edges are closed. Every expectation given must
    hold after ``frames`` frames.
    """

    name: str = Field(pattern=rf"^{TEST_NAME}$", description="Short name, unique in the mod (lower case, digits, _ and -).", examples=["sinks_in_water"])
    description: str = Field("", max_length=2000, description="What the test shows.", examples=["Sand poured into water sinks to the bottom."])
    mods: list[ModName] = Field(
        default_factory=list,
        description="Other mods to load for this test, besides this one and what it requires (e.g. 'water' to sink sand in).",
    )
    seed: int = Field(0, ge=0, le=2**32 - 1, description="Seed of every random choice.", examples=[7])
    frames: int = Field(ge=0, le=100000, description="Frames to run before checking.", examples=[60])
    legend: dict[str, ElementName | Placed] = Field(
        default_factory=dict,
        description="One character -> an element, or {element, temperature}. '.' is 'empty' unless given.",
        examples=[{"S": "sand", "w": {"element": "water", "temperature": 40}}],
    )
    scene: str = Field(description="The starting cells: one line per row, one legend character per cell.", examples=["..S..\n.www.\n#####"])
    expect: str | None = Field(
        None, description="The exact cells after 'frames' frames, drawn like 'scene'; the wildcard matches any cell."
    )
    wildcard: str = Field(DEFAULT_WILDCARD, min_length=1, max_length=1, description="The character in 'expect' that matches any cell.", examples=["*"])
    count: dict[ElementName, Count] = Field(
        default_factory=dict,
        description="Cells of an element at the end: an exact number or [fewest, most]; flying particles count as what they carry.",
    )
    present: list[ElementName] = Field(default_factory=list, description="Elements that must be somewhere at the end.")
    absent: list[ElementName] = Field(default_factory=list, description="Elements that must be nowhere at the end.")
    temperature: dict[ElementName, Bounds] = Field(
        default_factory=dict, description="Bounds in degrees Celsius that every cell of an element must be within at the end.",
        examples=[{"steam": {"min": 100, "max": 400}}],
    )

    @field_validator("legend")
    @classmethod
    def _single_characters(cls, value: dict) -> dict:
        for char in value:
            if len(char) != 1 or char.isspace():
                raise ValueError(f"legend keys are single, visible characters (got {char!r})")
        return value

    @model_validator(mode="after")
    def _grids_fit(self) -> "ModTest":
        legend = self.full_legend()
        if self.wildcard in legend:
            raise ValueError(f"the wildcard {self.wildcard!r} is also in the legend; pick another with wildcard = \"...\"")
        rows = self.rows("scene")
        if not rows:
            raise PydanticCustomError("grid", "draw at least one row", {"field": "scene", "row": None})
        _check_grid("scene", rows, set(legend), len(rows[0]), len(rows))
        if self.expect is not None:
            _check_grid("expect", self.rows("expect"), set(legend) | {self.wildcard}, len(rows[0]), len(rows))
        if not (self.expect is not None or self.count or self.present or self.absent or self.temperature):
            raise ValueError("a test needs at least one of expect, count, present, absent, temperature")
        return self

    def full_legend(self) -> dict[str, "str | Placed"]:
        """The legend with the defaults filled in."""
        return {**DEFAULT_LEGEND, **self.legend}

    def rows(self, which: str) -> list[str]:
        """``scene`` or ``expect`` as rows of characters."""
        text = textwrap.dedent(getattr(self, which) or "").strip("\n")
        return [line.rstrip() for line in text.splitlines()] if text.strip() else []


def _check_grid(name: str, rows: list[str], allowed: set[str], width: int, height: int) -> None:
    def wrong(message: str, row: int | None = None) -> PydanticCustomError:
        return PydanticCustomError("grid", "{message}", {"message": message, "field": name, "row": row})

    if len(rows) != height:
        raise wrong(f"{len(rows)} rows; the scene has {height}")
    for number, row in enumerate(rows, start=1):
        if len(row) != width:
            raise wrong(f"row {number} has {len(row)} cells; the scene's first row has {width}", number)
        unknown = sorted(set(row) - allowed)
        if unknown:
            raise wrong(f"row {number}: {', '.join(map(repr, unknown))} not in the legend", number)


def _patches_too(schema: dict) -> None:
    """Let editors accept the tables checked only when loaded: patches, and elements made ``like`` another."""
    for name, element in schema.get("patternProperties", {}).items():
        schema["patternProperties"][name] = {"anyOf": [element, {
            "type": "object",
            "description": "Without an archetype: a patch of another mod's element ('mod:NAME'), or an element made 'like' "
            "another; its fields are checked when the mods are loaded.",
            "not": {"required": ["archetype"]},
        }]}


class ModFile(_Strict):
    """A whole mod file."""

    mod: ModInfo = Field(description="Name, version and dependencies of the mod.")
    elements: dict[ElementName, Element] = Field(
        default_factory=dict,
        description="The elements this mod defines, by name; 'othermod:NAME' without an archetype changes only the fields it names of another mod's element.",
        json_schema_extra=_patches_too,
    )
    _patches: dict[str, dict] = PrivateAttr(default_factory=dict)

    @model_validator(mode="wrap")
    @classmethod
    def _patches_apart(cls, data, handler):
        """Set apart the tables of other mods' elements that have no archetype (patches) and those made
        ``like`` another: checked once the fields they take are known (by the compiler)."""
        patches = {}
        if isinstance(data, dict) and isinstance(data.get("elements"), dict):
            patches = {k: v for k, v in data["elements"].items() if isinstance(v, dict) and (("like" in v) or (":" in str(k) and "archetype" not in v))}
            if patches:
                data = {**data, "elements": {k: v for k, v in data["elements"].items() if k not in patches}}
        model = handler(data)
        model._patches = patches
        return model

    @property
    def patches(self) -> dict[str, dict]:
        """Tables of other mods' elements that name only the fields they change (no archetype), and
        tables of elements made ``like`` another, as written."""
        return self._patches
    reactions: list[Reaction] = Field(default_factory=list, description="Reactions between touching cells.")
    neighbours: list[NeighbourRule] = Field(
        default_factory=list, description="Rules by which a cell changes with how many of its 8 neighbours match (Life, growth, crystals)."
    )
    tests: list[ModTest] = Field(default_factory=list, description="Interaction tests, run by 'sandmod test' and pytest.")

    @field_validator("tests")
    @classmethod
    def _unique_test_names(cls, tests: list[ModTest]) -> list[ModTest]:
        names = [t.name for t in tests]
        doubled = sorted({n for n in names if names.count(n) > 1})
        if doubled:
            raise ValueError(f"test names must be unique in a mod: {', '.join(doubled)}")
        return tests


PATTERN_HINTS.update(
    {
        f"^{ELEMENT_REF}$": "must be an element name like 'sand' or 'base:stone' (lower case, digits, _)",
        f"^(?:{ELEMENT_REF}|{CELL_REF})$": "must be an element name like 'sand' or 'base:stone', or '@a', '@b', '@a.held' or '@b.held'",
        f"^(?:{ELEMENT_REF}|@held)$": "must be an element name like 'sand' or 'base:stone', or '@held'",
        f"^{MOD_NAME}$": "must be a mod name like 'sand' or 'my-mod' (lower case, digits, _ and -)",
        f"^{NAME}$": "must be a lower-case name like 'acid_proof'",
        f"^{SELECTOR}$": "must be an element ('water'), a tag ('#metal'), '*', or one of those after '!'",
        r"^#[0-9a-fA-F]{6}$": "must be a colour like '#c2b280'",
        f"^{TEST_NAME}$": "must be a short name like 'sinks_in_water' (lower case, digits, _ and -)",
        BEHAVIOUR_NAME: "must be a plugin's behaviour as 'PLUGIN:name', like 'garden:grow'",
    }
)
