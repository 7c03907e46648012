"""What a run measures: the built-in metrics and the plugins' (``register_metrics``)."""

from __future__ import annotations

from typing import Callable

import numpy as np

#: The built-in metrics, each a name a sweep's ``[metrics] names`` may list.
BUILT_IN = ("counts", "centre", "extent", "awake", "heat")

_BAND = 256  # rows measured at a time, so that no temporary array is the size of the world


def measure(world, names: list[str] | None, plugins: dict[str, Callable]) -> dict[str, float | int]:
    """The metrics ``names`` (None: all) of a world as it is now.

    ``counts`` gives ``count.ELEMENT``, the cells of each element of the world's mods (0 when
    there are none); ``centre`` ``centre_x.ELEMENT`` and ``centre_y.ELEMENT``, its centre of mass
    (none when absent); ``extent`` ``height.ELEMENT`` and ``width.ELEMENT``, the rows and columns it
    spans (a heap's height and width; 0 when absent); ``awake`` the share of chunks awake; ``heat``
    the total heat energy. A plugin's metric is its name, or ``NAME.KEY`` for each key of a dict.
    """
    wanted = (lambda name: names is None or name in names)
    values: dict[str, float | int] = {}
    if wanted("counts") or wanted("centre") or wanted("extent"):
        values.update(_element_metrics(world, wanted))
    if wanted("awake"):
        values["awake"] = round(world.awake_fraction, 6)
    if wanted("heat"):
        values["heat"] = float(world.heat_total())
    for name, function in sorted(plugins.items()):
        if wanted(name):
            result = function(world)
            if isinstance(result, dict):
                values.update({f"{name}.{key}": float(v) for key, v in result.items()})
            else:
                values[name] = float(result)
    return values


def _element_metrics(world, wanted) -> dict[str, float | int]:
    cells = world.cells
    kinds = len(world.ruleset.elements)
    count = np.zeros(kinds, np.int64)
    sum_x = np.zeros(kinds)
    sum_y = np.zeros(kinds)
    rows = np.zeros((kinds, cells.shape[0]), bool)
    columns = np.zeros((kinds, cells.shape[1]), bool)
    xs = np.arange(cells.shape[1], dtype=np.float64)
    for top in range(0, cells.shape[0], _BAND):
        band = cells[top : top + _BAND]
        flat = band.ravel()
        count += np.bincount(flat, minlength=kinds)
        sum_x += np.bincount(flat, weights=np.broadcast_to(xs, band.shape).ravel(), minlength=kinds)
        per_row = np.stack([np.bincount(row, minlength=kinds) for row in band], axis=1)  # (kinds, rows of the band)
        sum_y += per_row @ np.arange(top, top + band.shape[0], dtype=np.float64)
        rows[:, top : top + band.shape[0]] = per_row > 0
        columns[band, np.broadcast_to(np.arange(band.shape[1]), band.shape)] = True
    values: dict[str, float | int] = {}
    for element in range(1, kinds):
        name = world.ruleset.elements[element].id
        n = int(count[element])
        if wanted("counts"):
            values[f"count.{name}"] = n
        if wanted("centre") and n:
            values[f"centre_x.{name}"] = round(float(sum_x[element] / n), 6)
            values[f"centre_y.{name}"] = round(float(sum_y[element] / n), 6)
        if wanted("extent"):
            values[f"height.{name}"] = _span(rows[element])
            values[f"width.{name}"] = _span(columns[element])
    return values


def _span(present: np.ndarray) -> int:
    """From the first True to the last, both in (0 when none is)."""
    found = np.flatnonzero(present)
    return int(found[-1] - found[0] + 1) if found.size else 0
