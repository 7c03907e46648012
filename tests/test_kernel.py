"""The kernel on small scenes: each archetype, each built-in reaction, conservation."""

from __future__ import annotations

import numpy as np

from conftest import as_rows, make_world, run


def test_powder_rests_on_stone_where_it_lands(ruleset):
    world = make_world(ruleset, ["..S..", ".....", ".....", "#####"])
    assert as_rows(run(world, 1)) == [".....", "..S..", ".....", "#####"]
    rows = as_rows(run(world, 10))
    assert rows[2].count("S") == 1 and "S" not in rows[0] + rows[1]  # on the floor, maybe slid a cell
    assert as_rows(run(world, 10)) == rows  # and at rest


def test_powder_slides_diagonally_off_another_grain(ruleset):
    world = run(make_world(ruleset, [".....", "..S..", "..S..", "#####"]), 1)
    assert as_rows(world) in (
        [".....", ".....", ".SS..", "#####"],
        [".....", ".....", "..SS.", "#####"],
    )


def test_powder_cannot_squeeze_between_two_corners(ruleset):
    rows = ["S#..", "#...", "....", "####"]
    assert as_rows(run(make_world(ruleset, rows), 5)) == rows


def test_sand_sinks_through_water(ruleset):
    # A cell a frame at most, each frame by the chance their densities give (sand 1600, water 1000: 0.94).
    world = make_world(ruleset, ["#S#", "#W#", "#W#", "###"])
    frames = 0
    while as_rows(world) != ["#W#", "#W#", "#S#", "###"] and frames < 50:
        run(world, 1)
        frames += 1
    assert 2 <= frames <= 4


def test_liquid_flows_sideways_up_to_its_dispersion(ruleset):
    world = make_world(ruleset, ["#W.........#", "############"])
    assert ruleset.tables.dispersion[ruleset.index("water")] == 4
    assert as_rows(run(world, 1)) == ["#....W.....#", "############"]


def test_liquid_levels_out(ruleset):
    rows = ["#W.....#", "#W.....#", "#W.....#", "########"]
    world = run(make_world(ruleset, rows), 40)
    assert as_rows(world)[:2] == ["#......#", "#......#"]
    assert as_rows(world)[2].count("W") == 3


def test_static_never_moves(ruleset):
    rows = [".#T.", "....", "....", "...."]
    assert as_rows(run(make_world(ruleset, rows), 5)) == rows


def test_gas_rises_through_air_and_water(ruleset):
    world = make_world(ruleset, ["#.#", "#W#", "#G#", "###"])
    assert as_rows(run(world, 1)) == ["#.#", "#G#", "#W#", "###"]
    assert as_rows(run(world, 1)) == ["#G#", "#.#", "#W#", "###"]


def test_lava_on_water_boils_it_and_sets_into_basalt(ruleset):
    world = make_world(ruleset, ["#####", "#LLL#", "#WWW#", "#####"])
    run(world, 60)
    counts = world.counts()
    assert counts.get("lava:lava", 0) == 0 and counts["base:stone"] == 14 and counts["lava:basalt"] == 3
    assert counts.get("water:steam", 0) >= 1  # heat alone: lava and water have no reaction
    assert not world.ruleset.tables.react_pair[world.ruleset.index("lava"), world.ruleset.index("water")]


def test_acid_eats_stone_and_is_used_up(ruleset):
    world = run(make_world(ruleset, ["TAT", "T#T", "TTT"]), 100)
    assert as_rows(world) == ["T.T", "T.T", "TTT"]


def test_acid_does_not_touch_titanium_or_acid(ruleset):
    rows = ["TAAT", "TAAT", "TTTT"]
    assert as_rows(run(make_world(ruleset, rows), 200)) == rows


def test_fire_turns_to_smoke_after_its_lifetime_and_smoke_thins_away(ruleset):
    world = make_world(ruleset, ["###", "#.#", "#F#", "###"])
    life = ruleset.tables.life_frames[ruleset.index("fire")]
    jitter = ruleset.tables.life_jitter[ruleset.index("fire")]
    run(world, int(life) - 2)
    assert world.counts()["fire:fire"] == 1
    run(world, int(jitter) + 4)
    assert world.counts()["fire:smoke"] == 1
    run(world, 250)
    assert world.counts() == {"base:stone": 10, "base:empty": 2}


def test_motion_alone_neither_creates_nor_loses_cells(ruleset):
    rng = np.random.default_rng(5)
    rows = ["".join(rng.choice(list("..SW#"), 40)) for _ in range(30)]
    world = make_world(ruleset, rows)
    before = world.counts()
    run(world, 150)
    assert world.counts() == before


def test_a_falling_cell_speeds_up_to_its_terminal_speed_and_moves_once_a_frame(ruleset):
    world = make_world(ruleset, [".S."] + ["..."] * 400)
    t, sand = ruleset.tables, ruleset.index("sand")
    depths = [0]
    for _ in range(50):
        world.step()
        depths.append(int(np.nonzero(world.cells[:, 1] == sand)[0][0]))
    steps = np.diff(depths)
    assert (steps >= 1).all()  # at least a cell a frame
    assert steps.max() <= t.max_speed[sand] // 256  # never more than terminal speed: each cell moves once
    assert steps[:5].mean() < 2 and steps[-10:].mean() > 6  # it accelerates


def test_a_rising_gas_moves_at_most_its_terminal_speed(ruleset):
    world = make_world(ruleset, ["..."] * 100 + [".K."])
    smoke = ruleset.index("smoke")
    heights = []
    for _ in range(40):
        world.step()
        heights.append(int(np.nonzero(world.cells == smoke)[0][0]))
    assert max(-np.diff(heights)) <= ruleset.tables.max_speed[smoke] // 256


def test_a_reaction_limited_to_one_side_grows_only_that_way(registry, tmp_path):
    """A seed that turns the empty cell above it into seed grows a straight stalk upwards; one that
    also sprouts roots below and beside it (another reaction, other sides) grows those too."""
    from conftest import SEED, SEED_ROOTS, write_mods
    from sandmod.world.loading import load_ruleset

    legend = {".": "empty", "s": "seed", "r": "root", "#": "stone"}
    stalk = load_ruleset(["g"], [write_mods(tmp_path / "a", {"g.toml": SEED})], registry=registry)
    world = run(make_world(stalk, [".....", ".....", ".....", "..s..", "#####"], legend), 5)
    assert as_rows(world, legend) == ["..s..", "..s..", "..s..", "..s..", "#####"]
    both = load_ruleset(["g"], [write_mods(tmp_path / "b", {"g.toml": SEED_ROOTS})], registry=registry)
    scene = ["." * 40, ".s.." * 10, "." * 40]
    rows = as_rows(run(make_world(both, scene, legend), 1), legend)
    for x in range(1, 40, 4):  # each seed reacted with one neighbour (once a frame): a seed above, or a root elsewhere
        grown = {(rows[0][x], "above"), (rows[1][x - 1], "left"), (rows[1][x + 1], "right"), (rows[2][x], "below")} - {(".", s) for s in ("above", "left", "right", "below")}
        assert len(grown) == 1 and next(iter(grown)) in {("s", "above"), ("r", "left"), ("r", "right"), ("r", "below")}, (x, rows)
    assert "s" in rows[0] and "r" in rows[1] + rows[2]


def test_a_fan_lifts_sand_and_the_sand_lands_again(ruleset):
    """Grains on the fan fly up as particles carrying sand (none lost), well above it; with the fan
    turned to stone they all land again."""
    legend = {".": "empty", "S": "sand", "F": "fan", "#": "stone"}
    scene = [".........."] * 14 + ["...SSSS..."] + ["...FFFF..."] + ["##########"]
    world = make_world(ruleset, scene, legend)
    highest = len(scene)
    for _ in range(60):
        world.step()
        assert world.counts(carried=True)["sand:sand"] == 4
        flying = np.argwhere(world.shown() == ruleset.index("sand"))[:, 0]
        highest = min(highest, flying.min())
    assert highest <= 15 - 6  # six cells or more above where it lay
    world.paint(world.cells == ruleset.index("fan"), ruleset.index("stone"))
    run(world, 80)
    assert world.counts()["sand:sand"] == 4 and (world.cells == ruleset.particle).sum() == 0


def test_a_powder_of_negative_gravity_rises_as_a_body_and_piles_on_the_ceiling(registry, tmp_path):
    from conftest import write_mods
    from sandmod.world.loading import load_ruleset
    from test_scenes import alternating_rows

    anti = '[mod]\nname = "anti"\n[elements.antisand]\narchetype = "powder"\ncolor = "#8ac3dc"\ndensity = 1600\ngravity = -0.2\n'
    ruleset = load_ruleset(["anti"], [write_mods(tmp_path / "mods", {"anti.toml": anti})], registry=registry)
    e = ruleset.index("antisand")
    assert ruleset.tables.fall_dir[e] == -1 and ruleset.tables.accel[e] == round(0.2 * 256)
    legend = {".": "empty", "A": "antisand", "#": "stone"}
    world = make_world(ruleset, ["#" * 30] + ["#" + "." * 28 + "#"] * 30 + ["#" + "." * 11 + "A" * 6 + "." * 11 + "#"] * 6 + ["#" * 30], legend)
    for _ in range(100):
        world.step()
        assert alternating_rows(world.cells, e) <= 3  # no comb while it rises
    rows = (world.cells == e).sum(axis=1)
    assert rows[1:6].sum() == 36 and rows[1] > rows[2] > 0  # all against the ceiling, widest there: a heap upside down


ORDER = """
[mod]
name = "o"
requires = ["fire"]
[elements.wire]
archetype = "static"
color = "#b87333"
[elements.spark]
archetype = "static"
color = "#ffee88"
lifetime = { frames = LIFE, becomes = "wire" }
[elements.glow]
archetype = "static"
color = "#ffaa00"
lifetime = { frames = 10, becomes = "empty" }
[elements.fuel]
archetype = "static"
color = "#553311"
[elements.thermite]
archetype = "powder"
color = "#8a5a3a"
density = 2000
flammable = { ignites_at = 600, burn_time = 60 }
[[reactions]]
a = "spark"
b = "wire"
b_becomes = "spark"
chance = 1
[[reactions]]
a = "glow"
b = "fuel"
a_becomes = "glow"
b_becomes = "empty"
chance = 1
"""


def _order_rules(registry, tmp_path, life):
    from conftest import write_mods
    from sandmod.world.loading import load_ruleset

    return load_ruleset(["o"], [write_mods(tmp_path / f"o{life}", {"o.toml": ORDER.replace("LIFE", str(life))})], registry=registry)


def test_a_lifetime_runs_out_before_the_cell_reacts(registry, tmp_path):
    """Documented order (the reactions how-to): lifetime, then reactions. A spark that lives one frame
    is gone before it touches the wire; one that lives two passes on, once a frame, down the wire."""
    legend = {".": "empty", "w": "wire", "s": "spark"}
    world = run(make_world(_order_rules(registry, tmp_path, 1), ["swwwww"], legend), 1)
    assert as_rows(world, legend) == ["wwwwww"]  # it died into wire at once: nothing passed on
    world = make_world(_order_rules(registry, tmp_path, 2), ["swwwww"], legend)
    reached = [as_rows(run(world, 1), legend)[0].rfind("s") for _ in range(5)]
    assert reached == [1, 2, 3, 4, 5]  # the spark's front, one cell a frame


def test_a_reaction_that_leaves_a_cell_as_it_was_keeps_its_lifetime(registry, tmp_path):
    """Documented choice: ``a_becomes`` its own element changes nothing, so the glow's ten frames run on
    while it eats fuel; it is not born again."""
    legend = {".": "empty", "g": "glow", "f": "fuel"}
    world = run(make_world(_order_rules(registry, tmp_path, 2), ["gf", "ff"], legend), 10)
    assert "g" not in "".join(as_rows(world, legend))


def test_a_cell_painted_hotter_than_it_ignites_lights_on_its_first_frame(registry, tmp_path):
    """Heat flows first, then fire: a cell painted past ``ignites_at`` still is on its first frame
    (conduction moves under a quarter of a gap a frame), so it lights at once, alone in cold air too."""
    from sandmod.engine.layout import BURNING

    ruleset = _order_rules(registry, tmp_path, 2)
    world = make_world(ruleset, ["....", ".t..", "...."], {".": "empty", "t": "thermite"})
    world.set_temperature(world.cells == ruleset.index("thermite"), 700.0)
    world.step()
    assert world.state.flags[world.cells == ruleset.index("thermite")] & BURNING  # (where it fell to)
