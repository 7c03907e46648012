"""Neighbour-count rules (``[[neighbours]]``): Conway's Life is exact (every cell decided from the
frame as the step left it, then all changed together), growth that needs two neighbours, a crystal
that grows only from a seed below it; the tiles it looks at; mistakes are one line each."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import make_world, run, write_mods
from sandmod.errors import ProblemsError
from sandmod.world.loading import load_ruleset

LIFE = """
[mod]
name = "life"
requires = ["water"]

[elements.life]
archetype = "static"
color = "#40e040"

[[neighbours]]
cell = "empty"
count = "life"
counts = [3]
becomes = "life"

[[neighbours]]
cell = "life"
count = "life"
counts = [0, 1, 4, 5, 6, 7, 8]
becomes = "empty"

[elements.moss]
archetype = "static"
color = "#3a6a2a"

[[neighbours]]
cell = "empty"
count = "moss"
counts = [2, 3]
becomes = "moss"
chance = 0.05

[elements.crystal]
archetype = "static"
color = "#a0e0ff"

[[neighbours]]
cell = "water:water"
count = "crystal"
counts = [1]
where = ["below"]
becomes = "crystal"
chance = 0.5
"""

LEGEND = {".": "empty", "O": "life", "#": "stone", "M": "moss", "C": "crystal", "W": "water"}
GLIDER = [".O.", "..O", "OOO"]


@pytest.fixture(scope="module")
def ruleset(tmp_path_factory):
    return load_ruleset(["base", "water", "life"], [write_mods(tmp_path_factory.mktemp("mods"), {"life.toml": LIFE})])


def life_step(alive: np.ndarray) -> np.ndarray:
    """One generation of B3/S23 on a bounded grid (the slow, obvious reference)."""
    padded = np.pad(alive.astype(int), 1)
    around = sum(np.roll(np.roll(padded, dy, 0), dx, 1) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dx, dy) != (0, 0))[1:-1, 1:-1]
    return (around == 3) | (alive & (around == 2))


def test_a_glider_glides_cell_for_cell(ruleset):
    rows = ["." * 12 for _ in range(12)]
    for k, line in enumerate(GLIDER):
        rows[2 + k] = "..." + line + "." * 6
    world = make_world(ruleset, rows, LEGEND)
    life = ruleset.index("life")
    start = world.cells == life
    expected = start
    for generation in range(1, 9):
        world.step()
        expected = life_step(expected)
        assert ((world.cells == life) == expected).all(), f"generation {generation}"
    assert (np.roll(start, (2, 2), (0, 1)) == (world.cells == life)).all()  # 8 generations: two cells down and right


def test_life_is_the_reference_on_a_random_soup_across_tiles(ruleset):
    rng = np.random.default_rng(7)
    alive = rng.random((90, 150)) < 0.35
    world = make_world(ruleset, ["." * 150] * 90, LEGEND)
    world.paint(alive, ruleset.index("life"))
    for generation in range(30):
        world.step()
        alive = life_step(alive)
        assert ((world.cells == ruleset.index("life")) == alive).all(), f"generation {generation + 1}"


def test_moss_grows_only_where_two_or_three_touch(ruleset):
    world = run(make_world(ruleset, ["." * 60, "." * 60, "..M" + "." * 54 + "MM.", "." * 60, "." * 60], LEGEND), 200)
    moss = world.cells == ruleset.index("moss")
    assert moss[:, :6].sum() == 1  # a lone cell never has two neighbours
    assert moss[:, 40:].sum() > 6  # a pair grows into a patch


def test_a_crystal_grows_upwards_only(ruleset):
    rows = ["W" * 7] * 8 + ["WWWCWWW", "#######"]
    world = run(make_world(ruleset, rows, LEGEND), 60)
    crystal = world.cells == ruleset.index("crystal")
    assert crystal[:, 3].sum() >= 5 and crystal[:, [0, 1, 2, 4, 5, 6]].sum() == 0


def test_the_pass_looks_only_at_tiles_holding_its_elements(ruleset):
    from sandmod.passes.visit import tiles_holding

    world = make_world(ruleset, ["." * 200] * 130, LEGEND)
    world.paint(np.pad(np.ones((3, 3), bool), ((100, 27), (150, 47))), ruleset.index("life"))
    world.step()
    tiles = tiles_holding(world._seen, ruleset.neighbours.mask)
    assert 1 <= len(tiles) <= 2  # the block's tile (and the one past its edge), not the 12 of the world


@pytest.mark.parametrize("rule, message", [
    ('cell = "empty"\ncount = "x"\ncounts = [0, 3]\nbecomes = "x"', "neighbours.0: an empty cell with none of them around would change everywhere"),
    ('cell = "x"\ncount = "x"\ncounts = [9]\nbecomes = "empty"', "neighbours.0.counts.0: must be <= 8 (got 9)"),
    ('cell = "x"\ncount = "y"\ncounts = [1]\nbecomes = "empty"', "neighbours.0.count: unknown element 'y'"),
    ('cell = "x"\ncount = "x"\ncounts = [1]\nbecomes = "x"\nwhere = ["up"]', "neighbours.0.where.0: must be"),
])
def test_a_mistake_in_a_rule_is_one_line(tmp_path, rule, message):
    text = f'[mod]\nname = "m"\n[elements.x]\narchetype = "static"\ncolor = "#ffffff"\n[[neighbours]]\n{rule}\n'
    with pytest.raises(ProblemsError) as caught:
        load_ruleset(["base", "m"], [write_mods(tmp_path, {"m.toml": text})])
    assert message in str(caught.value) and len(str(caught.value).splitlines()) == 1
