"""Build a :class:`World` from a validated world file: the scene, emitters, sprays, explosions, timeline."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from pydantic import BaseModel, ConfigDict

from ..rules.compiler import Ruleset
from ..errors import Problem, ProblemsError
from ..formats.limits import PICTURE_BYTES_PER_PIXEL, WORLD_BYTES_PER_CELL, MemoryBudget
from ..formats.pictures import PictureError, fit, hex_rgb, legend_indices, read_rgba
from .shapes import Patch, circle_mask, fill_mask, rect_mask, stroke_mask
from ..formats.tomlsource import Loc, TomlSource
from ..formats.userfiles import Refused, inside
from ..formats.validation import validate
from .world import Emitter, Heater, Launcher, Painting, Spray, Switches, World
from ..formats.worldspec import (
    Burst,
    Event,
    Shape,
    CircleArea,
    FillArea,
    LineArea,
    Picture,
    RectArea,
    StrokeArea,
    WorldFile,
)

Layer = Callable[[np.ndarray], np.ndarray]  # the world's cells -> the element each cell becomes (-1: unchanged)


def shape_mask(shape: RectArea | CircleArea | LineArea | StrokeArea | FillArea, cells: np.ndarray) -> np.ndarray:
    """The cells a shape covers in a world holding ``cells``."""
    height, width = cells.shape
    if isinstance(shape, RectArea):
        return rect_mask(width, height, shape.x, shape.y, shape.width, shape.height)
    if isinstance(shape, CircleArea):
        return circle_mask(width, height, shape.x, shape.y, shape.radius)
    if isinstance(shape, LineArea):
        return stroke_mask(width, height, [tuple(shape.first), tuple(shape.last)], shape.thickness, shape.brush == "square")
    if isinstance(shape, StrokeArea):
        return stroke_mask(width, height, [tuple(p) for p in shape.points], shape.thickness, shape.brush == "square")
    x, y = shape.at
    if not (0 <= x < width and 0 <= y < height):
        return np.zeros_like(cells, bool)
    return fill_mask(cells, x, y)


@dataclass
class _Builder:
    """Turns a world file's parts into what the world runs, collecting every problem on the way."""

    spec: WorldFile | None  # None: a lone shape (see paint_shape)
    ruleset: Ruleset
    source: TomlSource
    world: World
    budget: MemoryBudget
    unloaded: dict[str, str] = field(default_factory=dict)  # elements of mods found but not loaded -> their mod
    problems: list[Problem] = field(default_factory=list)

    def note(self, loc: Loc, message: str) -> None:
        self.problems.append(self.source.problem(loc, message))

    def keep(self, loc: Loc, nbytes: int) -> bool:
        """Promise the memory a part of the world keeps until its frame; False (problem noted) past the limit."""
        over = self.budget.take(nbytes, "this")
        if over is not None:
            self.note(loc, over)
        return over is None

    def element(self, loc: Loc, ref: str) -> int | None:
        try:
            return self.ruleset.index(ref)
        except KeyError as exc:
            mod = self.unloaded.get(ref)
            hint = f"; mod '{mod}' has it: add \"{mod}\" to [world] mods" if mod else ""
            self.note(loc, exc.args[0] + hint)
            return None

    def area(self, loc: Loc, shape, what: str = "the shape", kept: bool = False) -> Callable[[np.ndarray], np.ndarray] | None:
        """The shape's mask function, or None (problem noted) when it covers no cell of the world now.

        Only a fill depends on what the world holds; other shapes' masks are made once.
        """
        mask = shape_mask(shape, self.world.cells)
        if not mask.any():
            self.note(loc, f"{what} lies outside the {self.world.width}x{self.world.height} world")
            return None
        if isinstance(shape, FillArea):
            return lambda cells: shape_mask(shape, cells)
        patch = Patch.of(mask)
        if kept and not self.keep(loc, patch.box.nbytes):
            return None
        return lambda cells: patch.whole()

    def layer(self, loc: Loc, shape, kept: bool = False) -> Layer | None:
        """What painting a shape (or a picture) does, or None (problem noted)."""
        if isinstance(shape, Picture):
            return self.picture(loc, shape, kept)
        element = self.element(loc + ("element",), shape.element)
        area = self.area(loc, shape, kept=kept)
        over = None if shape.over is None else self.element(loc + ("over",), shape.over)
        if element is None or area is None or (shape.over is not None and over is None):
            return None
        if over is not None:
            return lambda cells: np.where(area(cells) & (cells == over), np.int32(element), np.int32(-1))
        return lambda cells: np.where(area(cells), np.int32(element), np.int32(-1))

    def erasure(self, loc: Loc, shape) -> Layer | None:
        """What erasing a shape does: its cells become empty (element 0)."""
        area = self.area(loc, shape, kept=True)
        return None if area is None else lambda cells: np.where(area(cells), np.int32(0), np.int32(-1))

    def picture(self, loc: Loc, picture: Picture, kept: bool = False) -> Layer | None:
        elements = [self.element(loc + ("legend", colour), ref) for colour, ref in picture.legend.items()]
        world = self.world
        box_width = picture.width or world.width - picture.x
        box_height = picture.height or world.height - picture.y
        if box_width < 1 or box_height < 1 or picture.x >= world.width or picture.y >= world.height:
            self.note(loc, f"the picture's box lies outside the {world.width}x{world.height} world")
            return None
        folder = self.source.folder or Path(".")
        try:
            left = self.budget.left()
            rgba = read_rgba(inside(folder, picture.file, "picture"), None if left is None else left // PICTURE_BYTES_PER_PIXEL)
            colours = [hex_rgb(c) for c in picture.legend]
            indices = legend_indices(rgba, colours, nearest=picture.match == "nearest")
        except (PictureError, Refused) as exc:
            self.note(loc + ("file",), str(exc))
            return None
        if None in elements:
            return None
        lookup = np.array(elements + [-1], np.int32)  # index -1 (transparent) reads the last entry
        painted = lookup[fit(indices, box_width, box_height)]
        layer = np.full(world.cells.shape, -1, np.int32)
        x0, y0 = max(picture.x, 0), max(picture.y, 0)
        x1, y1 = min(picture.x + box_width, world.width), min(picture.y + box_height, world.height)
        layer[y0:y1, x0:x1] = painted[y0 - picture.y : y1 - picture.y, x0 - picture.x : x1 - picture.x]
        patch = Patch.of(layer, -1)
        if kept and not self.keep(loc, patch.box.nbytes):
            return None
        return lambda cells: patch.whole()

    def event(self, number: int, event: Event) -> None:
        """Set up timeline event ``number``: what it paints, erases, heats, sprays or blows up on its frame."""
        world, loc = self.world, ("timeline", number, event.action)
        if event.paint is not None:
            layer = self.layer(loc, event.paint, kept=True)
            if layer is not None:
                world.paintings.append(Painting(event.frame, layer, getattr(event.paint, "temperature", None), number))
        elif event.erase is not None:
            layer = self.erasure(loc, event.erase)
            if layer is not None:
                world.paintings.append(Painting(event.frame, layer, None, number))
        elif event.heat is not None:
            area = self.area(loc, event.heat, kept=True)
            if area is not None:
                world.heaters.append(Heater(area, event.heat.temperature, event.frame, event.frame + event.heat.frames))
        elif event.spawn is not None:
            made = self.burst(loc, event.spawn, event.frame, event.frame + 1, event.spawn.count, len(self.spec.sprays) + number)
            if made is not None:
                world.sprays.append(made)
        elif event.launch is not None:
            area = self.area(loc, event.launch, kept=True)
            if area is not None:
                launch = event.launch
                world.launchers.append(Launcher(event.frame, area, launch.direction, launch.spread, tuple(launch.speed), number))
        elif event.explode is not None:
            self.blast(loc, event.explode, event.frame)

    def blast(self, loc: Loc, blast, frame: int) -> None:
        """Schedule an explosion after the step of ``frame``."""
        x, y = blast.at
        if not (0 <= x < self.world.width and 0 <= y < self.world.height):
            self.note(loc + ("at",), f"the centre lies outside the {self.world.width}x{self.world.height} world")
            return
        try:
            self.world.scheduled.append((frame, self.world._blast_row(x, y, blast)))
        except KeyError as exc:
            self.note(loc + ("leaves",), exc.args[0])

    def switches(self, name: str | None) -> Switches:
        """The timeline's start and stop events for the emitter or spray called ``name``."""
        if name is None:
            return ()
        return tuple(
            (event.frame, event.start is not None) for event in self.spec.timeline if name in (event.start, event.stop)
        )

    def burst(self, loc: Loc, burst: Burst, start: int, stop: int | None, rate: float, number: int, switches: Switches = ()):
        """A spray (or a one-frame burst of particles), or None (problem noted)."""
        x, y = burst.at
        disc = CircleArea(shape="circle", x=x, y=y, radius=max(burst.radius, 0.5))
        element = self.element(loc + ("element",), burst.element)
        area = self.area(loc + ("at",), disc, "the start")
        if element == 0:
            self.note(loc + ("element",), "spray an element, not 'empty'")
        if not element or area is None:
            return None
        ys, xs = np.nonzero(area(self.world.cells))
        speeds = (burst.speed[0], burst.speed[1])
        return Spray(ys, xs, element, burst.direction, burst.spread, speeds, rate, start, stop, number, switches)


def build_world(
    spec: WorldFile,
    ruleset: Ruleset,
    source: TomlSource,
    seed: int | None = None,
    budget: MemoryBudget | None = None,
    unloaded: dict[str, str] | None = None,
) -> World:
    """Paint ``spec``'s scene into a new world and set up what runs over frames.

    ProblemsError names unknown elements, shapes outside the world, unreadable
    pictures, timeline events that name no emitter or spray, and whatever
    would pass the memory ``budget`` (by default, the default limit). An
    unknown element that ``unloaded`` maps to a mod is named with that mod.
    """
    info = spec.world
    budget = budget or MemoryBudget()
    over = budget.take(info.width * info.height * WORLD_BYTES_PER_CELL, f"a {info.width}x{info.height} world")
    if over is not None:
        raise ProblemsError([source.problem(("world",), over)])
    world = World(ruleset, info.width, info.height, info.seed if seed is None else seed, info.gravity)
    build = _Builder(spec, ruleset, source, world, budget, unloaded or {})
    for number, shape in enumerate(spec.scene):  # in order: a fill sees what came before
        layer = build.layer(("scene", number), shape)
        if layer is not None:
            painted = world.paint_layer(layer(world.cells))
            if getattr(shape, "temperature", None) is not None:
                world.set_temperature(painted, shape.temperature)
    _check_names(spec, build)
    for number, emitter in enumerate(spec.emitters):
        element = build.element(("emitters", number, "element"), emitter.element)
        area = build.area(("emitters", number), emitter)
        if element is not None and area is not None:
            ys, xs = np.nonzero(area(world.cells))
            if not build.keep(("emitters", number), ys.nbytes + xs.nbytes):
                continue
            world.emitters.append(
                Emitter(ys, xs, element, emitter.start, emitter.stop, emitter.chance, build.switches(emitter.name))
            )
    for number, spray in enumerate(spec.sprays):
        made = build.burst(("sprays", number), spray, spray.start, spray.stop, spray.rate, number, build.switches(spray.name))
        if made is not None:
            world.sprays.append(made)
    for number, blast in enumerate(spec.explosions):
        build.blast(("explosions", number), blast, blast.frame)
    for number, event in enumerate(spec.timeline):
        build.event(number, event)
    world.scheduled.sort(key=lambda scheduled: scheduled[0])  # stable: same frame, in the file's order
    if build.problems:
        raise ProblemsError(sorted(build.problems, key=lambda p: (p.line or 0, p.column or 0)))
    return world


def add_event(world: World, spec: WorldFile, source: TomlSource, number: int) -> None:
    """Set up ``spec.timeline[number]`` in a world built from the timeline's earlier events, as
    :func:`build_world` would have (``sandmod play`` adds events as they happen, and a render of
    the world file it writes makes the same frames). ProblemsError names a mistake."""
    build = _Builder(spec, world.ruleset, source, world, MemoryBudget(None))
    build.event(number, spec.timeline[number])
    if build.problems:
        raise ProblemsError(build.problems)


def _check_names(spec: WorldFile, build: _Builder) -> None:
    """Names of emitters and sprays are unique, and every start and stop event names one."""
    named: dict[str, Loc] = {}
    for table, sources in (("emitters", spec.emitters), ("sprays", spec.sprays)):
        for number, source in enumerate(sources):
            if source.name is None:
                continue
            if source.name in named:
                build.note((table, number, "name"), f"'{source.name}' names another emitter or spray too")
            named.setdefault(source.name, (table, number, "name"))
    for number, event in enumerate(spec.timeline):
        for action in ("start", "stop"):
            name = getattr(event, action)
            if name is not None and name not in named:
                known = f"named: {', '.join(sorted(named))}" if named else "none has a name"
                build.note(("timeline", number, action), f"no emitter or spray is called '{name}' ({known})")


class _OneShape(BaseModel):
    """A lone shape, validated as a world file's would be."""

    model_config = ConfigDict(extra="forbid")
    shape: Shape


def paint_shape(world: World, table: dict, origin: str = "paint_shape") -> int:
    """Paint ``table``, a shape as a world file's ``[[scene]]`` writes it, into ``world`` (see
    :meth:`World.paint_shape`); ProblemsError names each mistake, with ``origin`` for a file."""
    source = TomlSource(origin, "", {"shape": table}, folder=Path.cwd())
    shape = validate(_OneShape, source).shape
    build = _Builder(None, world.ruleset, source, world, MemoryBudget(None))
    layer = build.layer(("shape",), shape)
    if build.problems or layer is None:
        raise ProblemsError(build.problems)
    painted = world.paint_layer(layer(world.cells))
    if getattr(shape, "temperature", None) is not None:
        world.set_temperature(painted, shape.temperature)
    return int(painted.sum())
