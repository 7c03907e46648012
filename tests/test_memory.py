"""Cells that remember: each cell may hold an element (``State.carry``), which reactions set
(``a_holds``, ``b_holds``) and read (``@a.held``, ``@b.held``), a lifetime gives back (``@held``)
and a cell that ``shows_held`` is drawn as. A clone, a virus and its cure, a spark that runs along
two metals and gives each back, a dye."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import make_world, run, write_mods
from sandmod.errors import ProblemsError
from sandmod.world.loading import load_ruleset

MEMORY = """
[mod]
name = "mem"
requires = ["sand", "water"]

[elements.clone]
archetype = "static"
color = "#c0c040"
[elements.clone_on]
archetype = "static"
color = "#a0a020"
shows_held = true
hidden = true

[[reactions]]
a = "clone"
b = "!#machine"
a_becomes = "clone_on"
a_holds = "@b"
chance = 1
[[reactions]]
a = "clone_on"
b = "empty"
b_becomes = "@a.held"
chance = 0.5

[elements.virus]
archetype = "static"
color = "#b030b0"
tags = ["machine"]
[elements.cure]
archetype = "liquid"
color = "#30b0b0"
density = 900
dispersion = 3
tags = ["machine"]
[[reactions]]
a = "virus"
b = "!#machine"
b_becomes = "virus"
b_holds = "@b"
chance = 0.2
[[reactions]]
a = "cure"
b = "virus"
b_becomes = "@b.held"
chance = 1

[elements.copper]
archetype = "static"
color = "#b87333"
tags = ["conductor"]
[elements.iron]
archetype = "static"
color = "#8a8f96"
tags = ["conductor"]
[elements.battery]
archetype = "static"
color = "#404040"
tags = ["machine"]
[elements.spark]
archetype = "static"
color = "#fff070"
tags = ["machine"]
lifetime = { frames = 2, becomes = "spent" }
[elements.spent]
archetype = "static"
color = "#ffd0a0"
tags = ["machine"]
shows_held = true
lifetime = { frames = 3, becomes = "@held" }
[elements.lamp]
archetype = "static"
color = "#303020"
tags = ["machine"]
[elements.lamp_on]
archetype = "static"
color = "#ffff80"
tags = ["machine"]
lifetime = { frames = 8, becomes = "lamp" }

[[reactions]]
a = "battery"
b = "#conductor"
b_becomes = "spark"
b_holds = "@b"
chance = 1
[[reactions]]
a = "spark"
b = "#conductor"
b_becomes = "spark"
b_holds = "@b"
chance = 1
[[reactions]]
a = "spark"
b = "lamp"
b_becomes = "lamp_on"
chance = 1

[elements.dye]
archetype = "powder"
color = "#e02020"
density = 1200
tags = ["machine"]
[elements.dyed_water]
archetype = "liquid"
color = "#2d6bd0"
density = 1000
dispersion = 3
shows_held = true
tags = ["machine"]
[[reactions]]
a = "dye"
b = "water"
a_becomes = "empty"
b_becomes = "dyed_water"
b_holds = "@a"
chance = 1
"""

LEGEND = {".": "empty", "#": "stone", "S": "sand", "W": "water", "C": "clone", "V": "virus", "U": "cure",
          "c": "copper", "i": "iron", "B": "battery", "L": "lamp", "l": "lamp_on", "D": "dye", "d": "dyed_water"}


@pytest.fixture(scope="module")
def ruleset(tmp_path_factory):
    return load_ruleset(["base", "sand", "water", "mem"], [write_mods(tmp_path_factory.mktemp("mods"), {"mem.toml": MEMORY})])  # not every bundled mod: metals has its own copper and iron


def test_a_clone_learns_what_touches_it_and_pours_copies_of_it(ruleset):
    world = run(make_world(ruleset, ["......", "..S...", "..C...", "......", "......", "######"], LEGEND), 1)
    i = ruleset.index
    assert world.cells[2, 2] == i("clone_on") and world.state.carry[2, 2] == i("sand")
    run(world, 60)
    assert world.counts().get("sand:sand", 0) > 5  # copies of sand, fallen to the floor
    assert world.shown()[2, 2] == i("sand")  # it shows what it copies


def test_a_virus_keeps_what_it_ate_and_its_cure_gives_it_back(ruleset):
    rows = ["." * 10, "V" + "S" * 9, "#" * 10]
    world = run(make_world(ruleset, rows, LEGEND), 200)
    i = ruleset.index
    assert (world.cells[1] == i("virus")).all() and (world.state.carry[1, 1:] == i("sand")).all()
    assert world.state.carry[1, 0] == 0  # painted: it ate nothing
    world.paint(np.arange(30).reshape(3, 10) < 10, i("cure"))  # a layer of cure on top
    run(world, 30)
    assert (world.cells[1, 1:] == i("sand")).all() and world.cells[1, 0] != i("virus")  # what it ate, given back where it was
    floor = world.cells[2] == i("virus")  # out of the cure's reach, the floor it ate holds stone
    assert floor.sum() >= 9 and (world.state.carry[2][floor] == i("stone")).all()
    assert (world.state.carry[1] == 0).all()  # sand holds nothing


def test_a_spark_runs_along_two_metals_lights_a_lamp_and_gives_each_metal_back(ruleset):
    wire = "B" + "c" * 15 + "i" * 15 + "L"
    world = make_world(ruleset, [wire], LEGEND)
    i = ruleset.index
    lit = None
    for frame in range(1, 60):
        world.step()
        if lit is None and world.cells[0, -1] == i("lamp_on"):
            lit = frame
    assert lit is not None and 28 <= lit <= 34  # a cell a frame, 30 cells of copper and iron
    metals = world.cells[0, 1:31]
    assert set(np.unique(metals)) <= {i("copper"), i("iron"), i("spark"), i("spent")}
    held = world.state.carry[0, 1:31]
    kinds = np.where(held != 0, held, metals)
    assert (kinds[:15] == i("copper")).all() and (kinds[15:] == i("iron")).all()  # each cell still remembers its metal


def test_a_dye_stains_water_and_the_stain_moves_with_it(ruleset):
    rows = ["..D...", "..W...", "......", "......", "######"]
    world = run(make_world(ruleset, rows, LEGEND), 40)
    i = ruleset.index
    dyed = world.cells == i("dyed_water")
    assert dyed.sum() == 1 and world.state.carry[dyed][0] == i("dye")  # it fell to the floor holding the dye
    assert (world.shown()[dyed] == i("dye")).all()
    colour = world.image()[dyed][0]
    assert colour in ruleset.looks.normal[i("dye")]


def test_only_elements_that_can_hold_keep_anything(ruleset):
    t, i = ruleset.tables, ruleset.index
    assert t.remembers[i("clone_on")] and t.remembers[i("virus")] and t.remembers[i("spark")] and t.remembers[i("spent")]
    assert not t.remembers[i("sand")] and not t.remembers[i("water")] and t.remembers[ruleset.particle]


@pytest.mark.parametrize("field, value, message", [
    ("a_holds", '"@c"', "reactions.0.a_holds: must be an element name like 'sand' or 'base:stone', or '@a', '@b', '@a.held' or '@b.held' (got '@c')"),
    ("b_becomes", '"@held"', "reactions.0.b_becomes: must be an element name"),
])
def test_a_cell_word_misspelt_is_one_line(tmp_path, field, value, message):
    text = f'[mod]\nname = "m"\n[elements.x]\narchetype = "static"\ncolor = "#ffffff"\n[[reactions]]\na = "x"\nb = "x"\n{field} = {value}\nchance = 1\n'
    with pytest.raises(ProblemsError) as caught:
        load_ruleset(["base", "m"], [write_mods(tmp_path, {"m.toml": text})])
    assert message in str(caught.value)


def test_a_particle_a_reaction_makes_carries_what_b_holds_says(tmp_path):
    text = MEMORY + """
[elements.sifter]
archetype = "static"
color = "#806040"
tags = ["machine"]
[[reactions]]
a = "sifter"
b = "water:water"
where = ["above"]
b_becomes = "base:particle"
b_holds = "sand:sand"
chance = 1
"""
    rules = load_ruleset(["base", "sand", "water", "mem"], [write_mods(tmp_path, {"mem.toml": text})])
    legend = {**LEGEND, "F": "sifter"}
    world = make_world(rules, ["...W...", ".......", "...F...", "#######"], legend)
    i = rules.index
    run(world, 3)
    flying = world.cells == rules.particle
    assert flying.sum() == 1 and world.state.carry[flying][0] == i("sand")  # the water drop turned into a grain in flight
    run(world, 30)
    assert world.counts().get("sand:sand") == 1 and "water:water" not in world.counts()  # landed as sand


def test_what_a_fluid_holds_rises_with_it_as_sand_sinks_through_it(ruleset):
    rows = ["..SSS..", "..SSS..", "..ddd..", "..ddd..", "..ddd..", "..ddd..", "#######"]
    world = make_world(ruleset, rows, LEGEND)
    i = ruleset.index
    world.state.carry[world.cells == i("dyed_water")] = i("dye")
    assert ruleset.tables.movers_hold[0] == 1
    run(world, 80)
    dyed = world.cells == i("dyed_water")
    assert dyed.sum() == 12 and (world.state.carry[dyed] == i("dye")).all()  # each drop still holds its dye
    assert (world.state.carry[world.cells == i("sand")] == 0).all() and world.cells[5, 3] == i("sand")  # the sand sank to the floor
