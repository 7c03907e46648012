"""Timelines in world files: each event happens on its frame; mistakes name their line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sandmod.errors import ProblemsError
from sandmod.world.loading import load_world
from sandmod.engine.traversal import line_cells

HEAD = """
[world]
width = 40
height = 30
mods = ["sand", "water", "explosives"]

[[scene]]
shape = "rect"
element = "stone"
x = 0
y = 28
width = 40
height = 2
"""


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def world_from(tmp_path: Path, text: str):
    Path("w.toml").write_text(HEAD + text)
    return load_world("w.toml").world


def problems_of(tmp_path: Path, text: str) -> list[str]:
    with pytest.raises(ProblemsError) as caught:
        world_from(tmp_path, text)
    return [str(p) for p in caught.value.problems]


def steps(world, n: int) -> None:
    for _ in range(n):
        world.step()


def count(world, element: str) -> int:
    return int((world.cells == world.ruleset.index(element)).sum())


def test_paint_and_erase_happen_on_their_frame(tmp_path):
    world = world_from(
        tmp_path,
        """
[[timeline]]
frame = 5
paint = { shape = "rect", element = "stone", x = 10, y = 5, width = 4, height = 3 }

[[timeline]]
frame = 9
erase = { shape = "rect", x = 0, y = 28, width = 20, height = 2 }
""",
    )
    steps(world, 5)  # frames 0..4 done: the world is at frame 5, the event not yet happened
    assert count(world, "stone") == 80
    steps(world, 1)
    assert count(world, "stone") == 92 and (world.cells[5:8, 10:14] == world.ruleset.index("stone")).all()
    steps(world, 3)
    assert count(world, "stone") == 92
    steps(world, 1)
    assert count(world, "stone") == 52 and (world.cells[28:, :20] == 0).all()


def test_a_stroke_follows_its_polyline_without_gaps(tmp_path):
    points = [[2, 2], [30, 9], [12, 25], [37, 20]]
    world = world_from(
        tmp_path,
        f"""
[[scene]]
shape = "stroke"
element = "stone"
points = {points}
""",
    )
    stone = world.cells[:28] == world.ruleset.index("stone")
    wanted = {(int(x), int(y)) for a, b in zip(points, points[1:]) for x, y in line_cells(*a, *b)}
    assert {(int(x), int(y)) for y, x in zip(*np.nonzero(stone))} == wanted
    for a, b in zip(points, points[1:]):  # each segment: consecutive cells touch (8-neighbours)
        cells = list(line_cells(*a, *b))
        assert all(max(abs(p[0] - q[0]), abs(p[1] - q[1])) == 1 for p, q in zip(cells, cells[1:]))


def test_start_and_stop_switch_a_named_emitter(tmp_path):
    world = world_from(
        tmp_path,
        """
[[emitters]]
name = "tap"
shape = "rect"
element = "sand"
x = 18
y = 0
width = 4
height = 1
chance = 1.0
start = 2

[[timeline]]
frame = 6
stop = "tap"

[[timeline]]
frame = 20
start = "tap"
""",
    )
    poured = []
    for _ in range(24):
        world.step()
        poured.append(count(world, "sand"))
    assert poured[1] == 0 and poured[2] > 0  # its own start
    assert poured[5] > poured[4] and poured[6:20] == [poured[5]] * 14  # stopped from frame 6
    assert poured[20] > poured[19]  # started again on frame 20


def test_a_line_emitter_has_its_own_start_and_stop_beside_its_from_and_to(tmp_path):
    """A line's ends are "from" and "to": its start and stop are frames, as every emitter's."""
    world = world_from(
        tmp_path,
        """
[[emitters]]
shape = "line"
element = "sand"
from = [10, 0]
to = [30, 0]
chance = 1.0
start = 3
stop = 5
""",
    )
    poured = []
    for _ in range(8):
        world.step()
        poured.append(count(world, "sand"))
    assert poured[2] == 0 and poured[3] > 0 and poured[4] > poured[3] and poured[5:] == [poured[4]] * 3


def test_launch_sends_a_shapes_cells_flying_as_particles_that_land_as_themselves(tmp_path):
    world = world_from(
        tmp_path,
        """
[[scene]]
shape = "rect"
element = "sand"
x = 15
y = 24
width = 10
height = 4

[[timeline]]
frame = 3
launch = { shape = "rect", x = 15, y = 24, width = 10, height = 4, direction = 90, spread = 60, speed = [2, 3] }
""",
    )
    steps(world, 3)
    assert count(world, "particle") == 0 and count(world, "sand") == 40
    steps(world, 1)
    assert count(world, "particle") > 30  # in flight, carrying sand
    steps(world, 60)
    assert count(world, "particle") == 0 and count(world, "sand") == 40  # landed, every grain


def test_spawn_explode_and_heat_happen_on_their_frame(tmp_path):
    world = world_from(
        tmp_path,
        """
[[scene]]
shape = "rect"
element = "stone"
x = 28
y = 10
width = 8
height = 8

[[timeline]]
frame = 4
spawn = { element = "water", at = [5, 10], radius = 2, count = 6, direction = 45, speed = 2 }

[[timeline]]
frame = 7
explode = { at = [32, 14], radius = 3, strength = 40 }

[[timeline]]
frame = 3
heat = { shape = "rect", x = 0, y = 28, width = 4, height = 2, temperature = 900, frames = 5 }
""",
    )
    particle = "base:particle"
    steps(world, 3)
    assert world.temperature()[28:, :4].max() < 100
    steps(world, 1)  # frame 3: the heat source set them to 900 before the step, which conducted a little away
    held = world.temperature()[28:, :4]
    assert held.min() > 800
    assert world.counts().get(particle, 0) == 0
    steps(world, 1)  # frame 4: the particles fly
    assert world.counts(carried=True).get("water:water", 0) == 6 and world.counts()[particle] == 6
    steps(world, 2)
    assert world.temperature()[28:, :4].min() > 800  # still held (frames 3..7)
    stone_before = count(world, "stone")
    steps(world, 1)  # frame 7: the blast, after the step
    assert count(world, "stone") < stone_before
    steps(world, 30)
    assert world.temperature()[28:, :4].mean() < held.mean() - 20  # no longer held: it spreads into the floor


def test_timeline_mistakes_name_their_line_and_field(tmp_path):
    lines = problems_of(
        tmp_path,
        """
[[emitters]]
name = "tap"
shape = "circle"
element = "sand"
x = 5
y = 5
radius = 2

[[timeline]]
frame = 3
stop = "tapp"

[[timeline]]
frame = 4
paint = { shape = "circle", element = "sandd", x = 5, y = 5, radius = 2 }

[[timeline]]
frame = 5
erase = { shape = "rect", x = 50, y = 50, width = 3, height = 3 }
""",
    )
    assert lines == [
        "w.toml:25:1: timeline.0.stop: no emitter or spray is called 'tapp' (named: tap)",
        "w.toml:29:29: timeline.1.paint.element: unknown element 'sandd' (did you mean 'sand'?)",
        "w.toml:33:1: timeline.2.erase: the shape lies outside the 40x30 world",
    ]


def test_an_event_does_exactly_one_thing(tmp_path):
    lines = problems_of(
        tmp_path,
        """
[[timeline]]
frame = 3
stop = "a"
start = "b"

[[timeline]]
frame = -1
erase = { shape = "circle", element = "sand", x = 5, y = 5, radius = 2 }
""",
    )
    assert lines == [
        "w.toml:15:1: timeline.0: give exactly one of paint, erase, heat, start, stop, spawn, launch, explode (got start, stop)",
        "w.toml:21:1: timeline.1.frame: must be >= 0 (got -1)",
        "w.toml:22:1: timeline.1.erase: 'erase' empties its cells; leave 'element' out (or 'paint' with it)",
    ]


def test_load_world_finds_mods_as_the_command_line_does(tmp_path, monkeypatch):
    from sandmod.world.loading import load_world

    monkeypatch.chdir(tmp_path)
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "goo.toml").write_text(
        '[mod]\nname = "goo"\n[elements.goo]\narchetype = "liquid"\ndensity = 1.5\ndispersion = 2\ncolor = "#33aa44"\n'
    )
    (tmp_path / "worlds").mkdir()
    (tmp_path / "worlds" / "w.toml").write_text(
        '[world]\nwidth = 8\nheight = 8\nmods = ["goo"]\n[[scene]]\nshape = "rect"\nelement = "goo"\nx = 1\ny = 1\nwidth = 2\nheight = 2\n'
    )
    loaded = load_world("worlds/w.toml")  # goo is in ./mods, not beside the world
    assert (loaded.world.cells == loaded.ruleset.index("goo")).sum() == 4
