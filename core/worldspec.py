"""The world file format: size, seed, mods, a painted scene, emitters, render settings.

::

    [world]
    width = 160
    height = 120
    seed = 7
    mods = ["sand", "water"]      # leave out to load every mod found

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

    [render]
    frames = 400
    every = 2
    scale = 3
    fps = 30

Coordinates are cells; (0, 0) is the top-left corner and y grows downwards.
"""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, model_validator

from .modspec import ELEMENT_REF, ModName

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


class _Shape(_Strict):
    element: ElementRef = Field(description="The element to paint ('empty' erases).")


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


class _Emitting(_Strict):
    start: int = Field(0, ge=0, description="First frame of pouring.")
    stop: int | None = Field(None, ge=1, description="Pouring ends before this frame (never, if left out).")
    chance: float = Field(
        0.5, gt=0, le=1, description="Chance per frame that each empty cell of the shape gets the element."
    )

    @model_validator(mode="after")
    def _stop_after_start(self):
        if self.stop is not None and self.stop <= self.start:
            raise ValueError("stop must be greater than start")
        return self


class RectEmitter(Rect, _Emitting):
    """Pours into a rectangle."""


class CircleEmitter(Circle, _Emitting):
    """Pours into a disc."""


class LineEmitter(Line, _Emitting):
    """Pours along a stroke."""


Emitter = Annotated[Union[RectEmitter, CircleEmitter, LineEmitter], Field(discriminator="shape")]


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
    render: RenderSettings = Field(default_factory=RenderSettings, description="How 'sandmod render' records.")
