"""Build a :class:`World` from a validated world file: paint the scene, set up emitters."""

from __future__ import annotations

import numpy as np

from .compiler import Ruleset
from .errors import Problem, ProblemsError
from .shapes import circle_mask, fill_mask, line_mask, rect_mask
from .tomlsource import TomlSource
from .world import Emitter, World
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
    world = World(ruleset, info.width, info.height, info.seed if seed is None else seed)
    problems: list[Problem] = []

    def element(table: str, number: int, name: str) -> int | None:
        try:
            return ruleset.index(name)
        except KeyError as exc:
            problems.append(source.problem((table, number, "element"), exc.args[0]))
            return None

    for number, shape in enumerate(spec.scene):
        index = element("scene", number, shape.element)
        mask = shape_mask(shape, world.cells)
        if not mask.any():
            problems.append(source.problem(("scene", number), f"the shape lies outside the {info.width}x{info.height} world"))
        elif index is not None:
            world.paint(mask, index)
    for number, emitter in enumerate(spec.emitters):
        index = element("emitters", number, emitter.element)
        mask = shape_mask(emitter, world.cells)
        if not mask.any():
            problems.append(source.problem(("emitters", number), f"the shape lies outside the {info.width}x{info.height} world"))
        elif index is not None:
            world.emitters.append(Emitter(mask, index, emitter.start, emitter.stop, emitter.chance))
    if problems:
        raise ProblemsError(problems)
    return world
