"""The world file format: size, seed, mods, a painted scene, emitters, sprays, a timeline, render settings.

::

    [world]
    width = 160
    height = 120
    seed = 7
    mods = ["sand", "water"]      # leave out to load every mod found
    mod_folders = ["my-mods"]     # more mods, in folders inside the world file's
    gravity = 1.0                  # scales every element's gravity

    [[scene]]                      # painted in order, later shapes on top
    shape = "rect"
    element = "stone"
    x = 0
    y = 110
    width = 160
    height = 10

    [[emitters]]                   # pours an element while start <= frame < stop
    shape = "circle"
    element = "sand"
    x = 80
    y = 8
    radius = 3
    start = 0
    stop = 200
    chance = 0.5

    [[explosions]]                 # a blast at a frame and place
    frame = 120
    at = [80, 100]
    radius = 10
    strength = 20

    [[sprays]]                     # shoots particles that land as their element
    element = "water"
    at = [20, 100]
    direction = 80                 # degrees: 0 right, 90 up
    spread = 10
    speed = [3, 4]                 # cells per frame
    rate = 2                       # particles per frame
    stop = 300

    [[timeline]]                   # at a frame, exactly one of: paint, erase, heat,
    frame = 150                    # start, stop (a named emitter or spray), spawn, launch, explode
    heat = { shape = "rect", x = 60, y = 108, width = 30, height = 2, temperature = 600, frames = 100 }

    [render]
    frames = 400
    every = 2
    scale = 3
    fps = 30
    loop = 0                       # plays in all; 0 = forever
    crop = [0, 20, 160, 100]       # x, y, width, height in cells

Shapes are rect, circle, line, stroke (a polyline), fill (a paint bucket) and
image (a picture whose colours map to elements by a legend).
Coordinates are cells; (0, 0) is the top-left corner and y grows downwards.
"""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, field_validator, model_validator

from .modspec import ELEMENT_REF, MAX_SPEED, Explosion, HexColor, ModName, Temperature

#: Largest width or height (the kernel's cell hash packs x and y in 16 and 15 bits).
MAX_SIZE = 16384

#: Most entries in each of a world's lists (scene, emitters, sprays, explosions, timeline).
MAX_ITEMS = 10000
#: Most timeline events (a played session's record fills the 4 MB a world file may take first, at about 21,000 moves).
MAX_TIMELINE = 50000
#: Most frames a render simulates (a played session: about 4.6 hours at 60 a second).
MAX_FRAMES = 1000000
#: Coordinates lie within this distance of the world's corner (shapes may reach past its edges).
MAX_COORD = 2 * MAX_SIZE
#: A stroke's segments together span at most this many cells (along their longer axes).
MAX_STROKE_CELLS = 16 * MAX_SIZE

ElementRef = Annotated[str, Field(pattern=rf"^{ELEMENT_REF}$", description="An element, e.g. 'sand' or 'base:stone'.")]
Coord = Annotated[int, Field(ge=-MAX_COORD, le=MAX_COORD)]
Point = Annotated[list[Coord], Field(min_length=2, max_length=2, description="A cell as [x, y].")]
Extent = Annotated[int, Field(ge=1, le=MAX_COORD)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)


class WorldInfo(_Strict):
    """The ``[world]`` table."""

    width: int = Field(ge=4, le=MAX_SIZE, description="Width in cells.")
    height: int = Field(ge=4, le=MAX_SIZE, description="Height in cells.")
    seed: int = Field(0, ge=0, le=2**32 - 1, description="Seed of every random choice; same seed, same frames.", examples=[42])
    mods: list[ModName] | None = Field(
        None, description="Mods to load (with what they require, and 'base'); all that are found if left out."
    )
    mod_folders: list[Annotated[str, Field(min_length=1)]] = Field(
        default_factory=list,
        max_length=16,
        description="More folders of mods, besides a 'mods' folder beside the world file, './mods' and '--mods': "
        "each relative to the world file's folder and inside it (no absolute path, no '..' out, no symlink out), "
        "so a world file reads mods only from the folder the user named it in. "
        "'sandmod play' writes it when a session it saves needs mods from elsewhere.",
        examples=[["my-mods"]],
    )
    gravity: float = Field(
        1.0,
        ge=0.0,
        le=10.0,
        description=(
            "Scales every element's gravity: 1 as the mods set it, 0.5 moon-like, "
            "0 none (movers still go one cell a frame)."
        ),
        examples=[0.5],
    )
    made_with: dict[ModName, str] | None = Field(
        None,
        description="The mods and versions the world was made with ('sandmod new world' writes it); "
        "loading it with other mods or versions prints a warning.",
        examples=[{"base": "1.0.0", "sand": "1.0.0"}],
    )


class RectArea(_Strict):
    """An axis-aligned rectangle."""

    shape: Literal["rect"]
    x: Coord = Field(description="Left column.")
    y: Coord = Field(description="Top row.")
    width: Extent = Field(description="Width in cells.")
    height: Extent = Field(description="Height in cells.")


class CircleArea(_Strict):
    """A filled disc."""

    shape: Literal["circle"]
    x: Coord = Field(description="Centre column.")
    y: Coord = Field(description="Centre row.")
    radius: float = Field(gt=0, le=MAX_SIZE, description="Radius in cells.")


class LineArea(_Strict):
    """A straight stroke, drawn with the line traversal."""

    shape: Literal["line"]
    first: Point = Field(alias="from", description="First cell, [x, y].")
    last: Point = Field(alias="to", description="Last cell, [x, y].")
    thickness: int = Field(1, ge=1, le=64, description="Brush diameter in cells.")
    brush: Literal["round", "square"] = Field("round", description="The brush's shape: round, or a square 'thickness' cells a side.", examples=["square"])


class StrokeArea(_Strict):
    """A brush stroke along a polyline: the line traversal from each point to the next, no gaps."""

    shape: Literal["stroke"]
    points: list[Point] = Field(min_length=2, max_length=4096, description="The corners, [[x, y], ...], in order.")
    thickness: int = Field(1, ge=1, le=64, description="Brush diameter in cells.")
    brush: Literal["round", "square"] = Field("round", description="The brush's shape: round, or a square 'thickness' cells a side.", examples=["square"])

    @field_validator("points")
    @classmethod
    def _not_too_long(cls, points: list[list[int]]) -> list[list[int]]:
        cells = sum(max(abs(b[0] - a[0]), abs(b[1] - a[1])) for a, b in zip(points, points[1:]))
        if cells > MAX_STROKE_CELLS:
            raise ValueError(f"its segments span {cells} cells; at most {MAX_STROKE_CELLS}")
        return points


class FillArea(_Strict):
    """A paint bucket: the region connected to ``at`` that holds the same element as ``at`` (when it is painted)."""

    shape: Literal["fill"]
    at: Point = Field(description="A cell of the region to fill, [x, y].")


Area = Annotated[Union[RectArea, CircleArea, LineArea, StrokeArea, FillArea], Field(discriminator="shape")]


class _Paint(_Strict):
    element: ElementRef = Field(description="The element to paint ('empty' erases).", examples=["sand"])
    temperature: Temperature | None = Field(
        None, description="Degrees Celsius of the painted cells (default: the element's own).",
        examples=[900],
    )
    over: ElementRef | None = Field(None, description="Paint only the cells that hold this element (a replace brush).", examples=["water"])


class Rect(RectArea, _Paint):
    """A rectangle of an element."""


class Circle(CircleArea, _Paint):
    """A disc of an element."""


class Line(LineArea, _Paint):
    """A straight line of an element."""


class Stroke(StrokeArea, _Paint):
    """A polyline of an element."""


class Fill(FillArea, _Paint):
    """A connected region filled with an element."""


class Picture(_Strict):
    """A PNG (or any image pillow reads) painted cell by cell: each pixel's colour picks an element by the legend.

    The picture is scaled (nearest neighbour) to cover the box at (x, y),
    by default the whole world. Transparent pixels leave their cells alone.
    """

    shape: Literal["image"]
    file: str = Field(min_length=1, description="The image, relative to the world file.")
    legend: dict[HexColor, ElementRef] = Field(
        min_length=1,
        max_length=256, description="Which element each colour paints: {'#rrggbb' = 'element'}; 'empty' clears.",
        examples=[{"#c2b280": "sand", "#3366ff": "water"}],
    )
    match: Literal["exact", "nearest"] = Field(
        "exact", description="'exact': every colour must be in the legend; 'nearest': the closest legend colour."
    )
    x: Coord = Field(0, description="Left column of the box the picture covers.", examples=[10])
    y: Coord = Field(0, description="Top row of the box.", examples=[20])
    width: int | None = Field(None, ge=1, le=MAX_SIZE, description="Width of the box in cells (default: to the right edge).", examples=[96])
    height: int | None = Field(None, ge=1, le=MAX_SIZE, description="Height of the box in cells (default: to the bottom).", examples=[64])


Shape = Annotated[Union[Rect, Circle, Line, Stroke, Fill, Picture], Field(discriminator="shape")]


class _Timed(_Strict):
    name: str | None = Field(None, pattern=r"^[A-Za-z0-9_-]+$", description="A name the timeline can start and stop it by.", examples=["tap"])
    start: int = Field(0, ge=0, le=MAX_FRAMES, description="First frame it is on.")
    stop: int | None = Field(None, ge=1, le=MAX_FRAMES + 1, description="It stops before this frame (never, if left out).")

    @model_validator(mode="after")
    def _stop_after_start(self):
        if self.stop is not None and self.stop <= self.start:
            raise ValueError("stop must be greater than start")
        return self


class _Emitting(_Timed):
    chance: float = Field(
        0.5, gt=0, le=1, description="Chance per frame that each empty cell of the shape gets the element."
    )


class RectEmitter(Rect, _Emitting):
    """Pours into a rectangle."""


class CircleEmitter(Circle, _Emitting):
    """Pours into a disc."""


class LineEmitter(Line, _Emitting):
    """Pours along a stroke."""


class StrokeEmitter(Stroke, _Emitting):
    """Pours along a polyline."""


Emitter = Annotated[Union[RectEmitter, CircleEmitter, LineEmitter, StrokeEmitter], Field(discriminator="shape")]


Speed = Annotated[float, Field(gt=0, le=MAX_SPEED)]


def _as_range(value: object) -> object:
    return [value, value] if isinstance(value, (int, float)) else value


class _Flight(_Strict):
    direction: float = Field(90, ge=-360, le=360, description="Degrees: 0 right, 90 up, 180 left, -90 down.", examples=[45])
    spread: float = Field(0, ge=0, le=360, description="Width of the cone of directions, in degrees.", examples=[30])
    speed: Annotated[list[Speed], BeforeValidator(_as_range), Field(min_length=2, max_length=2)] = Field(
        description=f"Cells per frame (at most {MAX_SPEED}), or [slowest, fastest].",
        json_schema_extra={"anyOf": [{"type": "number"}, {"type": "array"}]},
        examples=[[2, 4]],
    )

    @field_validator("speed")
    @classmethod
    def _slowest_first(cls, speed: list[float]) -> list[float]:
        if speed[0] > speed[1]:
            raise ValueError("give [slowest, fastest]")
        return speed


class _Shooting(_Flight):
    element: ElementRef = Field(description="What flies: a particle element, or any element to carry.")
    at: Point = Field(description="Where particles start, [x, y].")
    radius: float = Field(0, ge=0, le=64, description="They start from empty cells within this distance of 'at'.")


class RectLaunch(RectArea, _Flight):
    """Sends the cells of a rectangle flying."""


class CircleLaunch(CircleArea, _Flight):
    """Sends the cells of a disc flying."""


class LineLaunch(LineArea, _Flight):
    """Sends the cells along a stroke flying."""


class StrokeLaunch(StrokeArea, _Flight):
    """Sends the cells along a polyline flying."""


Launch = Annotated[Union[RectLaunch, CircleLaunch, LineLaunch, StrokeLaunch], Field(discriminator="shape")]


class Spray(_Shooting, _Timed):
    """Shoots particles from around a point: a fountain, a hose, a shower of sparks.

    A particle element flies as itself; any other element flies as
    ``base:particle`` carrying it, and lands as that element.
    """

    rate: float = Field(
        1.0, gt=0, le=256, description="Particles per frame (a fraction: on average); at most one per free start cell."
    )


class Burst(_Shooting):
    """Particles shot all at once (a timeline event's ``spawn``)."""

    count: int = Field(1, ge=1, le=256, description="How many; at most one per free start cell.")


class Blast(Explosion):
    """An explosion at a place."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    at: Point = Field(description="Its centre, [x, y].")


class ScheduledExplosion(Blast):
    """An explosion the world sets off at a frame and place (after that frame's step)."""

    frame: int = Field(ge=0, le=MAX_FRAMES, description="The frame it goes off on.")


def _no_element(value: object) -> object:
    if isinstance(value, dict) and "element" in value:
        raise ValueError("'erase' empties its cells; leave 'element' out (or 'paint' with it)")
    return value


class _Heating(_Strict):
    temperature: Temperature = Field(description="Degrees Celsius the cells are set to, whatever they hold.")
    frames: int = Field(1, ge=1, le=100000, description="For how many frames, from the event's on (a heat source).")


class RectHeat(RectArea, _Heating):
    """Heats a rectangle."""


class CircleHeat(CircleArea, _Heating):
    """Heats a disc."""


class LineHeat(LineArea, _Heating):
    """Heats a line."""


class StrokeHeat(StrokeArea, _Heating):
    """Heats a polyline."""


class FillHeat(FillArea, _Heating):
    """Heats a connected region."""


Heat = Annotated[Union[RectHeat, CircleHeat, LineHeat, StrokeHeat, FillHeat], Field(discriminator="shape")]

#: What a timeline event may do; each event does exactly one.
ACTIONS = ("paint", "erase", "heat", "start", "stop", "spawn", "launch", "explode")


class Event(_Strict):
    """Something that happens at a frame: give ``frame`` and exactly one action.

    Paint, erase, heat, start, stop, spawn and launch happen before the frame's step;
    an explosion goes off after it (as ``[[explosions]]`` do).
    """

    frame: int = Field(ge=0, le=MAX_FRAMES, description="The frame it happens on.")
    paint: Shape | None = Field(None, description="Paint a shape (rect, circle, line, stroke, fill or image).")
    erase: Annotated[Area | None, BeforeValidator(_no_element)] = Field(None, description="Empty the cells of a shape.")
    heat: Heat | None = Field(None, description="Set the cells of a shape to a temperature, for 'frames' frames.")
    start: str | None = Field(None, description="Start the named emitter or spray.")
    stop: str | None = Field(None, description="Stop the named emitter or spray.")
    spawn: Burst | None = Field(None, description="Shoot particles at once.")
    launch: Launch | None = Field(
        None, description="Send the cells of a shape flying: each becomes a particle carrying its element, and lands as it."
    )
    explode: Blast | None = Field(None, description="Set off an explosion.")

    @model_validator(mode="after")
    def _one_action(self):
        given = [name for name in ACTIONS if getattr(self, name) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of {', '.join(ACTIONS)} (got {', '.join(given) or 'none'})")
        return self

    @property
    def action(self) -> str:
        """The name of what it does."""
        return next(name for name in ACTIONS if getattr(self, name) is not None)


class RenderSettings(_Strict):
    """The ``[render]`` table (the command line may override each)."""

    frames: int = Field(300, ge=1, le=MAX_FRAMES, description="Frames to simulate.")
    every: int = Field(2, ge=1, le=1000, description="Frames simulated per image written.")
    scale: int = Field(3, ge=1, le=16, description="Pixels per cell (nearest neighbour).")
    fps: float = Field(25, gt=0, le=50, description="Images per second when played back (GIF: delays of at least 20 ms).")
    loop: int = Field(0, ge=0, le=65535, description="Times the animation plays in all; 0 = forever.", examples=[1])
    crop: list[Coord] | None = Field(
        None, min_length=4, max_length=4, description="Record only this region of cells: [x, y, width, height].",
        examples=[[0, 40, 160, 60]],
    )
    format: str | None = Field(
        None, min_length=1, description="Output format (gif, apng, webp, png-frames, ...); default: by the output's extension.",
        examples=["webp"],
    )
    output: str | None = Field(
        None, min_length=1, description="Output file, relative to the world file; default: WORLD_NAME.gif here.",
        examples=["renders/hourglass.webp"],
    )


class WorldFile(_Strict):
    """A whole world file."""

    world: WorldInfo = Field(description="Size, seed and mods.")
    scene: list[Shape] = Field(default_factory=list, max_length=MAX_ITEMS, description="Shapes painted in order before the first frame.")
    emitters: list[Emitter] = Field(default_factory=list, max_length=MAX_ITEMS, description="Shapes that pour an element over frames.")
    sprays: list[Spray] = Field(default_factory=list, max_length=MAX_ITEMS, description="Sources of flying particles.")
    explosions: list[ScheduledExplosion] = Field(default_factory=list, max_length=MAX_ITEMS, description="Blasts at given frames and places.")
    timeline: list[Event] = Field(
        default_factory=list, max_length=MAX_TIMELINE, description="Events at given frames: paint, erase, heat, start, stop, spawn, launch, explode."
    )
    render: RenderSettings = Field(default_factory=RenderSettings, description="How 'sandmod render' records.")
