"""How hot cells look: they glow from the Draper point on, a level brighter every step, and
what a colour looks like at a temperature. Read by the colours (:mod:`.compiler`), by the forms
an element makes of itself (:mod:`.definitions`), and by the pixels' reference in numpy."""

from __future__ import annotations

#: Hot cells glow: from this temperature on, and a level brighter every GLOW_STEP degrees.
GLOW_FROM = 525.0  # the Draper point, where hot things start to glow red
GLOW_STEP = 300.0
GLOW_COLOURS = ((170, 40, 10), (255, 120, 25), (255, 225, 140))  # dull red, orange, yellow-white
GLOW_MIX = (0.45, 0.65, 0.8)  # how much of the glow colour covers the element's own


def lean(color: str, toward: str, share: float = 0.5) -> str:
    """``color`` (#rrggbb) moved ``share`` of the way to ``toward``."""
    a, b = bytes.fromhex(color[1:]), bytes.fromhex(toward[1:])
    return "#" + bytes(round(x + (y - x) * share) for x, y in zip(a, b)).hex()


def glowing(color: str, celsius: float) -> str:
    """``color`` as a cell of it looks at ``celsius`` (see :data:`GLOW_FROM`): a molten form looks as
    hot as its element does where it melts, not duller (it glows only when hotter than it is placed)."""
    if celsius < GLOW_FROM:
        return color
    level = min(len(GLOW_COLOURS) - 1, int((celsius - GLOW_FROM) // GLOW_STEP))
    return lean(color, "#" + bytes(GLOW_COLOURS[level]).hex(), GLOW_MIX[level])
