"""How elements look: every colour a cell can show, each element's shades, scorched shades and
glow levels, the same for an element however many others are loaded."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ..engine.layout import temperature_units
from ..formats.modspec import Element
from .glow import GLOW_COLOURS, GLOW_FROM, GLOW_MIX, GLOW_STEP

if TYPE_CHECKING:
    from .compiler import ElementInfo


def _hex_rgb(color: str) -> tuple[int, int, int]:
    return int(color[1:3], 16), int(color[3:5], 16), int(color[5:7], 16)


SCORCH_DARKEN = 0.45  # a scorched cell keeps this much of its brightness


SHADES = 8  # colours each element's cells pick from


SCORCHED_SHADES = 4  # of a scorched cell


@dataclass(frozen=True)
class Looks:
    """Colour indices (rows of :attr:`Ruleset.colours`) per element: its shades, its scorched shades,
    and its glow levels; the same for an element however many others are loaded."""

    normal: np.ndarray  # uint16[n, SHADES]
    scorched: np.ndarray  # uint16[n, SCORCHED_SHADES]
    glow: np.ndarray  # uint16[n, len(GLOW_COLOURS)]
    glow_from: np.ndarray  # int64[n]: temperature (TEMP_ONE units) where it starts to glow
    glow_energy: np.ndarray  # int64[n, len(GLOW_COLOURS)]: heat energy from which it glows at each level

    @property
    def shades(self) -> int:
        """How many colours each element's cells pick from."""
        return self.normal.shape[1]


def _glow_energies(glow_from: list[int], glow_step: int, heat_recip: list[int]) -> np.ndarray:
    """For each element, the heat energies from which a cell of it glows at each level (int64,
    (n, levels)), from the heat capacities' ``heat_recip``: the least energy whose temperature,
    read as the kernel reads it, is above its glow point, then at least a glow step, two, ...
    past it. So the pixels compare energies, and multiply nothing, for all but flying particles."""
    table = np.empty((len(glow_from), len(GLOW_COLOURS)), np.int64)
    for e, (start, recip) in enumerate(zip(glow_from, heat_recip)):
        for level in range(len(GLOW_COLOURS)):
            units = start + 1 if level == 0 else start + level * glow_step  # temperature (energy * recip) >> 32 must reach
            table[e, level] = -(-(units << 32) // recip)  # the least energy whose product reaches units << 32
    table[0] = np.iinfo(np.int64).max  # the air never glows
    return table


def colour_table(elements: Sequence[ElementInfo], heat_recip: np.ndarray) -> tuple[np.ndarray, Looks]:
    """Every colour a cell can show (uint8 (colours, 3)), and each element's indices into it: every
    element's shades first, in element order, then their darker scorched shades, then their glow
    levels (so that a format of few colours that takes them in order takes what most cells show
    first). The empty cell (air) gets shades only: it neither scorches nor glows (its scorched and
    glow indices are its first shade).
    """
    n = len(elements)
    # An element hot by nature (lava, fire) already looks hot: it glows only when hotter still.
    glow_from = [temperature_units(max(GLOW_FROM, e.spec.temperature)) for e in elements]
    looks = Looks(
        np.zeros((n, SHADES), np.uint16),
        np.zeros((n, SCORCHED_SHADES), np.uint16),
        np.zeros((n, len(GLOW_COLOURS)), np.uint16),
        np.array(glow_from, np.int64),
        _glow_energies(glow_from, temperature_units(GLOW_STEP), heat_recip.tolist()),
    )
    rows: list[np.ndarray] = []

    def add(colours: list[np.ndarray]) -> np.ndarray:
        rows.extend(colours)
        return np.arange(len(rows) - len(colours), len(rows))

    made = [_element_colours(info.spec) for info in elements]
    for info, shades in zip(elements, made):
        looks.normal[info.index] = add(shades[:SHADES])
    looks.scorched[0], looks.glow[0] = looks.normal[0, 0], looks.normal[0, 0]
    for info, shades in zip(elements[1:], made[1:]):
        looks.scorched[info.index] = add(shades[SHADES : SHADES + SCORCHED_SHADES])
    for info, shades in zip(elements[1:], made[1:]):
        looks.glow[info.index] = add(shades[SHADES + SCORCHED_SHADES :])
    return np.clip(np.round(rows), 0, 255).astype(np.uint8), looks


def _element_colours(spec: Element) -> list[np.ndarray]:
    """An element's colours (RGB, unrounded): its SHADES shades, its SCORCHED_SHADES scorched ones
    and a glow colour per level."""
    colors = [np.array(_hex_rgb(c), float) for c in spec.color]

    def shaded(j: int, count: int) -> np.ndarray:
        levels = -(-count // len(colors))
        v = ((j // len(colors)) + 0.5) / levels  # spread across (0, 1)
        return colors[j % len(colors)] * (1.0 + spec.shade * (2.0 * v - 1.0))

    base = sum(colors) / len(colors)
    return (
        [shaded(j, SHADES) for j in range(SHADES)]
        + [shaded(j, SCORCHED_SHADES) * SCORCH_DARKEN for j in range(SCORCHED_SHADES)]
        + [base * (1 - mix) + np.array(hot) * mix for hot, mix in zip(GLOW_COLOURS, GLOW_MIX)]
    )
