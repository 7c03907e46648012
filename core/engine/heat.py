"""Heat: conduction between touching cells and cooling to the outside, over the awake chunks.

The per-cell effects of heat (phase changes, fire) are :mod:`.fire`'s; a move
that changes the heat field stirs its chunk (:func:`stirs`), so that
:func:`conduct` sweeps it again.
"""

from __future__ import annotations

from .cells import _at, _energy, _scaled, _temperature, _within
from .chunks import _mark, _wake
from .jit import compiled, inlined
from .layout import CACHED_CELLS, CHUNK_SHIFT, LINE_CELLS
from .prefetch import prefetch

EVEN, SWEPT = 1, 2  # marks of conduct's `even`: heat known to be even; being swept whole this frame


@compiled
def _cooling_loss(energy, cap, cooling, ambient):
    """The heat a cell of ``cooling`` (of 256) gains per frame towards the outside's temperature (a loss when warmer)."""
    return _scaled(_energy(ambient, cap) - energy, cooling) if cooling != 0 else 0


@inlined
def stirs(heat_a, cap_a, cooling_a, heat_b, cap_b, cooling_b, ambient):
    """Does a swap of cells a and b change the heat field? Not where two cells of one temperature
    trade places and neither cools (see :func:`conduct`)."""
    return (
        heat_a * cap_b != heat_b * cap_a
        or _cooling_loss(heat_a, cap_a, cooling_a, ambient) != 0
        or _cooling_loss(heat_b, cap_b, cooling_b, ambient) != 0
    )


@compiled
def conduct(s, t, frame, awake, woken, even, stirred, x0, y0, x1, y1):
    """Heat flows between touching cells of the awake chunks among rows y0..y1-1 and
    columns x0..x1-1 (and the row below and column right of them), and cells with
    ``cooling`` lose heat to the outside.

    Each touching pair exchanges ``g * (T_a - T_b)`` of energy, where ``g`` is
    the smaller of the two cells' conductance (conductivity x capacity / 4),
    rounded towards zero. One side's temperature then moves by at most a
    quarter of the gap, so the two never swap places and no cell overshoots:
    the scheme is stable for any conductivities. What one cell loses the other
    gains, so conduction alone conserves the total exactly. The sweep runs
    forwards on even frames and backwards on odd ones, so heat has no
    favourite direction. A cell whose heat changes wakes the chunks around it.

    Even heat is skipped. A chunk is marked ``even`` (EVEN) when a whole sweep of
    it (marked SWEPT meanwhile) finds every pair it looks at (right and down,
    any conductance) at exactly one temperature and no cell cooling. Until a change has ``stirred``
    it (see :func:`sandmod.engine.kernel.step_region`; :func:`~sandmod.engine.kernel.step` clears the marks of stirred
    chunks), a sweep there would change nothing, so it is left out.
    """
    cells, heat = s.cells, s.heat
    height, width = cells.shape
    heat_cap, heat_recip, conductance, cooling = t.heat_cap, t.heat_recip, t.conductance, t.cooling
    ambient = int(t.temp_start[0])  # the air's temperature is the world's outside
    backwards = (frame & 1) == 1
    far = height * width > CACHED_CELLS  # prefetch the next row (see sandmod.engine.kernel.step_region)
    first_cx = x0 >> CHUNK_SHIFT
    segments = ((x1 - 1) >> CHUNK_SHIFT) - first_cx + 1
    first_cy, end_cy = y0 >> CHUNK_SHIFT, ((y1 - 1) >> CHUNK_SHIFT) + 1
    for cy in range(first_cy, end_cy):
        for cx in range(first_cx, first_cx + segments):
            if (awake[_at(cy, cx)] != 0 or woken[_mark(cy, cx)] != 0) and (even[_at(cy, cx)] != EVEN or stirred[_mark(cy, cx)] != 0):
                even[_at(cy, cx)] = SWEPT  # swept whole: even, unless a pair at two temperatures or a cooling cell stirs it
    for r in range(y1 - y0):
        y = y1 - 1 - r if backwards else y0 + r
        cy = y >> CHUNK_SHIFT
        for j in range(segments):
            cx = first_cx + (segments - 1 - j if backwards else j)
            if awake[_at(cy, cx)] == 0 and woken[_mark(cy, cx)] == 0:
                continue
            if even[_at(cy, cx)] == EVEN and stirred[_mark(cy, cx)] == 0:
                continue  # one temperature throughout, as its last sweep found
            uneven = False
            sx0 = max(x0, cx << CHUNK_SHIFT)
            sx1 = min(x1, (cx + 1) << CHUNK_SHIFT)
            changed_x0, changed_x1 = sx1, sx0 - 1  # the first and last cell of the segment whose heat changed
            ahead = y - 1 if backwards else y + 2  # the row the sweep reads next
            if far and _within(ahead, height):
                for ax in range(sx0, sx1, LINE_CELLS):
                    prefetch(cells, ahead, ax)
                    prefetch(heat, ahead, ax)
            for i in range(sx1 - sx0):
                x = sx1 - 1 - i if backwards else sx0 + i
                e = cells[_at(y, x)]
                energy = int(heat[_at(y, x)])
                changed = False
                loss = _cooling_loss(energy, heat_cap[e], cooling[e], ambient)
                if loss != 0:
                    energy += loss
                    heat[_at(y, x)] = energy
                    changed = True
                g_own = conductance[e]
                for k in range(2):
                    nx = x + 1 - k
                    ny = y + k
                    if nx >= width or ny >= height:
                        continue
                    n = cells[_at(ny, nx)]
                    other = int(heat[_at(ny, nx)])
                    if other * heat_cap[e] == energy * heat_cap[n]:
                        continue  # the common case: the same temperature (E_a / C_a == E_b / C_b)
                    uneven = True
                    g = min(g_own, conductance[n])
                    if g == 0:
                        continue
                    gap = _temperature(energy, heat_recip[e]) - _temperature(other, heat_recip[n])
                    flow = _scaled(gap * g, 1)
                    if flow != 0:
                        energy -= flow
                        heat[_at(y, x)] = energy
                        heat[_at(ny, nx)] = other + flow
                        changed = True
                if changed:
                    changed_x0 = min(changed_x0, x)
                    changed_x1 = max(changed_x1, x)
            if changed_x0 <= changed_x1:  # wake (and stir) the cells next to them and to their partners
                _wake(woken, stirred, True, max(changed_x0 - 1, 0), max(y - 1, 0), min(changed_x1 + 2, width - 1), min(y + 2, height - 1))
            if uneven:
                stirred[_mark(cy, cx)] = 1
    for cy in range(first_cy, end_cy):
        for cx in range(first_cx, first_cx + segments):
            if even[_at(cy, cx)] == SWEPT:
                even[_at(cy, cx)] = EVEN
