"""How fluids look and move, as numbers: the checks of the fluids work, run from a checkout.

    python tools/dev/fluids.py

Prints, for the bundled mods:

- how fast a clump of sand (12 x 12) sinks through deep water, and how far it
  spreads (a plume that keeps together spreads little);
- how many frames a tank of 30 rows of sand over 50 of water takes to put 95%
  of its sand in the bed, and oil under water to rise above it;
- the longest run of *striped* rows at any frame (:func:`striped_rows`) for a
  gas cloud rising through air, oil under water, sand through water and the
  heated pool of ``examples/timeline.toml`` (steam in water);
- how many frames after the 300th of ``examples/boiling_pool.toml`` show steam
  under water colder than 95 degrees.

Each figure is a run of the engine, deterministic: the same on any machine.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from sandmod.world.loading import load_ruleset, load_world
from sandmod.world.world import World

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: A gas that neither cools nor decays, so that only motion changes it.
VAPOUR = """
[mod]
name = "vapour"
version = "1.0.0"
requires = ["water"]

[elements.vapour]
archetype = "gas"
color = "#dddddd"
density = 0.6
dispersion = 3
"""


def striped_rows(cells: np.ndarray, a: int, b: int) -> int:
    """The longest run of rows of the mixing region each over 80% ``a`` while both rows beside it are
    over 80% ``b``, or the other way round (0 for a mixture, all but the region's end rows for a
    comb). The mixing region is the rows where both reach (from the lower of their top rows to the
    higher of their bottom ones); rows of it whose cells are less than a fifth one or the other
    (drops in the air) count as neither."""
    rows_a, rows_b = np.flatnonzero((cells == a).any(1)), np.flatnonzero((cells == b).any(1))
    if len(rows_a) == 0 or len(rows_b) == 0:
        return 0
    region = cells[max(rows_a.min(), rows_b.min()) : min(rows_a.max(), rows_b.max()) + 1]
    filled = ((region == a) | (region == b)).sum(1)
    share = np.where(filled > 0, (region == a).sum(1) / np.maximum(filled, 1), 0.5)
    counted = filled >= 0.2 * cells.shape[1]
    high, low = counted & (share > 0.8), counted & (share < 0.2)
    striped = np.zeros(len(share), bool)
    striped[1:-1] = (high[1:-1] & low[:-2] & low[2:]) | (low[1:-1] & high[:-2] & high[2:])
    longest = run = 0
    for row in striped:
        run = run + 1 if row else 0
        longest = max(longest, run)
    return longest


def _layers(ruleset, lower: str, upper: str, size: int = 96, empty: int = 20) -> World:
    world = World(ruleset, size, size, seed=5)
    y = np.arange(size)[:, None] * np.ones((1, size), int)
    band = (size - empty) // 2
    world.paint((y >= empty) & (y < empty + band), ruleset.index(upper))
    world.paint(y >= empty + band, ruleset.index(lower))
    return world


def _tank(ruleset, upper: str, lower: str) -> World:
    """30 rows of ``upper`` over 50 of ``lower`` on a floor of stone, 64 wide."""
    world = World(ruleset, 64, 81, seed=5)
    y = np.arange(81)[:, None] * np.ones((1, 64), int)
    world.paint(y < 30, ruleset.index(upper))
    world.paint((y >= 30) & (y < 80), ruleset.index(lower))
    world.paint(y == 80, ruleset.index("stone"))
    return world


def clump(ruleset) -> str:
    world = World(ruleset, 96, 200, seed=3)
    y, x = np.mgrid[:200, :96]
    world.paint((y >= 10) & (y < 199), ruleset.index("water"))
    world.paint(y == 199, ruleset.index("stone"))
    world.paint((y >= 14) & (y < 26) & (x >= 42) & (x < 54), ruleset.index("sand"))
    rows = []
    for _ in range(100):
        world.step()
        ys = np.nonzero(world.cells == ruleset.index("sand"))[0]
        rows.append((ys.mean(), ys.std()))
    return (
        f"a clump of sand in deep water: sinks {(rows[60][0] - rows[10][0]) / 50:.2f} cell a frame (frames 10-60); "
        f"its rows' spread (std) {rows[10][1]:.1f} at frame 10, {rows[60][1]:.1f} at 60, {rows[99][1]:.1f} at 100"
    )


def tanks(ruleset) -> list[str]:
    sand, water, oil = (ruleset.index(name) for name in ("sand", "water", "oil"))
    world = _tank(ruleset, "sand", "water")
    for frame in range(1, 3001):
        world.step()
        if (np.nonzero(world.cells == sand)[0] >= 50).mean() >= 0.95:
            break
    lines = [f"30 rows of sand over 50 of water: 95% of the sand in the bed after {frame} frames"]
    world = _tank(ruleset, "water", "oil")
    for frame in range(1, 3001):
        world.step()
        if np.nonzero(world.cells == oil)[0].mean() < np.nonzero(world.cells == water)[0].mean():
            break
    return lines + [f"30 rows of water over 50 of oil: the oil above the water after {frame} frames"]


def stripes(ruleset) -> list[str]:
    def longest(world: World, a: int, b: int, frames: int, box=(slice(None), slice(None))) -> int:
        most = 0
        for _ in range(frames):
            world.step()
            most = max(most, striped_rows(world.cells[box], a, b))
        return most

    vapour = ruleset.index("vapour")
    cloud = World(ruleset, 96, 96, seed=5)
    y, x = np.mgrid[:96, :96]
    cloud.paint((y >= 60) & (y < 90) & (x >= 28) & (x < 68), vapour)
    pool = load_world(EXAMPLES / "timeline.toml")
    steam, water = pool.ruleset.index("steam"), pool.ruleset.index("water")
    runs = {
        "gas rising through air": longest(cloud, vapour, 0, 150),
        "oil under water": longest(_layers(ruleset, "oil", "water"), ruleset.index("oil"), ruleset.index("water"), 600),
        "sand through water": longest(_layers(ruleset, "water", "sand"), ruleset.index("water"), ruleset.index("sand"), 400),
        "steam in timeline.toml's heated pool": longest(pool.world, steam, water, 480, (slice(60, 112), slice(114, 180))),
    }
    return [f"striped rows in a row, at most, {name}: {most}" for name, most in runs.items()]


def cold_steam() -> str:
    loaded = load_world(EXAMPLES / "boiling_pool.toml")
    world, steam, water = loaded.world, loaded.ruleset.index("steam"), loaded.ruleset.index("water")
    frames = 0
    for frame in range(1, 1201):
        world.step()
        under = np.zeros(world.cells.shape, bool)
        under[1:] = (world.cells[1:] == steam) & (world.cells[:-1] == water)
        frames += frame > 300 and bool((under & (world.temperature() < 95)).any())
    return f"boiling_pool.toml, frames 301-1200 with steam under water colder than 95 degrees: {frames}"


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "vapour.toml").write_text(VAPOUR, encoding="utf-8")
        ruleset = load_ruleset(mod_dirs=[Path(folder)])
    for line in [clump(ruleset), *tanks(ruleset), *stripes(ruleset), cold_steam()]:
        print(line, flush=True)


if __name__ == "__main__":
    main()
