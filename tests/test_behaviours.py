"""Plugin behaviours: named by elements, run after the kernel's step by a pass compiled on its own.

What they make is counted in cells; a world without them never imports the pass;
the frames are the same on any number of threads; an unknown name, and a behaviour
that does not compile, are each one line; the kernel is not compiled again.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from sandmod.api import arg, behaviour, here, hookimpl, look, put, swap, temperature
from sandmod.errors import ProblemsError
from sandmod.registry import collect, make_plugin_manager
from sandmod.rules.compiler import compile_mods
from sandmod.rules.modset import find_mods
from sandmod.world.world import World

ROOT = Path(__file__).resolve().parent.parent
GARDEN = ROOT / "examples" / "garden-plugin"


@behaviour(args=("into",))
def climb(v):
    """Put ``into`` in the empty cell above, every frame."""
    if look(v, 0, -1) == 0:
        put(v, 0, -1, int(arg(v, 0)))


@behaviour()
def walk(v):
    """Step right into an empty cell, every frame."""
    if look(v, 1, 0) == 0:
        swap(v, 1, 0)


@behaviour(args={"into": None, "above": 100.0})
def melt(v):
    """Turn into ``into`` when hotter than ``above`` degrees."""
    if temperature(v, 0, 0) > arg(v, 1):
        put(v, 0, 0, int(arg(v, 0)))


@behaviour()
def broken(v):
    v.nothing_here[0] = here(v)  # no such field: does not compile


def plugin(*pairs, elements: dict) -> object:
    class Plugin:
        @hookimpl
        def register_behaviours(register):
            for name, function in pairs:
                register(name, function)

        @hookimpl
        def register_mods(register):
            register({"mod": {"name": "lab"}, "elements": elements}, "lab (python)")

    return Plugin


def rules(*pairs, elements: dict, name: str = "lab"):
    pm = make_plugin_manager(entry_points=False)
    pm.register(plugin(*pairs, elements=elements), name=name)
    modset = find_mods(collect(pm))
    return compile_mods(modset.select(["lab"]), modset.behaviours)


STATIC = {"archetype": "static", "color": "#33aa33"}


def test_a_behaviour_makes_one_cell_a_frame_across_sleeping_chunks():
    rs = rules(("climb", climb), elements={"vine": {**STATIC, "behaviour": "lab:climb", "behaviour_args": {"into": "vine"}}})
    world = World(rs, 64, 64)
    vine = rs.index("lab:vine")
    world.paint_cells(np.array([63]), np.array([5]), vine)
    world.run(40)
    column = world.cells[:, 5]
    assert (world.cells == vine).sum() == 41 and (column[23:] == vine).all()  # one a frame, up across a chunk's edge


def test_the_pass_walks_no_chunk_far_from_behaviour_cells_however_busy():
    rs = rules(("climb", climb), elements={
        "vine": {**STATIC, "behaviour": "lab:climb", "behaviour_args": {"into": "vine"}},
        "grain": {"archetype": "powder", "color": "#ccaa66", "density": 1500},
    })
    world = World(rs, 256, 64)
    world.paint_cells(np.array([63]), np.array([5]), rs.index("lab:vine"))
    ys, xs = np.mgrid[0:20, 192:240]
    world.paint_cells(ys.ravel(), xs.ravel(), rs.index("lab:grain"))
    for _ in range(3):
        before = world.awake.copy()
        world.step()
        visited = world._walker.visited(world, before)
        assert world.awake[:, 6:].any()  # the grains' chunks are busy...
        assert not visited[:, 4:].any() and visited[1, 0]  # ...and never walked: only the vine's, and those near it
    assert (world.cells == rs.index("lab:vine")).sum() == 4


def test_swap_walks_a_cell_one_step_a_frame():
    rs = rules(("walk", walk), elements={"ant": {**STATIC, "behaviour": "lab:walk"}})
    world = World(rs, 100, 8)
    world.paint_cells(np.array([4]), np.array([10]), rs.index("lab:ant"))
    world.run(50)
    assert list(zip(*np.nonzero(world.cells == rs.index("lab:ant")))) == [(4, 60)]


def test_arguments_take_defaults_and_temperature_reads_the_cell():
    rs = rules(("melt", melt), elements={"wax": {**STATIC, "behaviour": "lab:melt", "behaviour_args": {"into": "empty"}}})
    assert rs.behaviours.args[rs.index("lab:wax")].tolist() == [0.0, 100.0]
    world = World(rs, 8, 8)
    wax = rs.index("lab:wax")
    world.paint(np.ones((8, 8), bool), wax)
    hot = np.zeros((8, 8), bool)
    hot[:, :3] = True
    world.set_temperature(hot, 500)
    world.step()
    assert (world.cells == wax).sum() == 40  # the three hot columns melted, the rest did not


def test_a_ruleset_without_behaviours_has_none_and_never_imports_the_pass():
    code = """
import sys
from sandmod.world.loading import load_world
loaded = load_world(sys.argv[1])
loaded.world.run(3)
print(loaded.ruleset.behaviours, sorted(m for m in sys.modules if m.startswith("sandmod.passes")))
"""
    done = subprocess.run([sys.executable, "-c", code, str(ROOT / "examples" / "hourglass.toml")], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "None []"


def test_a_behaviour_that_does_not_compile_is_one_problem_naming_its_plugin():
    rs = rules(("broken", broken), ("climb", climb), name="bad-plugin", elements={
        "vine": {**STATIC, "behaviour": "bad-plugin:climb", "behaviour_args": {"into": "vine"}},
        "rot": {**STATIC, "behaviour": "bad-plugin:broken"},
    })
    world = World(rs, 8, 8)
    world.paint(np.ones((8, 8), bool), rs.index("lab:rot"))
    with pytest.raises(ProblemsError) as caught:
        world.step()
    (problem,) = caught.value.problems
    line = broken.function.__code__.co_firstlineno + 2  # the decorator's line, the def, then the mistake
    assert str(problem).startswith("bad-plugin: behaviour bad-plugin:broken: does not compile: ")
    assert str(problem).endswith(f"Unknown attribute 'nothing_here' of type View (tests/test_behaviours.py:{line})")


MOD = """\
[mod]
name = "lab"

[elements.vine]
archetype = "static"
color = "#33aa33"
behaviour = "lab:climbs"
behaviour_args = { into = "vine" }

[elements.moss]
archetype = "static"
color = "#33aa33"
behaviour = "nobody:grows"

[elements.ivy]
archetype = "static"
color = "#33aa33"
behaviour_args = { into = "vine" }
"""


def test_unknown_behaviours_and_arguments_are_one_line_each_and_exit_2(tmp_path, monkeypatch):
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "lab.toml").write_text(MOD)
    monkeypatch.chdir(tmp_path)
    from sandmod.tools.cli import cli

    result = CliRunner().invoke(cli, ["validate", "mods"])
    assert result.exit_code == 2
    lines = sorted(line for line in result.output.splitlines() if line.startswith("mods/lab.toml"))
    assert lines == [
        "mods/lab.toml:13:1: elements.moss.behaviour: no plugin gives a behaviour 'nobody:grows' (known: none is installed)",
        "mods/lab.toml:18:1: elements.ivy.behaviour_args: arguments without a 'behaviour' to take them",
        "mods/lab.toml:7:1: elements.vine.behaviour: no plugin gives a behaviour 'lab:climbs' (known: none is installed)",
    ], result.output


def test_arguments_a_behaviour_does_not_take_or_needs_are_named():
    with pytest.raises(ProblemsError) as caught:
        rules(("climb", climb), elements={"vine": {**STATIC, "behaviour": "lab:climb", "behaviour_args": {"height": 3}}})
    assert [p.path + ": " + p.message for p in caught.value.problems] == [
        "elements.vine.behaviour_args.height: the behaviour takes no argument 'height' (it takes: into)",
        "elements.vine.behaviour_args: the behaviour needs argument 'into'",
    ]


def test_a_name_registered_twice_or_not_a_name_is_a_problem():
    class Twice:
        @hookimpl
        def register_behaviours(register):
            register("grow", climb)
            register("grow", climb)
            register("Grow!", climb)

    pm = make_plugin_manager(entry_points=False)
    pm.register(Twice, name="twice")
    with pytest.raises(ProblemsError) as caught:
        collect(pm)
    assert [p.message.split(",")[0] for p in caught.value.problems] == [
        "'twice:grow' is registered twice",
        "register(name",
    ]


THREADS = """
import hashlib, sys
from pathlib import Path
sys.path.insert(0, sys.argv[1])
import sandmod_garden
from sandmod.registry import collect, make_plugin_manager
from sandmod.world.loading import load_world
pm = make_plugin_manager(entry_points=False)
pm.register(sandmod_garden, name="garden")
registry = collect(pm)

def run(threads):
    world = load_world(Path(sys.argv[2]), registry=registry).world
    world.threads = threads
    h = hashlib.sha256()
    for _ in range(150):
        world.step()
        for array in world.state:
            h.update(array.tobytes())
    return h.hexdigest(), world.counts().get("garden:vine", 0)

one, two = run(1), run(2)
print(one == two, one[1] > 100)
"""

BIG_GARDEN = """
[world]
width = 256
height = 256
seed = 11
mods = ["garden"]

[[scene]]
shape = "rect"
element = "dirt"
x = 0
y = 240
width = 256
height = 16

[[emitters]]
shape = "rect"
element = "seed"
x = 0
y = 100
width = 256
height = 1
chance = 0.01
stop = 40
"""


def test_a_garden_grows_the_same_on_one_thread_and_two(tmp_path):
    world = tmp_path / "garden.toml"
    world.write_text(BIG_GARDEN)
    env = os.environ | {"NUMBA_NUM_THREADS": "2"}
    done = subprocess.run([sys.executable, "-c", THREADS, str(GARDEN), str(world)], env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True"]


KERNEL_STAYS = """
import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
import lab_plugin
from sandmod.registry import collect, make_plugin_manager
from sandmod.rules.compiler import compile_mods
from sandmod.rules.modset import find_mods
from sandmod.world.world import World
pm = make_plugin_manager(entry_points=False)
pm.register(lab_plugin, name="fresh")
modset = find_mods(collect(pm))
rs = compile_mods(modset.select(["fresh_lab"]), modset.behaviours)
World(compile_mods(modset.select([]), modset.behaviours), 8, 8).step()  # the kernel, loaded from its cache
world = World(rs, 32, 32)
world.paint_cells(np.array([31]), np.array([3]), rs.index("fresh_lab:vine"))
started = time.perf_counter()
world.step()
print(f"{time.perf_counter() - started:.2f}", int((world.cells != 0).sum()))
"""

LAB_PLUGIN = '''
from sandmod.api import arg, behaviour, hookimpl, look, put

SALT = {salt}  # a new behaviour, each run of the test: compiled cold


@behaviour(args=("into",))
def climb(v):
    if look(v, 0, -1) == 0:
        put(v, 0, -1, int(arg(v, 0)))


@hookimpl
def register_behaviours(register):
    register("climb", climb)


@hookimpl
def register_mods(register):
    register({{"mod": {{"name": "fresh_lab"}}, "elements": {{"vine": {{"archetype": "static", "color": "#00aa00",
        "behaviour": "fresh:climb", "behaviour_args": {{"into": "vine"}}}}}}}}, "fresh_lab")
'''


def kernel_index_files() -> dict[str, float]:
    """The kernel cache's index files and their times, the behaviours' passes left out."""
    from sandmod.engine.kernelcache import kernel_cache_dir

    return {str(p): p.stat().st_mtime_ns for p in kernel_cache_dir().rglob("*.nbi") if "behaviours" not in str(p)}


def test_a_new_behaviour_compiles_alone_and_the_kernel_is_loaded_from_its_cache(tmp_path):
    World(rules(elements={"rock": STATIC}), 8, 8).step()  # this version's kernel, compiled (or loaded)
    before = kernel_index_files()
    assert before
    (tmp_path / "lab_plugin.py").write_text(textwrap.dedent(LAB_PLUGIN.format(salt=os.getpid() ^ int.from_bytes(os.urandom(4), "little"))))
    done = subprocess.run([sys.executable, "-c", KERNEL_STAYS, str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    seconds, cells = done.stdout.split()
    assert int(cells) == 2  # the vine grew a cell
    assert kernel_index_files() == before  # no kernel compiled, none added to
    print(f"a new behaviours pass compiled in {seconds} s")


GARDEN_STEP = """
import hashlib, sys
sys.path.insert(0, sys.argv[1])
import sandmod_garden
from sandmod.registry import collect, make_plugin_manager
from sandmod.world.loading import load_world
from sandmod.world.snapshots import load_snapshot, save_snapshot
pm = make_plugin_manager(entry_points=False)
pm.register(sandmod_garden, name="garden")
registry = collect(pm)
path = sys.argv[1] + "/garden.toml"

def digest(world):
    return hashlib.sha256(b"".join(a.tobytes() for a in (*world.state, world.awake))).hexdigest()

straight = load_world(path, registry=registry).world
straight.run(160)
before = load_world(path, registry=registry).world
before.run(70)
save_snapshot(before, sys.argv[2])
before.run(30)  # a walker that has run, then a snapshot loaded into its world
load_snapshot(before, sys.argv[2])
before.run(90)
resumed = load_world(path, registry=registry).world
load_snapshot(resumed, sys.argv[2])
resumed.run(90)
print(digest(straight) == digest(before) == digest(resumed), straight.counts()["garden:vine"] > 100)
"""


def test_a_garden_resumed_from_a_snapshot_grows_as_it_would_have(tmp_path):
    done = subprocess.run([sys.executable, "-c", GARDEN_STEP, str(GARDEN), str(tmp_path / "s.npz")], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True"]
