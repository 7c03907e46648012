"""Motion: velocity and gravity, the line traversal, impact spread, resting and knocking, particles."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import write_mods
from sandmod.engine.cells import _line_point
from sandmod.engine.layout import LOOSE
from sandmod.world.loading import load_ruleset
from sandmod.world.shapes import fill_mask
from sandmod.engine.traversal import line_cells
from sandmod.world.world import Emitter, World


def floor(world: World, rows: int = 2) -> None:
    world.paint(np.arange(world.height)[:, None] >= world.height - rows + np.zeros((1, world.width)), world.ruleset.index("stone"))


def pour(ruleset, name: str, drop: int, seed: int = 1, frames: int = 500) -> np.ndarray:
    """Pour ``name`` from ``drop`` cells above a floor until it settles; the columns of its cells."""
    world = World(ruleset, 201, drop + 24, seed)
    floor(world)
    element = ruleset.index(name)
    world.emitters.append(Emitter(np.array([2]), np.array([100]), element, 0, frames, 0.5))
    for _ in range(frames + drop + 300):
        world.step()
    assert not (world.state.flags[world.cells == element] & LOOSE).any()  # all at rest
    return np.nonzero(world.cells == element)[1]


def test_the_kernel_walks_the_same_cells_as_the_python_traversal():
    rng = np.random.default_rng(0)
    pairs = [tuple(int(v) for v in rng.integers(-20, 20, 4)) for _ in range(300)]
    pairs += [(0, 0, sx * a, sy * b) for a, b in [(7, 3), (3, 7), (5, 5), (9, 0)] for sx in (1, -1) for sy in (1, -1)]
    for x0, y0, x1, y1 in pairs:
        steps = max(abs(x1 - x0), abs(y1 - y0))
        if steps == 0:
            continue
        compiled = [tuple(_line_point(x0, y0, x1 - x0, y1 - y0, steps, i)) for i in range(steps + 1)]
        assert compiled == [tuple(c) for c in line_cells(x0, y0, x1, y1)]


def wall_across(rng, size: int) -> np.ndarray:
    """A one-cell-thick line of cells from one edge of a square world to the opposite edge."""
    a, b = (int(v) for v in rng.integers(8, size - 8, 2))
    if rng.random() < 0.5:
        return line_cells(0, a, size - 1, b)
    return line_cells(a, 0, b, size - 1)


@pytest.mark.parametrize("seed", range(8))
def test_nothing_crosses_a_one_cell_wall_at_any_speed_or_angle(ruleset, seed):
    rng = np.random.default_rng(seed)
    size = 64
    world = World(ruleset, size, size, seed)
    stone = ruleset.index("stone")
    wall = wall_across(rng, size)
    world.cells[wall[:, 1], wall[:, 0]] = stone
    side = fill_mask(world.cells, 0, 0)  # the cells on the (0, 0) side of the wall, joined by sides
    ys, xs = np.nonzero(side)
    pick = rng.choice(len(xs), size=min(300, len(xs)), replace=False)
    for name, cells in (("sand", pick[:100]), ("water", pick[100:150])):
        world.paint_cells(ys[cells], xs[cells], ruleset.index(name))
    angles = rng.uniform(0, 2 * np.pi, len(pick) - 150)
    world.spawn_particles(ys[pick[150:]], xs[pick[150:]], ruleset.index("dirt"), 16 * np.cos(angles), 16 * np.sin(angles))
    before = world.counts(carried=True)
    for _ in range(120):
        world.step()
        assert not world.cells[~side & (world.cells != stone)].any()
    assert world.counts(carried=True) == before


def test_a_high_drop_spreads_wider_than_a_low_one(ruleset):
    low, high = pour(ruleset, "sand", 10), pour(ruleset, "sand", 150)
    assert len(low) == len(high)
    assert high.std() > 1.3 * low.std()


def test_impact_spread_decides_how_much_landing_speed_turns_sideways(registry, tmp_path):
    folder = write_mods(
        tmp_path,
        {
            "drops.toml": """
                [mod]
                name = "drops"
                [elements.dead]
                archetype = "powder"
                color = "#ffffff"
                density = 1500
                impact_spread = 0
                [elements.lively]
                archetype = "powder"
                color = "#000000"
                density = 1500
                impact_spread = 1
            """
        },
    )
    drops = load_ruleset(["drops"], [folder], registry)
    dead, lively = pour(drops, "dead", 100, frames=200), pour(drops, "lively", 100, frames=200)
    assert lively.std() > 2 * dead.std()


def test_sand_dirt_and_coal_piles_have_different_slopes(ruleset):
    def steepness(name):
        columns = pour(ruleset, name, 20)
        return np.bincount(columns).max() / columns.std()  # tall and narrow: steep

    sand, dirt, coal = steepness("sand"), steepness("dirt"), steepness("coal")
    assert sand * 1.2 < dirt and dirt * 1.2 < coal


@pytest.fixture(scope="module")
def grains(registry, tmp_path_factory):
    """Two frictionless test powders: one a knock always loosens, one nothing does."""
    folder = write_mods(
        tmp_path_factory.mktemp("grains"),
        {
            "grains.toml": """
                [mod]
                name = "grains"
                [elements.loosey]
                archetype = "powder"
                color = "#ffffff"
                density = 1500
                friction = 0
                inertial_resistance = 0
                [elements.sticky]
                archetype = "powder"
                color = "#000000"
                density = 1500
                friction = 0
                inertial_resistance = 1
            """
        },
    )
    return load_ruleset(["grains"], [folder], registry)


def grain_on_a_pillar(ruleset, name: str) -> World:
    """A resting grain on a one-cell stone pillar: both of its diagonals are open."""
    world = World(ruleset, 9, 8, 0)
    world.paint_cells(np.arange(4, 8), np.full(4, 4), ruleset.index("stone"))
    world.paint_cells(np.array([3]), np.array([4]), ruleset.index(name))
    world.state.flags[3, 4] = 0  # at rest
    return world


@pytest.mark.parametrize("name", ["loosey", "sticky"])
def test_a_resting_grain_stays_put_with_open_diagonals(grains, name):
    world = grain_on_a_pillar(grains, name)
    before = world.cells.copy()
    for _ in range(20):
        world.step()
    assert (world.cells == before).all()


def test_a_moving_neighbour_knocks_a_grain_loose_unless_it_resists(grains):
    moved = {}
    for name in ("loosey", "sticky"):
        world = grain_on_a_pillar(grains, name)
        world.paint_cells(np.array([2]), np.array([5]), grains.index("sticky"))  # falls past its right side
        for _ in range(20):
            world.step()
        moved[name] = world.cells[3, 4] != grains.index(name)
    assert moved == {"loosey": True, "sticky": False}


def test_a_resting_grain_falls_when_the_cell_below_opens(grains):
    world = grain_on_a_pillar(grains, "sticky")
    world.paint_cells(np.array([4]), np.array([4]), 0)
    world.step()
    assert world.cells[4, 4] == grains.index("sticky")


def test_a_settled_pile_is_perfectly_still(ruleset):
    world = World(ruleset, 60, 40, 2)
    floor(world)
    world.emitters.append(Emitter(np.array([1]), np.array([30]), ruleset.index("coal"), 0, 200, 0.5))
    for _ in range(500):
        world.step()
    before = [array.copy() for array in world.state]
    for _ in range(30):
        world.step()
    assert all((a == b).all() for a, b in zip(before, world.state))


def expected_landing(world: World, x: int, y: int, vx: int, vy: int) -> tuple[int, int]:
    """Where a particle flying at a constant whole-cell velocity stops: the last free cell on its path."""
    while True:
        for cx, cy in line_cells(x, y, x + vx, y + vy)[1:]:
            if not (0 <= cx < world.width and 0 <= cy < world.height) or world.cells[cy, cx] != 0:
                return x, y
            x, y = int(cx), int(cy)


@pytest.mark.parametrize("velocity", [(5, 1), (3, 0), (4, -2), (7, 3)])
def test_a_particle_puts_down_exactly_one_cell_where_it_stops(ruleset, velocity):
    world = World(ruleset, 40, 30, 0, gravity=0.0)  # no gravity: a straight flight
    world.paint_cells(np.arange(30), np.full(30, 33), ruleset.index("stone"))
    where = expected_landing(world, 2, 12, *velocity)
    assert world.spawn_particles(np.array([12]), np.array([2]), ruleset.index("coal"), *velocity) == 1
    assert world.counts()["base:particle"] == 1
    while world.counts().get("base:particle"):  # until it lands; the coal then falls on as a powder
        world.step()
        assert world.frame < 15
    assert world.counts()["coal:coal"] == 1
    assert world.cells[where[1], where[0]] == ruleset.index("coal")


def test_a_particle_that_carries_nothing_vanishes_where_it_hits(ruleset):
    world = World(ruleset, 30, 20, 0)
    floor(world)
    world.spawn_particles(np.array([5]), np.array([5]), ruleset.particle, 2.0, -1.0)
    assert world.counts()["base:particle"] == 1
    for _ in range(40):
        world.step()
    assert set(world.counts()) == {"base:empty", "base:stone"}


def test_launched_cells_fly_and_land_as_themselves(ruleset):
    world = World(ruleset, 80, 60, 4)
    floor(world)
    block = np.zeros((60, 80), bool)
    block[40:58, 10:20] = True
    sand = ruleset.index("sand")
    world.paint(block, sand)
    ys, xs = np.nonzero(block)
    assert world.launch(ys, xs, 3.0, -4.0) == block.sum()
    assert world.counts().get("sand:sand", 0) == 0
    shown = world.image()
    assert (shown[block] == ruleset.looks.normal[sand, (world.state.shade[block].astype(int) * ruleset.shades) >> 8]).all()
    for _ in range(150):
        world.step()
        assert world.counts(carried=True)["sand:sand"] == block.sum()
    assert world.counts()["sand:sand"] == block.sum()
    assert np.nonzero(world.cells == sand)[1].mean() > 30  # they flew to the right


def test_motion_alone_neither_creates_nor_loses_cells_of_any_kind(ruleset):
    rng = np.random.default_rng(9)
    legend = np.array([0] + [ruleset.index(n) for n in ("stone", "sand", "dirt", "coal", "water")])
    world = World(ruleset, 90, 70, 9)
    choice = rng.choice(len(legend), size=(70, 90), p=[0.5, 0.1, 0.1, 0.1, 0.1, 0.1])
    for k in range(1, len(legend)):
        world.paint(choice == k, int(legend[k]))
    movers = np.nonzero((choice >= 2) & (rng.random((70, 90)) < 0.2))
    world.launch(*movers, rng.uniform(-8, 8, len(movers[0])), rng.uniform(-8, 2, len(movers[0])))
    before = world.counts(carried=True)
    for _ in range(200):
        world.step()
        assert world.counts(carried=True) == before


def test_world_gravity_scales_every_elements(ruleset):
    def depth_after(gravity):
        world = World(ruleset, 3, 300, 0, gravity=gravity)
        world.paint_cells(np.array([0]), np.array([1]), ruleset.index("sand"))
        for _ in range(30):
            world.step()
        return int(np.nonzero(world.cells[:, 1])[0][0])

    none, moon, earth = depth_after(0.0), depth_after(0.5), depth_after(1.0)
    assert none == 30  # one cell a frame, never faster
    assert none < moon < earth
