"""What emitters and sprays paint every frame, in the kernel, against the numpy ``World.paint_cells``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sandmod.engine.hashing import SALT_SPRAY
from sandmod.world.world import World
from test_chunks import digest


def scattered_world(ruleset, seed: int) -> World:
    """A 96x80 world with a few elements scattered in it, every chunk asleep and its heat even."""
    world = World(ruleset, 96, 80, seed)
    rng = np.random.default_rng(seed)
    for name in ("sand", "water", "stone", "lava"):
        world.paint(rng.random((80, 96)) < 0.1, ruleset.index(name))
    world.awake[:] = 0
    world._even[:] = 1
    return world


def same_world(a: World, b: World) -> None:
    assert digest(a) == digest(b)
    assert np.array_equal(a.awake, b.awake)
    assert np.array_equal(a._even, b._even)


@pytest.mark.parametrize("chance", [1.0, 0.4, 0.02])
@pytest.mark.parametrize("only_empty", [True, False])
@pytest.mark.parametrize("name", ["sand", "fire", "lava"])  # at rest, with a lifetime, hot
def test_the_kernel_paints_what_paint_cells_paints(ruleset, chance, only_empty, name):
    reference, kernel = scattered_world(ruleset, 3), scattered_world(ruleset, 3)
    rng = np.random.default_rng(11)
    picked = rng.choice(96 * 80, 500, replace=False)  # distinct cells, edges and corners among them
    ys, xs = np.concatenate([picked // 96, [0, 79, 0, 79]]), np.concatenate([picked % 96, [0, 95, 95, 0]])
    painted = 0
    for frame in range(3):  # the rolls differ by frame
        reference.frame = kernel.frame = frame
        element = ruleset.index(name)
        expected = reference.paint_cells(ys, xs, element, chance=chance, only_empty=only_empty, salt=99)
        assert kernel._pour(ys, xs, element, chance=chance, only_empty=only_empty, salt=99) == expected
        same_world(reference, kernel)
        painted += expected
    assert 0 < painted


def spawn_reference(world: World, ys, xs, element: int, vx, vy) -> int:
    """``World.spawn_particles`` spelt out: the first time each cell is named, if it is empty, it becomes a
    particle carrying the element (a particle element flies as itself), at the velocity given."""
    t, s = world.tables, world.state
    ys, xs = np.asarray(ys, np.int64), np.asarray(xs, np.int64)
    vx, vy = np.broadcast_to(vx, ys.shape), np.broadcast_to(vy, ys.shape)
    first = np.sort(np.unique(ys * world.width + xs, return_index=True)[1])
    keep = first[s.cells[ys[first], xs[first]] == 0]
    ys, xs, vx, vy = ys[keep], xs[keep], vx[keep], vy[keep]
    flying = t.archetype[element] == world.tables.archetype[world.ruleset.particle]
    particle, cargo = (element, int(t.carries[element])) if flying else (world.ruleset.particle, element)
    world.paint_cells(ys, xs, particle, salt=SALT_SPRAY)
    s.carry[ys, xs] = cargo
    s.vx[ys, xs] = np.clip(np.round(vx * 256), -16 * 256, 16 * 256)
    s.vy[ys, xs] = np.clip(np.round(vy * 256), -16 * 256, 16 * 256)
    s.flags[ys, xs] = 0
    return len(xs)


@pytest.mark.parametrize("name", ["water", "base:particle"])
def test_particles_are_spawned_as_the_reference_spawns_them(ruleset, name):
    reference, kernel = scattered_world(ruleset, 5), scattered_world(ruleset, 5)
    rng = np.random.default_rng(2)
    ys, xs = rng.integers(0, 80, 300), rng.integers(0, 96, 300)  # some cells named twice, some full
    vx, vy = rng.uniform(-20, 20, 300), rng.uniform(-20, 20, 300)  # some beyond the fastest speed
    element = ruleset.index(name)
    expected = spawn_reference(reference, ys, xs, element, vx, vy)
    assert kernel.spawn_particles(ys, xs, element, vx, vy) == expected > 100
    same_world(reference, kernel)


def test_emitters_and_sprays_hand_the_kernel_arrays_of_one_layout():
    """Each layout of the cells' arrays is a signature numba compiles paint_cells for anew: an
    emitter's (a view of a shape's cells) was one more, compiled by the first world that poured."""
    from sandmod.engine import kernel
    from sandmod.world.loading import load_world
    from sandmod.world.scene import build_world

    loaded = load_world(str(Path(__file__).resolve().parent.parent / "examples" / "acid_wall.toml"))
    world = build_world(loaded.spec, loaded.ruleset, loaded.source, None)
    world.step()
    assert all(str(sig[2]).endswith(", C)") and str(sig[3]).endswith(", C)") for sig in kernel.paint_cells.signatures)
