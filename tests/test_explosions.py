"""Explosions: round holes, rays stopped by resistant cells, scorch only past the destruction,
each cell handled once, and blasts from world files."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import make_world
from sandmod.formats.modspec import Explosion
from sandmod.engine.layout import SCORCHED


def field(ruleset, char="#", size=61):
    return make_world(ruleset, [char * size] * size)


def blasted(world, char="#"):
    """The cells a blast destroyed in a field of one element: stone's are left as rubble (its breaks_into)."""
    return world.cells != world.ruleset.index({"#": "stone", "S": "sand"}[char])


def distances(size, cx, cy):
    ys, xs = np.mgrid[0:size, 0:size]
    return np.hypot(xs - cx, ys - cy)


@pytest.mark.parametrize("radius", [3, 8, 17])
def test_an_unresisted_blast_leaves_exactly_the_disc_of_its_radius(ruleset, radius):
    world = field(ruleset)
    world.explode(30, 30, Explosion(radius=radius, strength=10_000, fling=0, scorch=0))
    hole = blasted(world)
    assert (hole == (distances(61, 30, 30) <= radius + 1e-9)).all()


def test_resistance_shortens_every_ray_alike_so_the_hole_stays_round(ruleset):
    world = field(ruleset)  # stone resists 2 a cell: strength 16 reaches about 8 cells, whatever the angle
    world.explode(30, 30, Explosion(radius=20, strength=16, fling=0, scorch=0))
    d = distances(61, 30, 30)[blasted(world)]
    assert d.max() <= 8.6 and (distances(61, 30, 30)[~blasted(world)] >= 7.0).all()


def test_titanium_stops_the_blast_and_shields_what_is_behind_it(ruleset):
    world = field(ruleset, "S")
    world.paint(_rect(world, 36, 20, 2, 21), ruleset.index("titanium"))  # a wall at x = 36..37
    before = world.cells.copy()
    world.explode(30, 30, Explosion(radius=14, strength=10_000, fling=0, scorch=4))
    shadow = np.zeros_like(before, bool)
    shadow[24:37, 38:45] = True  # straight behind the wall, within the blast's reach
    assert (world.cells[shadow] == before[shadow]).all()
    assert not (world.state.flags[shadow] & SCORCHED).any()
    assert (world.cells[20:41, 36:38] == ruleset.index("titanium")).all()
    assert (world.cells[30, 31:36] == 0).all()  # in front of it, the sand is gone


def _rect(world, x, y, width, height):
    mask = np.zeros(world.cells.shape, bool)
    mask[y : y + height, x : x + width] = True
    return mask


def test_scorch_marks_lie_only_outside_the_destroyed_area(ruleset):
    world = field(ruleset)
    world.explode(30, 30, Explosion(radius=9, strength=10_000, fling=0, scorch=4))
    scorched = (world.state.flags & SCORCHED) != 0
    d = distances(61, 30, 30)
    assert scorched.sum() > 20
    assert (world.cells[scorched] != 0).all() and d[scorched].min() > 9
    assert d[scorched].max() <= 9 + 4 + 1
    near, far = scorched[(d > 9) & (d <= 11)].mean(), scorched[(d > 11) & (d <= 14)].mean()
    assert near > far  # it falls off away from the hole


def test_each_destroyed_cell_flies_off_once(ruleset):
    world = field(ruleset, "S")
    before = world.counts(carried=True)
    world.explode(30, 30, Explosion(radius=10, strength=10_000, fling=1.0, speed=5, scorch=0))
    assert world.counts(carried=True)["sand:sand"] == before["sand:sand"]  # none lost, none doubled
    flying = world.state.carry != 0
    assert flying.sum() == (distances(61, 30, 30) <= 10).sum()
    # They fly outwards.
    ys, xs = np.nonzero(flying)
    outward = (xs - 30) * world.state.vx[flying] + (ys - 30) * world.state.vy[flying]
    assert (outward >= 0).all()


def test_a_heap_of_gunpowder_goes_off_in_a_chain(ruleset):
    world = make_world(ruleset, ["." * 60] * 20 + ["." * 10 + "P" * 40 + "." * 10] * 4 + ["#" * 60])
    world.set_temperature(_rect(world, 10, 20, 1, 1), 500.0)
    frames = 0
    while world.counts().get("explosives:gunpowder", 0) and frames < 200:
        world.step()
        frames += 1
    assert world.counts().get("explosives:gunpowder", 0) == 0
    assert frames > 3  # not one blast: a chain, grain after grain


def test_world_files_schedule_explosions(tmp_path):
    from sandmod.world.loading import load_world

    path = tmp_path / "w.toml"
    path.write_text(
        '[world]\nwidth = 40\nheight = 30\nmods = ["base"]\n'
        '[[scene]]\nshape = "rect"\nelement = "stone"\nx = 0\ny = 0\nwidth = 40\nheight = 30\n'
        "[[explosions]]\nframe = 3\nat = [20, 15]\nradius = 5\nstrength = 100\n",
        encoding="utf-8",
    )
    world = load_world(path).world
    for _ in range(3):
        world.step()
    assert (world.cells != 0).all()
    world.step()  # frame 3: it goes off after the step
    assert blasted(world).sum() == (distances(40, 20, 15)[:30, :40] <= 5).sum()
