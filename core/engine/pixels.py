"""Frames to pixels, compiled: what every cell shows, as colour indices or as RGB.

A cell shows its element's colour in its own shade (a particle shows what it
carries); a scorched cell a darker shade; a cell hotter than its element's
glow point glows red, orange, then yellow-white, a level every GLOW_STEP
degrees (see :class:`sandmod.rules.colours.Looks`): an index into the
ruleset's ``colours``, which :func:`rgb` turns into RGB. The heat view shows every
cell's temperature instead, on one colour scale for all elements.

Each function takes the world's arrays and writes into ``out``, for the
whole world or only the chunks marked in ``chunks`` (a world's ``awake``
after a step: the chunks that may have changed), so that a window redraws
only what changed.
"""

from __future__ import annotations

import numpy as np

from .jit import njit
from .layout import CHUNK_SHIFT, MAX_TEMPERATURE, MIN_TEMPERATURE, SCORCHED, TEMP_ONE

#: The heat view's colours: (degrees Celsius, RGB), linear between them.
HEAT_SCALE = (
    (MIN_TEMPERATURE, (0, 0, 40)),
    (-50.0, (20, 40, 150)),
    (0.0, (40, 110, 210)),
    (20.0, (20, 20, 30)),
    (100.0, (110, 20, 110)),
    (300.0, (200, 20, 40)),
    (600.0, (255, 70, 0)),
    (1000.0, (255, 170, 0)),
    (2000.0, (255, 250, 90)),
    (MAX_TEMPERATURE, (255, 255, 255)),
)


def heat_colours() -> np.ndarray:
    """The heat view's colour of every whole degree from MIN_TEMPERATURE to MAX_TEMPERATURE, uint8 (n, 3)."""
    degrees = np.arange(int(MIN_TEMPERATURE), int(MAX_TEMPERATURE) + 1, dtype=float)
    stops = np.array([t for t, _ in HEAT_SCALE])
    colours = np.array([c for _, c in HEAT_SCALE], float)
    return np.stack([np.interp(degrees, stops, colours[:, k]) for k in range(3)], axis=1).round().astype(np.uint8)


@njit(cache=True)
def _units(energy, recip):
    """A cell's temperature in TEMP_ONE units, as the kernel reads it (exact on both sides of 0)."""
    return (energy * recip) >> 32 if energy >= 0 else -((-energy * recip) >> 32)


@njit(cache=True)
def colour_indices(cells, carry, shade, flags, heat, heat_recip, shows_held, normal, scorched, glow, glow_from, glow_step, glow_energy, chunks, out):
    """Write every cell's colour index into ``out`` (uint16, the world's shape); ``chunks``: a
    mask of the chunks to draw (empty: all). ``glow_energy``: :attr:`sandmod.rules.colours.Looks.glow_energy`.
    A cell of an element that ``shows_held`` (a particle, a dye) holding an element shows that one."""
    height, width = cells.shape
    shades, scorched_shades, levels = normal.shape[1], scorched.shape[1], glow.shape[1]
    every = chunks.shape[0] == 0
    glowing = heat.max() >= glow_energy[:, 0].min()  # none: leave the glow out (it costs a third)
    for y in range(height):
        for x in range(width):
            if not every and chunks[y >> CHUNK_SHIFT, x >> CHUNK_SHIFT] == 0:
                continue
            e = cells[y, x]
            tone = np.int64(shade[y, x])
            energy = np.int64(heat[y, x])
            if carry[y, x] == 0 or shows_held[e] == 0:
                index = normal[e, (tone * shades) >> 8]
                if (flags[y, x] & SCORCHED) != 0:
                    index = scorched[e, (tone * scorched_shades) >> 8]
                if glowing:
                    level = 0  # no branch: hot cells are scattered
                    for k in range(1, levels):
                        level += energy >= glow_energy[e, k]
                    hot = glow[e, level]
                    index = hot if energy >= glow_energy[e, 0] else index
            else:  # a flying particle shows what it carries (a dye what it holds), at its own temperature
                shown = carry[y, x]
                index = normal[shown, (tone * shades) >> 8]
                if (flags[y, x] & SCORCHED) != 0:
                    index = scorched[shown, (tone * scorched_shades) >> 8]
                over = _units(energy, heat_recip[e]) - glow_from[shown]
                if over > 0:
                    index = glow[shown, min(over // glow_step, levels - 1)]
            out[y, x] = index


@njit(cache=True)
def heat_rgb(cells, heat, heat_recip, colours, chunks, out):
    """Write every cell's heat-view colour into ``out`` (uint8, (height, width, 3)); ``colours`` from
    :func:`heat_colours`; ``chunks`` as in :func:`colour_indices`."""
    height, width = cells.shape
    lowest = np.int64(MIN_TEMPERATURE)
    every = chunks.shape[0] == 0
    for y in range(height):
        for x in range(width):
            if not every and chunks[y >> CHUNK_SHIFT, x >> CHUNK_SHIFT] == 0:
                continue
            degrees = _units(np.int64(heat[y, x]), heat_recip[cells[y, x]]) // TEMP_ONE
            k = min(max(degrees - lowest, 0), len(colours) - 1)
            out[y, x, 0] = colours[k, 0]
            out[y, x, 1] = colours[k, 1]
            out[y, x, 2] = colours[k, 2]


@njit(cache=True)
def rgb(indices, colours, chunks, out):
    """Write the colour of every index in ``indices`` (a frame of :func:`colour_indices`) into ``out``
    (uint8, (height, width, 3)); ``colours``: the ruleset's; ``chunks`` as in :func:`colour_indices`."""
    height, width = indices.shape
    every = chunks.shape[0] == 0
    for y in range(height):
        for x in range(width):
            if not every and chunks[y >> CHUNK_SHIFT, x >> CHUNK_SHIFT] == 0:
                continue
            k = indices[y, x]
            out[y, x, 0] = colours[k, 0]
            out[y, x, 1] = colours[k, 1]
            out[y, x, 2] = colours[k, 2]
