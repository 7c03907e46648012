"""Fluids and gases: exchanges by chance, no combs of alternating rows, nothing starved of its own update."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from conftest import make_world, run, write_mods
from sandmod.world.loading import load_ruleset, load_world
from sandmod.world.world import World

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

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


@pytest.fixture(scope="module")
def with_vapour(registry, tmp_path_factory):
    """Every bundled mod and a gas that neither cools nor decays, so that only motion changes it."""
    folder = write_mods(tmp_path_factory.mktemp("mods"), {"vapour.toml": VAPOUR})
    return load_ruleset(registry=registry, mod_dirs=[folder])


def alternation(cells: np.ndarray, a: int, b: int) -> float:
    """The share of the rows where ``a`` and ``b`` meet that are mostly one while both rows beside
    them are mostly the other (over the columns ``a`` reaches): 0 for a mixture, 1 for a comb."""
    rows_a, rows_b = np.flatnonzero((cells == a).any(1)), np.flatnonzero((cells == b).any(1))
    if len(rows_a) == 0 or len(rows_b) == 0:
        return 0.0
    top, bottom = max(rows_a.min(), rows_b.min()), min(rows_a.max(), rows_b.max())
    if bottom - top < 2:
        return 0.0
    columns = np.flatnonzero((cells[top : bottom + 1] == a).any(0))
    region = cells[top : bottom + 1, columns.min() : columns.max() + 1]
    both = ((region == a) | (region == b)).sum(1)
    share = np.where(both > 0, (region == a).sum(1) / np.maximum(both, 1), 0.5)
    high, low = share > 0.6, share < 0.4
    return float(((high[1:-1] & low[:-2] & low[2:]) | (low[1:-1] & high[:-2] & high[2:])).mean())


def test_the_stripe_measure_tells_a_comb_from_a_mixture():
    comb = np.where(np.arange(20)[:, None] % 2 == 0, 1, 2) * np.ones((1, 30), int)
    mixture = np.random.default_rng(1).choice([1, 2], size=(20, 30))
    assert alternation(comb, 1, 2) == 1.0
    assert alternation(mixture, 1, 2) < 0.05


def layers(ruleset, lower: str, upper: str, size: int = 96, empty_rows: int = 20) -> World:
    """``upper`` over ``lower``, each a third of a square world, the rest empty above them."""
    world = World(ruleset, size, size, seed=5)
    y = np.arange(size)[:, None] * np.ones((1, size), int)
    band = (size - empty_rows) // 2
    world.paint((y >= empty_rows) & (y < empty_rows + band), ruleset.index(upper))
    world.paint(y >= empty_rows + band, ruleset.index(lower))
    return world


@pytest.mark.parametrize(("lower", "upper", "frames"), [("oil", "water", 600), ("water", "sand", 400)])
def test_a_lighter_layer_under_a_heavier_one_mixes_without_stripes_and_comes_up(ruleset, lower, upper, frames):
    world = layers(ruleset, lower, upper)
    a, b = ruleset.index(lower), ruleset.index(upper)
    stripes = [alternation(run(world, 1).cells, a, b) for _ in range(frames)]
    assert max(stripes) < 0.1 and np.mean(stripes) < 0.01
    # In the end the lighter one is on top: its mean row above the heavier one's.
    rows = np.arange(world.height)[:, None] * np.ones((1, world.width))
    assert rows[world.cells == a].mean() < rows[world.cells == b].mean()


def test_a_cloud_of_gas_rises_raggedly_not_in_rows(with_vapour):
    world = World(with_vapour, 96, 96, seed=5)
    y, x = np.mgrid[:96, :96]
    vapour = with_vapour.index("vapour")
    world.paint((y >= 60) & (y < 90) & (x >= 28) & (x < 68), vapour)
    start = world.counts()
    stripes = [alternation(run(world, 1).cells, vapour, 0) for _ in range(120)]
    assert max(stripes) < 0.1 and np.mean(stripes) < 0.01
    assert world.counts() == start  # motion alone: every cell is still there
    assert y[world.cells == vapour].mean() < 50  # and it rose


def test_fluids_of_every_kind_trading_places_neither_create_nor_lose_cells(with_vapour):
    rng = np.random.default_rng(3)
    names = ["empty", "sand", "water", "oil", "vapour", "stone", "acid"]
    world = World(with_vapour, 80, 60, seed=3)
    choice = rng.choice(len(names) - 1, size=(60, 80), p=[0.3, 0.15, 0.2, 0.15, 0.15, 0.05])
    for k, name in enumerate(names[1:-1], start=1):
        world.paint(choice == k, with_vapour.index(name))
    before = world.counts()
    for _ in range(300):
        world.step()
        assert world.counts() == before


def test_a_cell_due_to_change_is_not_moved_out_of_its_turn(ruleset):
    # Cold steam under water and beside it: water would trade places with it every frame, but
    # steam below its condensation point condenses on its own turn, the first frame.
    world = make_world(ruleset, ["#WWWW#", "#WGWW#", "#GWGW#", "######"])
    steam = world.cells == ruleset.index("steam")
    world.set_temperature(steam, 30.0)
    world.set_temperature(~steam, 30.0)
    run(world, 1)
    assert "water:steam" not in world.counts()


def test_steam_trapped_in_water_rises_out_or_condenses(ruleset):
    # Under the water's surface, steam is a bubble on its way up, never a checkerboard that stays.
    world = make_world(ruleset, ["#......#", "#WWWWWW#", "#WWWWWW#", "#GWGWGW#", "#WGWGWG#", "########"])
    world.set_temperature(world.cells == ruleset.index("steam"), 150.0)
    run(world, 60)
    rows = [row for row in world.cells[1:5] if (row == ruleset.index("water")).any()]
    assert not any((row == ruleset.index("steam")).any() for row in rows[1:])


def test_the_boiling_pool_boils_dry():
    loaded = load_world(EXAMPLES / "boiling_pool.toml")
    world, ruleset = loaded.world, loaded.ruleset
    water, steam = ruleset.index("water"), ruleset.index("steam")
    condenses = float(ruleset.elements[steam].spec.cooled.below)
    pool = (slice(86, 96), slice(48, 112))  # the bottom of the pot, inside its titanium walls
    start = int((world.cells[pool] == water).sum())
    in_pool, was_cold = [], np.zeros(world.cells.shape, bool)
    for frame in range(1, 1801):
        world.step()
        # Steam cooled below its condensation point after its turn (by a later tile's heat flow at a
        # seam) condenses on its next turn: never cold at the same place two frames running.
        cold = (world.cells == steam) & (world.temperature() < condenses)
        assert not (cold & was_cold).any(), f"frame {frame}: steam colder than {condenses} stays at {np.argwhere(cold & was_cold)[0]}"
        was_cold = cold
        in_pool.append(int((world.cells[pool] == water).sum()))
    # It boils down to a quarter within 300 frames, and stays low: a film fed by what rains back,
    # while the water that rains outside the pot gathers on the crust of cooled lava.
    assert min(in_pool[:300]) < start // 4
    assert max(in_pool[300:]) < start * 0.45, max(in_pool[300:])
    outside = (world.cells == water).sum() - (world.cells[pool] == water).sum()
    assert outside > start // 4


@pytest.mark.parametrize("name", ["boiling_pool", "lava_lake", "fountain", "forest_fire", "hourglass"])
def test_no_liquid_rests_on_air_for_more_than_a_few_frames(name):
    world = load_world(EXAMPLES / f"{name}.toml").world
    liquid = np.array([e.spec.archetype == "liquid" for e in world.ruleset.elements])
    resting, before = np.zeros(world.cells.shape, int), None
    for frame in range(400):
        world.step()
        cells = world.cells
        on_air = np.zeros(cells.shape, bool)
        on_air[:-1] = liquid[cells[:-1]] & (cells[1:] == 0) & (world.state.vy[:-1] == 0)
        same = cells.astype(np.int64) * 256 + world.state.shade  # the same cell still there, as far as one can tell
        resting = np.where(on_air & (same == before), resting + 1, on_air.astype(int))
        before = same
        assert resting.max() <= 3, f"frame {frame}: a liquid rests on air at {np.unravel_index(resting.argmax(), resting.shape)}"
