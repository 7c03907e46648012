"""The kernel on small scenes: each archetype, each built-in reaction, conservation."""

from __future__ import annotations

import numpy as np

from conftest import as_rows, make_world, run


def test_powder_falls_one_cell_a_frame_and_rests_on_stone(ruleset):
    world = make_world(ruleset, [".S.", "...", "...", "###"])
    assert as_rows(run(world, 1), ) == ["...", ".S.", "...", "###"]
    assert as_rows(run(world, 1)) == ["...", "...", ".S.", "###"]
    assert as_rows(run(world, 5)) == ["...", "...", ".S.", "###"]


def test_powder_slides_diagonally_off_another_grain(ruleset):
    world = run(make_world(ruleset, [".....", "..S..", "..S..", "#####"]), 1)
    assert as_rows(world) in (
        [".....", ".....", ".SS..", "#####"],
        [".....", ".....", "..SS.", "#####"],
    )


def test_powder_piles_into_a_slope(ruleset):
    rows = ["." * 15] * 7 + ["#" * 15]
    world = make_world(ruleset, rows)
    sand = ruleset.index("sand")
    for _ in range(60):  # pour one grain every other frame onto the middle
        if world.frame % 2 == 0:
            world.paint(np.eye(1, 15 * 8, 7, dtype=bool).reshape(8, 15), sand, only_empty=True)
        world.step()
    run(world, 20)
    heights = [(world.cells[:, x] == sand).sum() for x in range(15)]
    assert heights[7] == max(heights) and heights[7] >= 3
    # A slope: no column is more than one grain taller than its outer neighbour.
    for x in range(1, 8):
        assert heights[x] - heights[x - 1] <= 1
        assert heights[14 - x] - heights[15 - x] <= 1


def test_powder_cannot_squeeze_between_two_corners(ruleset):
    rows = ["S#..", "#...", "....", "####"]
    assert as_rows(run(make_world(ruleset, rows), 5)) == rows


def test_sand_sinks_through_water(ruleset):
    world = make_world(ruleset, ["#S#", "#W#", "#W#", "###"])
    assert as_rows(run(world, 2)) == ["#W#", "#W#", "#S#", "###"]


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


def test_lava_and_water_give_stone_and_steam(ruleset):
    world = run(make_world(ruleset, ["TTT", "TLT", "TWT", "TTT"]), 30)
    counts = world.counts()
    assert counts.get("lava:lava", 0) == 0
    assert counts["base:stone"] == 1
    assert counts.get("steam:steam", 0) + counts.get("water:water", 0) == 1


def test_acid_eats_stone_and_is_used_up(ruleset):
    world = run(make_world(ruleset, ["TAT", "T#T", "TTT"]), 100)
    assert as_rows(world) == ["T.T", "T.T", "TTT"]


def test_acid_does_not_touch_titanium_or_acid(ruleset):
    rows = ["TAAT", "TAAT", "TTTT"]
    assert as_rows(run(make_world(ruleset, rows), 200)) == rows


def test_steam_condenses_back_into_water_after_its_lifetime(ruleset):
    world = make_world(ruleset, ["TTT", "T.T", "TGT", "TTT"])
    life = ruleset.tables.life_frames[ruleset.index("steam")]
    jitter = ruleset.tables.life_jitter[ruleset.index("steam")]
    run(world, int(life) - 5)
    assert world.counts()["steam:steam"] == 1
    run(world, int(jitter) + 10)
    assert world.counts() == {"titanium:titanium": 10, "water:water": 1, "base:empty": 1}


def test_motion_alone_neither_creates_nor_loses_cells(ruleset):
    rng = np.random.default_rng(5)
    rows = ["".join(rng.choice(list("..SW#"), 40)) for _ in range(30)]
    world = make_world(ruleset, rows)
    before = world.counts()
    run(world, 150)
    assert world.counts() == before


def test_each_cell_moves_at_most_once_a_frame(ruleset):
    # A grain above a tall empty column moves exactly one cell per frame.
    world = make_world(ruleset, [".S."] + ["..."] * 10)
    for frame in range(1, 9):
        world.step()
        assert world.cells[frame, 1] == ruleset.index("sand")
