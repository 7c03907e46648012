"""Fire: catching by heat or flame, spreading through wood, stopping at stone, water putting it out."""

from __future__ import annotations

import numpy as np

from conftest import make_world, run
from sandmod.engine.layout import BURNING


def burning(world) -> int:
    return int(((world.state.flags & BURNING) != 0).sum())


def test_wood_catches_fire_at_its_ignition_temperature_and_not_below(ruleset):
    cold = make_world(ruleset, ["wwww"] * 4)
    cold.set_temperature(np.ones((4, 4), bool), 299.5)
    run(cold, 30)
    assert burning(cold) == 0
    hot = make_world(ruleset, ["wwww"] * 4)
    hot.set_temperature(np.ones((4, 4), bool), 300.0)
    run(hot, 1)
    assert burning(hot) == 16


def test_fire_spreads_through_wood_and_stops_at_stone(ruleset):
    rows = ["." * 40] * 30 + ["wwwwwwwwwwwww######wwwwwwwwwwwww........"] * 8 + ["#" * 40]
    world = make_world(ruleset, rows)
    world.set_temperature(_cells(world, [(0, y) for y in range(30, 38)]), 400.0)  # light the left edge
    wood = ruleset.index("wood")
    right = np.zeros(world.cells.shape, bool)
    right[30:38, 19:32] = True
    seen_burning = 0
    for _ in range(900):
        world.step()
        seen_burning = max(seen_burning, burning(world))
        assert not ((world.state.flags[right] & BURNING) != 0).any()
    assert seen_burning > 20
    left = world.cells[30:38, 0:13]
    assert (left == wood).sum() < 10  # the left wood burnt away...
    assert (world.cells[right] == wood).all()  # ...the right wood, past the stone, is untouched
    assert world.counts().get("fire:ash", 0) > 0  # and some of it is ash


def _cells(world, points):
    mask = np.zeros(world.cells.shape, bool)
    for x, y in points:
        mask[y, x] = True
    return mask


def test_water_puts_out_burning_wood(ruleset):
    rows = ["#.........#", "#WWWWWWWWW#", "#WWWWWWWWW#", "#wwwwwwwww#", "###########"]
    for water, survives in (("W", True), (".", False)):
        world = make_world(ruleset, [r.replace("W", water) for r in rows])
        world.set_temperature(world.cells == ruleset.index("wood"), 320.0)  # alight
        run(world, 1)
        assert burning(world) > 0 or survives
        run(world, 600)
        wood = world.counts().get("wood:wood", 0)
        assert (burning(world), wood == 9) == (0, survives)


def test_water_douses_flames(ruleset):
    world = make_world(ruleset, ["#####", "#FFF#", "#WWW#", "#####"])
    run(world, 3)
    assert world.counts().get("fire:fire", 0) == 0


def test_a_flame_sets_off_gunpowder(ruleset):
    world = make_world(ruleset, ["#" * 12] + ["#..........#"] * 6 + ["#FPPPPPPPP.#", "#" * 12])
    run(world, 10)
    assert world.counts().get("explosives:gunpowder", 0) < 8
