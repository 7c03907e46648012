"""Sleeping chunks and parallel tiles: a pure speed-up, never a change in what happens."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from conftest import as_rows, make_world, run, write_mods
from sandmod.jobs import benchmark
from sandmod.world.loading import load_ruleset, load_world
from sandmod.engine.layout import CACHE_LINE, CHUNK, PART, TILE, WAKE_MARGIN, WHOLE
from sandmod.world.world import World

EXAMPLES = Path(__file__).parent.parent / "examples"


def digest(world) -> str:
    """A hash of every cell's state: its values, whatever width each array stores them in, and its
    elements by id, whatever numbers the compiler gave them and whatever else is loaded."""
    ids = [e.id for e in world.ruleset.elements]
    shown = np.unique(np.concatenate([world.state.cells.ravel(), world.state.carry.ravel()]))
    present = sorted(ids[k] for k in shown)
    code = np.full(len(ids), -1, np.int64)
    code[[ids.index(i) for i in present]] = np.arange(len(present))
    h = hashlib.sha256("\n".join(present).encode())
    for name, array in zip(world.state._fields, world.state):
        h.update((code[array] if name in ("cells", "carry") else array.astype(np.int64)).tobytes())
    return h.hexdigest()


@pytest.mark.parametrize(
    ("name", "frames"),
    [("demolition", 300), ("forest_fire", 200), ("lava_lake", 150), ("fountain", 150), ("piles", 200), ("acid_wall", 150)],
)
def test_sleeping_chunks_change_nothing(name, frames):
    # The same world stepped with every chunk forced awake gives the same state on every frame.
    sleeping = load_world(EXAMPLES / f"{name}.toml").world
    awake = load_world(EXAMPLES / f"{name}.toml").world
    slept = 0.0
    for frame in range(frames):
        slept += 1 - sleeping.awake_fraction
        awake.wake()
        sleeping.step()
        awake.step()
        assert digest(sleeping) == digest(awake), f"frame {frame}"
    assert slept / frames > 0.1  # and the chunks did sleep


@pytest.mark.parametrize(("name", "frames"), [("lava_lake", 150), ("forest_fire", 150), ("boiling_pool", 120), ("fountain", 120)])
def test_skipping_even_heat_changes_nothing(name, frames):
    # Conduction left out where a chunk's heat is even gives the same state as a sweep of every awake chunk.
    skipping = load_world(EXAMPLES / f"{name}.toml").world
    sweeping = load_world(EXAMPLES / f"{name}.toml").world
    skipped = 0.0
    for frame in range(frames):
        skipped += skipping._even.mean()
        sweeping._even[:] = 0
        skipping.step()
        sweeping.step()
        assert digest(skipping) == digest(sweeping), f"frame {frame}"
    assert skipped / frames > 0.1  # and heat was found even


def test_a_hot_grain_falling_through_even_air_warms_it_on_its_way(ruleset):
    def dropped():
        world = make_world(ruleset, ["." * 6] * 120)  # four chunks high
        for _ in range(3):
            world.step()
        assert world._even.all()
        grain = np.zeros(world.cells.shape, bool)
        grain[1, 3] = True
        world.paint(grain, ruleset.index("sand"))
        world.set_temperature(grain, 600)
        return world

    skipping, sweeping = dropped(), dropped()
    for frame in range(40):
        sweeping._even[:] = 0
        skipping.step()
        sweeping.step()
        assert digest(skipping) == digest(sweeping), f"frame {frame}"
    sand = np.argwhere(skipping.cells == ruleset.index("sand"))[0]
    assert sand[0] > 100  # it fell into chunks whose heat was even
    assert skipping._temperature_units()[70:100].max() > skipping._temperature_units()[0, 0]  # and warmed the air there


def stepped_both_ways(world_of, frames, switch="_also_present", values=(0, -1)):
    """Step two copies of a world with one of the kernel's test switches set to each of ``values``
    (by default: skipping absent partners, and looking next to every cell, see kernel.step_region);
    returns the frame at which they first differ (None: never)."""
    plain, changed = world_of(), world_of()
    setattr(plain, switch, values[0])
    setattr(changed, switch, values[1])
    for frame in range(frames):
        plain.step()
        changed.step()
        if digest(plain) != digest(changed):
            return frame
    return None


def random_world(ruleset, seed, size=40):
    """One to three elements, at random, over a world that is full or has gaps, some cells heated or chilled."""
    r = np.random.default_rng(seed)
    world = World(ruleset, size, size, seed)
    kinds = r.choice(np.arange(1, len(ruleset.elements)), size=r.integers(1, 4), replace=False)
    pick = r.integers(0, len(kinds) + 1, size=(size, size))
    for i, element in enumerate(kinds):
        world.paint(pick == i, int(element))
    if r.random() < 0.5:
        world.paint(pick == len(kinds), int(kinds[0]))  # full: not one empty cell
    world.set_temperature(r.random((size, size)) < 0.3, float(r.choice([-50, 20, 150, 500, 1500])))
    return world


def test_the_fast_loop_changes_nothing(ruleset):
    # The fast loop's cases (resting cells, a straight fall into a fluid) done by the full update instead:
    # every tile routed through it, against none.
    both = {"switch": "_fast_route", "values": (-1, 1)}
    differ = [(seed, stepped_both_ways(lambda: random_world(ruleset, seed), 40, **both)) for seed in range(120)]
    assert [(seed, frame) for seed, frame in differ if frame is not None] == []
    for scene in ("halves", "mix", "everything", "settled"):
        assert stepped_both_ways(benchmark.scene_bench(ruleset, scene, 128, seed=3).make, 150, **both) is None, scene
    for name in ("hourglass", "boiling_pool", "fountain", "tall_drop"):
        assert stepped_both_ways(lambda: load_world(EXAMPLES / f"{name}.toml").world, 200, **both) is None, name


def test_each_tile_takes_the_fast_loop_where_it_pays(ruleset):
    # Sand sinking through water is mostly resting water, waiting grains and straight falls; mix's
    # first frames are nearly all cells in flight, which the fast loop hands on to the full update.
    halves, mix = (benchmark.scene_bench(ruleset, scene, 256).make() for scene in ("halves", "mix"))
    for _ in range(100):
        halves.step()
    for _ in range(10):
        mix.step()
    assert (halves._fast_gain > 0).mean() >= 0.5
    assert (mix._fast_gain < 0).mean() > 0.9  # every tile has tried it by frame 8


def test_skipping_absent_partners_changes_nothing(ruleset):
    # Fire lit, phases changed, particles landed: elements new to a region on the frame they appear.
    differ = [(seed, stepped_both_ways(lambda: random_world(ruleset, seed), 40)) for seed in range(120)]
    assert [(seed, frame) for seed, frame in differ if frame is not None] == []
    assert stepped_both_ways(benchmark.scene_bench(ruleset, "everything", 96, seed=5).make, 100) is None


def vanishing_mod(tmp_path):
    return write_mods(
        tmp_path / "mods",
        {
            "vanish.toml": """
            [mod]
            name = "vanish"
            [elements.melt]
            archetype = "static"
            color = "#aa8800"
            [elements.fleeting]
            archetype = "static"
            color = "#442200"
            lifetime = { frames = 1, becomes = "empty" }
            [[reactions]]
            a = "melt"
            b = "stone"
            a_becomes = "empty"
            chance = 1
            """
        },
    )


@pytest.mark.parametrize(
    "rows",
    [
        ["WW", "SM"],  # the bottom row goes right to left on frame 0: melt looks first, and becomes empty
        ["WW", "MS"],  # stone looks first, and the melt it touches becomes empty
        ["WW", "FF"],  # fleeting cells live one frame
    ],
)
def test_a_cell_emptied_in_a_full_region_takes_the_water_above_on_that_frame(registry, tmp_path, rows):
    rs = load_ruleset(["vanish", "water"], [vanishing_mod(tmp_path)], registry=registry)
    legend = {".": "empty", "W": "water", "S": "stone", "M": "melt", "F": "fleeting"}
    assert stepped_both_ways(lambda: make_world(rs, rows, legend), 1) is None
    assert "W" in as_rows(run(make_world(rs, rows, legend), 1), legend)[1]  # the water fell in at once


def test_frames_are_the_same_on_any_number_of_threads():
    code = """
import hashlib, sys
from sandmod.world.loading import load_world
def run(name, frames, threads):
    world = load_world(sys.argv[1] + "/" + name + ".toml").world
    world.threads = threads
    h = hashlib.sha256()
    for _ in range(frames):
        world.step()
        for array in world.state:
            h.update(array.tobytes())
    return h.hexdigest()
for name, frames in (("demolition", 280), ("fountain", 120), ("boiling_pool", 120)):
    one = run(name, frames, 1)
    for threads in (2, 3, 4, None):
        assert run(name, frames, threads) == one, (name, threads)
print("same")
"""
    env = os.environ | {"NUMBA_NUM_THREADS": "4"}
    done = subprocess.run([sys.executable, "-c", code, str(EXAMPLES)], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "same"


def layered(ruleset, width=100, height=80):
    """Full rows of water over full rows of sand: nothing can move."""
    rows = ["." * width] * (height // 2) + ["W" * width] * (height // 4) + ["S" * width] * (height - height // 2 - height // 4)
    return make_world(ruleset, rows)


def test_a_world_at_rest_falls_asleep(ruleset):
    world = run(layered(ruleset), 5)
    assert world.awake_fraction == 0.0
    before = digest(world)
    run(world, 10)
    assert digest(world) == before and world.frame == 15


def test_a_chunk_wakes_where_it_is_touched_and_sleeps_again(ruleset):
    world = run(make_world(ruleset, ["." * 100] * 60 + ["S" * 100] * 20), 5)
    assert world.awake_fraction == 0.0
    # A grain dropped in wakes only the chunks around it; it falls, lands, and all sleeps again.
    world.paint_cells(np.array([2]), np.array([70]), ruleset.index("sand"))
    assert world.awake.sum() == 1 and world.awake[0, 70 // CHUNK] == 1
    for _ in range(100):
        world.step()
        if world.awake_fraction == 0.0:
            break
    assert world.awake_fraction == 0.0 and world.frame < 100
    assert (world.cells[:59] == 0).all() and (world.cells[59] != 0).sum() == 1  # it lies on the sand


def test_a_chunk_updates_only_the_rows_near_a_change(ruleset):
    sand = ruleset.index("sand")
    world = run(make_world(ruleset, ["." * 100] * 60 + ["S" * 100] * 20), 5)
    world.paint_cells(np.array([2]), np.array([70]), sand)
    assert world.awake[0, 70 // CHUNK] == WHOLE  # painting wakes whole chunks
    world.step()
    (y,) = np.nonzero(world.cells[:CHUNK, 70])  # the grain fell a cell or two
    assert world.awake[0, 70 // CHUNK] == PART | 0 | (y[0] + WAKE_MARGIN) << 6  # rows 0 .. its row + 2
    # A grain written straight into the state, far below those rows, is not noticed...
    world.state.cells[20, 75] = sand
    world.step()
    assert world.cells[20, 75] == sand
    # ...until the world is told (what every method that changes cells does).
    world.wake()
    world.step()
    assert world.cells[20, 75] == 0


def test_an_explosion_wakes_what_it_reaches(ruleset):
    from sandmod.formats.modspec import Explosion

    world = run(layered(ruleset), 5)
    world.explode(50, 45, Explosion(radius=6, strength=2))
    assert world.awake.any() and not world.awake[:, 0].any()
    run(world, 3)
    assert (world.cells[40:46, 45:56] == 0).any()  # a hole in the water, and things moving


def test_a_falling_stream_stays_together_across_tile_seams(ruleset):
    # Tiles are updated in passes; a grain must not mistake the unmoved grain below it
    # (in a tile updated later) for the ground and slide off sideways.
    height = 3 * TILE
    world = make_world(ruleset, ["." * 9] * (height - 1) + ["#" * 9])
    sand = ruleset.index("sand")
    for _ in range(120):
        world.paint_cells(np.array([0]), np.array([4]), sand)
        world.step()
    in_air = world.cells[: height - 40] == sand
    assert in_air.sum() > 20 and (np.nonzero(in_air)[1] == 4).all()


def test_the_marks_threads_write_lie_on_cache_lines_of_their_own(ruleset):
    """Threads updating tiles side by side write these marks often; sharing lines, the cores would fight over them."""
    world = World(ruleset, 100, 70)
    for marks in (world._woken, world._stirred):
        assert marks.shape[:2] == world.awake.shape and not marks.any()
        assert marks.strides[1] == CACHE_LINE and marks.strides[0] == CACHE_LINE * marks.shape[1]


@pytest.mark.parametrize("size", [(8, 8), (32, 32), (20, 100), (100, 20)])
def test_worlds_of_every_size_give_the_kernel_the_same_types(ruleset, size):
    """Numba compiles the kernel anew for each set of argument types (about a minute): a world of one
    chunk must not need a compile of its own after a render of a larger one, or the other way round."""
    typed = lambda world: [numba.typeof(a) for a in (world.state, world.tables, world.awake, world._woken, world._even, world._stirred, world._detonations, world._fast_gain)]
    assert typed(World(ruleset, *size)) == typed(World(ruleset, 100, 70))


def test_step_calls_the_kernels_with_plain_numbers_not_literal_ones(ruleset):
    """A literal argument (``count = 0`` passed on) makes numba compile the callee again for that
    one value: the cells' update and all it calls, a quarter of a minute more on a first run."""
    from sandmod.engine import kernel

    world = World(ruleset, 100, 70)
    step = numba.njit(kernel.step.py_func)  # typed here, so the kernels it calls are looked up (in the cache) again
    step(world.state, world.tables, 1, 2, 3, 0, world.awake, world._woken, world._even, world._stirred, world._detonations, 1, 0, world._fast_gain, 0, world._seen)
    # A tile's update is checked, not what it calls: loaded from a warm cache, it types none of its calls again.
    for called in (kernel._update_tile, kernel.clear_marks, kernel._tiles_of_pass):
        assert called.signatures and not any("Literal" in str(sig) for sig in called.signatures), called


def test_a_run_on_one_thread_never_loads_or_starts_the_parallel_kernel():
    code = """
import sys
import numba.np.ufunc.parallel as parallel
from sandmod.engine import kernel
from sandmod.world.loading import load_world
from sandmod.jobs.warmup import compile_kernels
compile_kernels()
world = load_world(sys.argv[1] + "/hourglass.toml").world  # one tile a pass: too small for a second thread
for _ in range(50):
    world.step()
assert not kernel.update_tiles_at_once.signatures and not kernel.step_at_once.signatures
assert not parallel._is_initialized  # numba's threads were never started
print("serial")
"""
    done = subprocess.run([sys.executable, "-c", code, str(EXAMPLES)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "serial"


@pytest.mark.parametrize("start", ["fork", "spawn"])
def test_worker_processes_step_the_same_frames_after_the_parent_started_threads(start, tmp_path):
    # GNU OpenMP cannot run in a child forked after its threads started: such a child steps on one.
    code = """
import multiprocessing, sys
from sandmod.jobs import benchmark
from sandmod.world.loading import load_ruleset
ruleset = load_ruleset()
def work(threads):
    world = benchmark.scene_bench(ruleset, "mix", 256).make()
    world.threads = threads
    for _ in range(20):
        world.step()
    return benchmark.state_digest(world)
if __name__ == "__main__":
    parent = work(2)  # numba's threads started here
    with multiprocessing.get_context(sys.argv[1]).Pool(2) as pool:
        assert pool.map(work, [2, None, 1]) == [parent] * 3
    print("same")
"""
    script = tmp_path / "workers.py"  # spawned workers import their function from a real file
    script.write_text(code)
    done = subprocess.run([sys.executable, str(script), start], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "same"


def test_the_quick_step_of_a_first_run_gives_the_same_frames(ruleset, monkeypatch):
    # A first run steps with kernel.step_soon (the update without its fast loop, called by name, optimized
    # lightly) while kernel.step compiles; halves is where the fast loop takes most cells.
    from sandmod.engine import kernel, kernelcache
    from sandmod.world import world as world_module

    def digests(world_of, quick):
        with monkeypatch.context() as patched:
            patched.setattr(world_module, "_STEP_COMPILED", not quick)
            patched.setattr(kernelcache, "best_step_cached", lambda: not quick)
            world = world_of()
            world.threads = 1
            assert world_module._serial_step(kernel) is (kernel.step_soon if quick else kernel.step)
            return [(world.step(), digest(world))[1] for _ in range(150)]

    for scene in ("mix", "halves", "everything"):
        make = benchmark.scene_bench(ruleset, scene, 128, seed=3).make
        assert digests(make, True) == digests(make, False), scene
    boiling = lambda: load_world(EXAMPLES / "boiling_pool.toml").world  # noqa: E731
    assert digests(boiling, True) == digests(boiling, False)
