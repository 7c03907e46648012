"""Breaking: what a blast leaves of a cell (``breaks_into``), and hard landings (``breaks_on_impact``)
that break a cell or set off an explosive; elements without the fields behave as before."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from conftest import make_world, run, write_mods
from sandmod.engine.layout import NO_BREAK, NO_IMPACT, SUBCELL
from sandmod.errors import ProblemsError
from sandmod.formats.modspec import Explosion
from sandmod.jobs import benchmark
from sandmod.world.loading import load_ruleset
from sandmod.world.world import World
from test_chunks import digest
from test_golden import GOLDEN

LEGEND = {".": "empty", "#": "stone", "g": "glass", "R": "rubble", "S": "sand", "N": "nitroglycerin", "W": "water"}


def unbreakable(ruleset):
    """The ruleset with nothing that breaks: the tables as an element without the fields has them."""
    t = ruleset.tables
    tables = t._replace(breaks_into=np.full_like(t.breaks_into, NO_BREAK), impact=np.full_like(t.impact, NO_IMPACT))
    return dataclasses.replace(ruleset, tables=tables)


def drop(ruleset, what: str, height: int, onto: str, frames: int = 60, width: int = 5):
    """A world ``width`` cells wide: one cell of ``what`` ``height`` cells above a row of ``onto`` on a
    stone floor, stepped ``frames`` frames."""
    rows = ["." * (width // 2) + what + "." * (width // 2)] + ["." * width] * (height - 1) + [onto * width, "." * width, "#" * width]
    return run(make_world(ruleset, rows, LEGEND), frames)


def count(world, name: str) -> int:
    e = world.ruleset.index(name)
    carried = (world.cells == world.ruleset.particle) & (world.state.carry == e)
    return int((world.cells == e).sum() + carried.sum())


def test_tables_hold_what_breaks_into_what_and_how_hard(ruleset):
    t, i = ruleset.tables, ruleset.index
    assert t.breaks_into[i("stone")] == i("rubble") and t.impact[i("stone")] == NO_IMPACT  # blasts only: piles stand on stone
    assert t.breaks_into[i("glass")] == i("shards") and t.impact[i("glass")] == 3 * SUBCELL
    assert t.breaks_into[i("nitroglycerin")] == NO_BREAK and t.impact[i("nitroglycerin")] == round(2.5 * SUBCELL)
    assert t.breaks_into[i("sand")] == NO_BREAK and t.impact[i("sand")] == NO_IMPACT
    assert t.breaks_into[0] == NO_BREAK and t.impact[0] == NO_IMPACT


def test_a_blast_breaks_stone_into_rubble_where_it_would_leave_a_hole(ruleset):
    world = make_world(ruleset, ["#" * 41] * 41, LEGEND)
    world.explode(20, 20, Explosion(radius=6, strength=10_000, fling=0, scorch=0))
    disc = np.hypot(*np.mgrid[-20:21, -20:21]) <= 6
    assert (world.cells[disc] == ruleset.index("rubble")).all() and (world.cells[~disc] == ruleset.index("stone")).all()
    plain = make_world(unbreakable(ruleset), ["#" * 41] * 41, LEGEND)
    plain.explode(20, 20, Explosion(radius=6, strength=10_000, fling=0, scorch=0))
    assert (plain.cells[disc] == 0).all()  # without breaks_into: a hole, as before


def test_broken_cells_are_flung_as_destroyed_grains_are_and_never_become_what_the_blast_leaves(ruleset):
    world = make_world(ruleset, ["#" * 41] * 41, LEGEND)
    world.explode(20, 20, Explosion(radius=6, strength=10_000, fling=1.0, leaves="fire", scorch=0))
    disc = np.hypot(*np.mgrid[-20:21, -20:21]) <= 6
    assert (world.cells[disc] == ruleset.particle).all() and (world.state.carry[disc] == ruleset.index("rubble")).all()
    assert count(world, "fire") == 0


@pytest.mark.parametrize("what", ["S", "R"])
def test_a_grain_dropped_from_high_up_shatters_glass_and_falls_on_through(ruleset, what):
    world = drop(ruleset, what, 30, "g")
    assert count(world, "shards") == 1 and count(world, "glass") == 4
    assert world.cells[-2, 2] in (ruleset.index("shards"), ruleset.index(LEGEND[what]))  # both fell through the hole
    assert world.cells[-3, 2] == 0 or world.cells[-3, 2] != ruleset.index("glass")


def test_a_grain_dropped_from_low_down_leaves_glass_whole(ruleset):
    world = drop(ruleset, "S", 12, "g")  # under 3 cells a frame when it lands
    assert count(world, "glass") == 5 and count(world, "shards") == 0 and world.cells[-4, 2] == ruleset.index("sand")


def test_glass_that_nothing_breaks_holds_a_grain_from_any_height(ruleset):
    world = drop(unbreakable(ruleset), "S", 30, "g")
    assert count(world, "glass") == 5 and count(world, "shards") == 0


def test_stone_breaks_in_blasts_only_never_under_a_landing(ruleset):
    world = drop(ruleset, "S", 30, "#")
    assert count(world, "rubble") == 0 and world.cells[-4, 2] == ruleset.index("sand")


def test_nitroglycerin_goes_off_when_it_lands_hard(ruleset):
    world = drop(ruleset, "N", 26, "#", frames=40)
    assert count(world, "nitroglycerin") == 0 and count(world, "rubble") > 0


def test_nitroglycerin_lands_softly_from_low_down(ruleset):
    world = drop(ruleset, "N", 6, "#", frames=40)
    assert count(world, "nitroglycerin") == 1 and count(world, "rubble") == 0


def test_a_grain_landing_hard_on_nitroglycerin_sets_it_off(ruleset):
    world = drop(ruleset, "S", 30, "N", frames=40, width=7)  # sand cannot sink into nitroglycerin (one density): it lands
    assert count(world, "nitroglycerin") == 0


def test_a_grain_plunging_hard_into_nitroglycerin_sets_it_off(ruleset):
    world = drop(ruleset, "R", 30, "N", frames=40, width=7)  # rubble is denser: it would sink into it
    assert count(world, "nitroglycerin") == 0


def test_a_falling_drop_that_catches_up_with_the_one_below_is_no_impact(ruleset):
    # A column of nitroglycerin falls far, faster than would set it off: a drop that catches up with
    # the one below it lands on it only at their speeds' difference.
    rows = ["..N.."] * 6 + ["....."] * 80 + ["#####"]
    world = make_world(ruleset, rows, LEGEND)
    for _ in range(22):
        world.step()
        assert count(world, "nitroglycerin") == 6
    assert np.abs(world.state.vy[world.cells == ruleset.index("nitroglycerin")]).min() > 3 * SUBCELL


def test_the_bench_scenes_with_nothing_that_breaks_step_to_the_frames_before_breaking(ruleset):
    # The golden digests of mix and halves hold as they are; everything's changed only by what breaks
    # (stone in gunpowder's blasts, glass made from molten sand): without it, the digest before breaking.
    before = {96: "8834bd61c869e6eec5bc3c699f6035ed2fb72f6bb595176408ef50f9148e8cf3", 272: "e7432de3fc647df94b985ac5978f74a3ba22a6cbb2b7d4c9eedb42da382f5563"}
    for size, recorded in before.items():
        world = World(unbreakable(ruleset), size, size, seed=7)
        benchmark.SCENES["everything"](world, world.ruleset)
        assert digest(run(world, 160)) == recorded != GOLDEN["everything", size]


def problems_of(tmp_path, text: str) -> list[str]:
    with pytest.raises(ProblemsError) as caught:
        load_ruleset(["base", "m"], [write_mods(tmp_path / "mods", {"m.toml": text})])
    return [str(p) for p in caught.value.problems]


HEAD = '[mod]\nname = "m"\n\n[elements.pane]\narchetype = "static"\ncolor = "#ffffff"\n'


def test_breaking_on_impact_needs_something_to_break_into_or_an_explosion(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert problems_of(tmp_path, HEAD + "breaks_on_impact = 3\n") == [
        "mods/m.toml:7:1: elements.pane.breaks_on_impact: an element that breaks on impact needs 'breaks_into' "
        "(what it breaks into) or an 'explosion' (it goes off)"
    ]


@pytest.mark.parametrize(
    ("into", "message"),
    [
        ('"pane"', "'m:pane' cannot break into itself"),
        ('"particle"', "an element cannot break into a particle ('base:particle')"),
        ('"glass"', "unknown element 'glass'"),
    ],
)
def test_breaks_into_names_another_element_that_is_no_particle(tmp_path, monkeypatch, into, message):
    monkeypatch.chdir(tmp_path)
    (problem,) = problems_of(tmp_path, HEAD + f"breaks_into = {into}\n")
    assert problem.startswith("mods/m.toml:7:1: ") and "elements.pane.breaks_into: " in problem and message in problem
