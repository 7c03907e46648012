"""The world file format: size, seed, mods, a painted scene, emitters, render settings.

::

    [world]
    width = 160
    height = 120
    seed = 7
    mods = ["sand", "water"]      # leave out to load every mod found
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

    [render]
    frames = 400
    every = 2
    scale = 3
    fps = 30

Coordinates are cells; (0, 0) is the top-left corner and y grows downwards.
"""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, field_validator, model_validator

from .modspec import ELEMENT_REF, MAX_SPEED, Explosion, ModName, Temperature

#: Largest width or height (the kernel's cell hash packs x and y in 16 and 15 bits).
MAX_SIZE = 16384

ElementRef = Annotated[str, Field(pattern=rf"^{ELEMENT_REF}$", description="An element, e.g. 'sand' or 'base:stone'.")]
Point = Annotated[list[int], Field(min_length=2, max_length=2, description="A cell as [x, y].")]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)


class WorldInfo(_Strict):
    """The ``[world]`` table."""

    width: int = Field(ge=4, le=MAX_SIZE, description="Width in cells.")
    height: int = Field(ge=4, le=MAX_SIZE, description="Height in cells.")
    seed: int = Field(0, ge=0, le=2**32 - 1, description="Seed of every random choice; same seed, same frames.")
    mods: list[ModName] | None = Field(
        None, description="Mods to load (with what they require, and 'base'); all that are found if left out."
    )
    gravity: float = Field(
        1.0,
        ge=0.0,
        le=10.0,
        description=(
            "Scales every element's gravity: 1 as the mods set it, 0.5 moon-like, "
            "0 none (movers still go one cell a frame)."
        ),
    )
    made_with: dict[ModName, str] | None = Field(
        None,
        description="The mods and versions the world was made with ('sandmod new world' writes it); "
        "loading it with other mods or versions prints a warning.",
    )


class _Shape(_Strict):
    element: ElementRef = Field(description="The element to paint ('empty' erases).")
    temperature: Temperature | None = Field(
        None, description="Degrees Celsius of the painted cells (default: the element's own)."
    )


class Rect(_Shape):
    """An axis-aligned rectangle."""

    shape: Literal["rect"]
    x: int = Field(description="Left column.")
    y: int = Field(description="Top row.")
    width: int = Field(ge=1, description="Width in cells.")
    height: int = Field(ge=1, description="Height in cells.")


class Circle(_Shape):
    """A filled disc."""

    shape: Literal["circle"]
    x: int = Field(description="Centre column.")
    y: int = Field(description="Centre row.")
    radius: float = Field(gt=0, le=MAX_SIZE, description="Radius in cells.")


class Line(_Shape):
    """A straight stroke, drawn with the line traversal."""

    shape: Literal["line"]
    start: Point = Field(alias="from", description="First cell, [x, y].")
    end: Point = Field(alias="to", description="Last cell, [x, y].")
    thickness: int = Field(1, ge=1, le=64, description="Brush diameter in cells.")


class Fill(_Shape):
    """A paint bucket: the region connected to ``at`` that holds the same element as ``at``."""

    shape: Literal["fill"]
    at: Point = Field(description="A cell of the region to fill, [x, y].")


Shape = Annotated[Union[Rect, Circle, Line, Fill], Field(discriminator="shape")]


class _Timed(_Strict):
    start: int = Field(0, ge=0, description="First frame it is on.")
    stop: int | None = Field(None, ge=1, description="It stops before this frame (never, if left out).")

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


Emitter = Annotated[Union[RectEmitter, CircleEmitter, LineEmitter], Field(discriminator="shape")]


Speed = Annotated[float, Field(gt=0, le=MAX_SPEED)]


def _as_range(value: object) -> object:
    return [value, value] if isinstance(value, (int, float)) else value


class Spray(_Timed):
    """Shoots particles from around a point: a fountain, a hose, a shower of sparks.

    A particle element flies as itself; any other element flies as
    ``base:particle`` carrying it, and lands as that element.
    """

    element: ElementRef = Field(description="What flies: a particle element, or any element to carry.")
    at: Point = Field(description="Where particles start, [x, y].")
    radius: float = Field(0, ge=0, le=64, description="They start from empty cells within this distance of 'at'.")
    direction: float = Field(90, ge=-360, le=360, description="Degrees: 0 right, 90 up, 180 left, -90 down.")
    spread: float = Field(0, ge=0, le=360, description="Width of the cone of directions, in degrees.")
    speed: Annotated[list[Speed], BeforeValidator(_as_range), Field(min_length=2, max_length=2)] = Field(
        description=f"Cells per frame (at most {MAX_SPEED}), or [slowest, fastest].",
        json_schema_extra={"anyOf": [{"type": "number"}, {"type": "array"}]},
    )
    rate: float = Field(
        1.0, gt=0, le=256, description="Particles per frame (a fraction: on average); at most one per free start cell."
    )

    @field_validator("speed")
    @classmethod
    def _slowest_first(cls, speed: list[float]) -> list[float]:
        if speed[0] > speed[1]:
            raise ValueError("give [slowest, fastest]")
        return speed


class ScheduledExplosion(Explosion):
    """An explosion the world sets off at a frame and place (after that frame's step)."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    frame: int = Field(ge=0, description="The frame it goes off on.")
    at: Point = Field(description="Its centre, [x, y].")


class RenderSettings(_Strict):
    """The ``[render]`` table (the command line may override each)."""

    frames: int = Field(300, ge=1, le=100000, description="Frames to simulate.")
    every: int = Field(2, ge=1, le=1000, description="Frames simulated per image written.")
    scale: int = Field(3, ge=1, le=16, description="Pixels per cell (nearest neighbour).")
    fps: float = Field(25, gt=0, le=50, description="Images per second when played back.")
    output: str | None = Field(
        None, min_length=1, description="Output file, relative to the world file; default: WORLD_NAME.gif here."
    )


class WorldFile(_Strict):
    """A whole world file."""

    world: WorldInfo = Field(description="Size, seed and mods.")
    scene: list[Shape] = Field(default_factory=list, description="Shapes painted in order before the first frame.")
    emitters: list[Emitter] = Field(default_factory=list, description="Shapes that pour an element over frames.")
    sprays: list[Spray] = Field(default_factory=list, description="Sources of flying particles.")
    explosions: list[ScheduledExplosion] = Field(default_factory=list, description="Blasts at given frames and places.")
    render: RenderSettings = Field(default_factory=RenderSettings, description="How 'sandmod render' records.")
