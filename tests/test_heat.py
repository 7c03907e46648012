"""Heat: conduction (against a slow reference), conservation, phase changes at their thresholds,
reactions with temperature ranges, glow."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import LEGEND, as_rows, make_world, run, write_mods
from sandmod.rules.compiler import TEMP_ONE
from sandmod.world.loading import load_ruleset
from sandmod.world.world import World


def conduct_reference(cells, heat, t, frame):
    """The documented scheme, written out plainly: each touching pair, in sweep order,
    exchanges min(conductance) x (temperature gap) / 256 of energy, rounded towards zero."""
    heat = heat.astype(np.int64).copy()
    height, width = cells.shape
    order = [(y, x) for y in range(height) for x in range(width)]
    if frame % 2:
        order.reverse()

    def temperature(y, x):
        energy = int(heat[y, x])
        magnitude = (abs(energy) * int(t.heat_recip[cells[y, x]])) >> 32
        return magnitude if energy >= 0 else -magnitude

    for y, x in order:
        e = cells[y, x]
        if t.cooling[e]:
            gap = int(t.heat_cap[e]) * int(t.temp_start[0]) - int(heat[y, x])
            heat[y, x] += int(gap * int(t.cooling[e]) / 256)
        for ny, nx in ((y, x + 1), (y + 1, x)):
            if ny < height and nx < width:
                g = min(int(t.conductance[e]), int(t.conductance[cells[ny, nx]]))
                flow = int((temperature(y, x) - temperature(ny, nx)) * g / 256)
                heat[y, x] -= flow
                heat[ny, nx] += flow
    return heat


def static_world(ruleset, seed, size=(12, 16)):
    """Static solids and air at random temperatures (nothing moves, only heat)."""
    rng = np.random.default_rng(seed)
    rows = ["".join(rng.choice(list("#Tgw."), size[1])) for _ in range(size[0])]
    world = make_world(ruleset, rows)
    world.set_temperature(np.ones(size, bool), 20.0)
    temps = rng.uniform(-50, 250, size)  # below wood's ignition point
    for (y, x), celsius in np.ndenumerate(temps):
        mask = np.zeros(size, bool)
        mask[y, x] = True
        world.set_temperature(mask, celsius)
    return world


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_conduction_matches_the_slow_reference(ruleset, seed):
    from sandmod.engine.kernel import conduct

    world = static_world(ruleset, seed)
    s, t = world.state, world.tables
    for frame in range(6):
        expected = conduct_reference(s.cells, s.heat, t, frame)
        conduct(s, t, frame, np.ones_like(world.awake), np.zeros_like(world._woken), np.zeros_like(world._even), np.zeros_like(world._stirred), 0, 0, world.width, world.height)
        assert (s.heat == expected).all()


def test_conduction_conserves_heat_exactly_in_a_closed_box(ruleset):
    # No air (the only element that loses heat to the outside) and nothing hot enough to change.
    rng = np.random.default_rng(7)
    rows = ["T" * 30] + ["T" + "".join(rng.choice(list("#gSWT"), 28)) + "T" for _ in range(20)] + ["T" * 30]
    world = make_world(ruleset, rows)
    temps = rng.uniform(5, 90, world.cells.shape)
    for (y, x), celsius in np.ndenumerate(temps):
        world.state.heat[y, x] = world.tables.heat_cap[world.cells[y, x]] * round(celsius * TEMP_ONE)
    total, spread, before = world.heat_total(), world.temperature().std(), world.counts()
    for _ in range(300):
        world.step()
        assert world.heat_total() == total
    assert world.counts() == before  # no phase changes happened
    after = world.temperature()
    assert after.std() < spread / 3  # it evens out...
    assert 5 <= after.min() and after.max() <= 90  # ...without overshooting


def test_air_cools_back_to_the_ambient_temperature(ruleset):
    world = World(ruleset, 8, 8)
    world.set_temperature(np.ones((8, 8), bool), 300.0)
    run(world, 400)
    assert np.allclose(world.temperature(), 20.0, atol=1.0)


def uniform(ruleset, name, celsius, size=6):
    """A world filled with one element at one temperature: nothing to conduct, and (steam) no cooling."""
    world = make_world(ruleset, [{v: k for k, v in LEGEND.items()}[name] * size] * size)
    world.tables = world.tables._replace(cooling=np.zeros_like(world.tables.cooling))
    world.set_temperature(np.ones((size, size), bool), celsius)
    return world


@pytest.mark.parametrize(
    ("name", "threshold", "direction", "into"),
    [
        ("water", 0, -1, "ice"),
        ("ice", 0, +1, "water"),
        ("lava", 900, -1, "basalt"),
        ("basalt", 1200, +1, "lava"),
        ("stone", 1300, +1, "lava"),
        ("sand", 1100, +1, "glass"),
    ],
)
def test_each_phase_change_happens_past_its_threshold_and_not_before(ruleset, name, threshold, direction, into):
    safe = run(uniform(ruleset, name, threshold), 40)
    assert set(safe.counts()) == {ruleset.elements[ruleset.index(name)].id}
    past = run(uniform(ruleset, name, threshold + direction * 0.5), 1)
    assert set(past.counts()) == {ruleset.elements[ruleset.index(into)].id}
    assert np.allclose(past.temperature(), threshold + direction * 0.5)  # it keeps its temperature


def test_boiling_takes_its_latent_heat_and_condensing_gives_it_back_so_nothing_flickers(ruleset):
    water, steam = (ruleset.elements[ruleset.index(name)].spec for name in ("water", "steam"))
    latent, spread = water.heated.latent_heat, water.heated.spread
    assert steam.cooled.latent_heat == latent and 95 <= steam.cooled.below < water.heated.above
    # Water at its boiling point stays water; past it by its spread, it boils within a few frames,
    # its heat less the latent heat making the steam far hotter than the point where it condenses.
    assert set(run(uniform(ruleset, "water", 100), 40).counts()) == {"water:water"}
    hot = 100 + spread + 0.5
    boiled = run(uniform(ruleset, "water", hot), 12)
    assert set(boiled.counts()) == {"water:steam"}
    born = (hot * water.heat_capacity - latent) / steam.heat_capacity
    # (cells that boiled on different frames then trade some heat)
    assert abs(boiled.temperature().mean() - born) < 3 and boiled.temperature().min() > steam.cooled.below + 20
    # Steam at its condensation point stays steam; just below it, it condenses at once, given the
    # latent heat back: water below its boiling point, which does not boil again.
    assert set(run(uniform(ruleset, "steam", steam.cooled.below), 40).counts()) == {"water:steam"}
    cold = steam.cooled.below - 0.5
    condensed = run(uniform(ruleset, "steam", cold), 1)
    assert set(condensed.counts()) == {"water:water"}
    back = (cold * steam.heat_capacity + latent) / water.heat_capacity
    assert np.allclose(condensed.temperature(), back, atol=0.1) and back < 100
    assert set(run(condensed, 40).counts()) == {"water:water"}


def test_a_floor_heated_evenly_boils_in_bubbles_not_a_sheet(ruleset):
    # A row of water far past its boiling point: a chance a frame, rolled for blocks of cells
    # together, boils it over several frames, never the whole row on the first.
    world = uniform(ruleset, "water", 200, size=64)
    steam = ruleset.index("steam")
    firsts = []
    for _ in range(30):
        run(world, 1)
        firsts.append(int((world.cells == steam).sum()))
    assert 0 < firsts[0] < 64 * 64 * 0.75 and firsts[-1] == 64 * 64


def test_titanium_over_lava_conducts_but_never_melts(ruleset):
    rows = ["#........#", "#WWWWWWWW#", "#TTTTTTTT#", "#LLLLLLLL#", "#LLLLLLLL#", "#LLLLLLLL#", "##########"]
    world = make_world(ruleset, rows)
    titanium = world.cells == ruleset.index("titanium")
    hottest_plate = 0.0
    for _ in range(200):
        world.step()
        hottest_plate = max(hottest_plate, world.temperature()[titanium].max())
    assert (world.cells[titanium] == ruleset.index("titanium")).all()
    assert hottest_plate > 500  # far past what melts stone's neighbours, and it stays titanium
    assert world.counts().get("water:water", 0) < 8  # the water over it boiled


def temperature_mod(tmp_path):
    return write_mods(
        tmp_path / "mods",
        {
            "fuse.toml": """
            [mod]
            name = "fuse"
            [elements.fuel]
            archetype = "static"
            color = "#aa8800"
            conductivity = 0
            [elements.cinder]
            archetype = "static"
            color = "#442200"
            conductivity = 0
            [[reactions]]
            a = "fuel"
            b = "stone"
            a_becomes = "cinder"
            chance = 1
            min_temperature = 200
            max_temperature = 300
            heat = 150
            """
        },
    )


@pytest.mark.parametrize(("celsius", "reacts"), [(199, False), (200, True), (300, True), (301, False)])
def test_reactions_happen_only_within_their_temperature_range_and_release_heat(registry, tmp_path, celsius, reacts):
    rs = load_ruleset(["fuse"], [temperature_mod(tmp_path)], registry=registry)
    legend = {".": "empty", "f": "fuel", "#": "stone"}
    world = make_world(rs, ["f#"], legend)
    stone = rs.index("stone")
    rs.tables.conductance[stone] = 0  # (this ruleset is the test's own) keep both temperatures put
    world.set_temperature(np.ones((1, 2), bool), celsius)
    run(world, 5)
    assert as_rows(world, legend | {"c": "cinder"}) == (["c#"] if reacts else ["f#"])
    if reacts:
        assert world.temperature()[0, 0] == celsius + 150


def test_hot_cells_glow_and_cheap_cells_do_not(ruleset):
    world = make_world(ruleset, ["###", "LLL"])
    looks = ruleset.looks
    world.set_temperature(np.array([[False, True, False], [False, False, False]]), 1000.0)
    image = world.image()
    stone, lava = ruleset.index("stone"), ruleset.index("lava")
    assert image[0, 1] in looks.glow[stone] and image[0, 0] in looks.normal[stone]
    assert all(v in looks.normal[lava] for v in image[1])  # lava at its own 1400 degrees looks like lava
