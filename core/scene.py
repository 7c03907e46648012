"""Build a :class:`World` from a validated world file: paint the scene, set up emitters and sprays."""

from __future__ import annotations

import numpy as np

from .compiler import Ruleset
from .errors import Problem, ProblemsError
from .shapes import circle_mask, fill_mask, line_mask, rect_mask
from .tomlsource import TomlSource
from .world import Emitter, Spray, World
from .worldspec import Circle, Fill, Line, Rect, WorldFile


def shape_mask(shape: Rect | Circle | Line | Fill, cells: np.ndarray) -> np.ndarray:
    """The cells a shape covers in a world holding ``cells``."""
    height, width = cells.shape
    if isinstance(shape, Rect):
        return rect_mask(width, height, shape.x, shape.y, shape.width, shape.height)
    if isinstance(shape, Circle):
        return circle_mask(width, height, shape.x, shape.y, shape.radius)
    if isinstance(shape, Line):
        return line_mask(width, height, tuple(shape.start), tuple(shape.end), shape.thickness)
    x, y = shape.at
    if not (0 <= x < width and 0 <= y < height):
        return np.zeros_like(cells, bool)
    return fill_mask(cells, x, y)


def build_world(spec: WorldFile, ruleset: Ruleset, source: TomlSource, seed: int | None = None) -> World:
    """Paint ``spec``'s scene into a new world; ProblemsError names unknown elements and lost shapes."""
    info = spec.world
    world = World(ruleset, info.width, info.height, info.seed if seed is None else seed, info.gravity)
    problems: list[Problem] = []

    def place(table: str, number: int, shape, field: tuple = (), what: str = "the shape") -> tuple[int, np.ndarray] | None:
        """The element and the cells of a scene shape, emitter or spray, or None (problem noted)."""
        mask = shape_mask(shape, world.cells)
        if not mask.any():
            outside = f"{what} lies outside the {info.width}x{info.height} world"
            problems.append(source.problem((table, number) + field, outside))
        try:
            index = ruleset.index(shape.element)
        except KeyError as exc:
            problems.append(source.problem((table, number, "element"), exc.args[0]))
            return None
        return (index, mask) if mask.any() else None

    for number, shape in enumerate(spec.scene):  # in order: a fill sees what came before
        placed = place("scene", number, shape)
        if placed is not None:
            world.paint(placed[1], placed[0])
            if shape.temperature is not None:
                world.set_temperature(placed[1], shape.temperature)
    for number, emitter in enumerate(spec.emitters):
        placed = place("emitters", number, emitter)
        if placed is not None:
            ys, xs = np.nonzero(placed[1])
            world.emitters.append(Emitter(ys, xs, placed[0], emitter.start, emitter.stop, emitter.chance))
    for number, spray in enumerate(spec.sprays):
        disc = Circle(shape="circle", element=spray.element, x=spray.at[0], y=spray.at[1], radius=max(spray.radius, 0.5))
        placed = place("sprays", number, disc, ("at",), "the start")
        if placed is not None and placed[0] == 0:
            problems.append(source.problem(("sprays", number, "element"), "spray an element, not 'empty'"))
        elif placed is not None:
            ys, xs = np.nonzero(placed[1])
            world.sprays.append(
                Spray(ys, xs, placed[0], spray.direction, spray.spread, tuple(spray.speed), spray.rate, spray.start, spray.stop, number)
            )
    for number, blast in enumerate(spec.explosions):
        x, y = blast.at
        if not (0 <= x < info.width and 0 <= y < info.height):
            problems.append(source.problem(("explosions", number, "at"), f"the centre lies outside the {info.width}x{info.height} world"))
            continue
        try:
            world.scheduled.append((blast.frame, world.blast_row(x, y, blast)))
        except KeyError as exc:
            problems.append(source.problem(("explosions", number, "leaves"), exc.args[0]))
    if problems:
        raise ProblemsError(problems)
    return world
