"""Snapshots: resuming equals never stopping, bit for bit; elements travel by name; bad files are named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import invoke
from sandmod.errors import ProblemsError
from sandmod.world.loading import load_ruleset, load_world
from sandmod.world.snapshots import load_snapshot, save_snapshot
from sandmod.world.world import State, World

EXAMPLES = Path(__file__).parent.parent / "examples"


def same_state(a: World, b: World) -> None:
    assert a.frame == b.frame and a.seed == b.seed
    for name in State._fields:
        assert np.array_equal(getattr(a.state, name), getattr(b.state, name)), name
    assert np.array_equal(a.awake, b.awake)


@pytest.mark.parametrize("example, first, then", [("demolition", 40, 60), ("fountain", 25, 30), ("boiling_pool", 30, 30), ("timeline", 50, 100)])
def test_resuming_a_snapshot_equals_an_uninterrupted_run(example, first, then, tmp_path):
    path = EXAMPLES / f"{example}.toml"
    straight = load_world(path).world
    for _ in range(first + then):
        straight.step()
    before = load_world(path).world
    for _ in range(first):
        before.step()
    save_snapshot(before, tmp_path / "s.npz")
    resumed = load_world(path, seed=12345).world  # the snapshot's seed wins over the world's
    load_snapshot(resumed, tmp_path / "s.npz")
    assert resumed.frame == first
    for _ in range(then):
        resumed.step()
    same_state(resumed, straight)


def test_elements_are_mapped_by_name_across_other_mods(tmp_path):
    small = load_ruleset(["sand", "water"])
    world = World(small, 16, 16, seed=3)
    world.paint(np.arange(16)[None, :].repeat(16, 0) < 8, small.index("water"))
    world.paint(np.arange(16)[:, None].repeat(16, 1) < 4, small.index("sand"))
    for _ in range(3):
        world.step()
    save_snapshot(world, tmp_path / "s.npz")
    big = load_ruleset()  # every mod: the element numbers differ
    assert big.index("water") != small.index("water") or big.index("sand") != small.index("sand")
    other = World(big, 16, 16)
    assert load_snapshot(other, tmp_path / "s.npz") == []
    names = lambda w: np.array([e.id for e in w.ruleset.elements])[w.cells]  # noqa: E731
    assert (names(other) == names(world)).all()
    assert np.allclose(other.temperature(), world.temperature())
    no_water = World(load_ruleset(["sand"]), 16, 16)
    with pytest.raises(ProblemsError, match=r"s\.npz: holds water:water, which no loaded mod defines"):
        load_snapshot(no_water, tmp_path / "s.npz")


def test_a_snapshot_with_a_narrower_carry_array_still_loads(tmp_path):
    """Snapshots written while ``carry`` was uint8 (at most 256 elements) load into today's uint16; their flying cargo lands the same."""
    ruleset = load_ruleset(["sand"])
    world = World(ruleset, 16, 16, seed=5)
    ys, xs = np.full(4, 2), np.arange(4, 8)
    world.paint_cells(ys, xs, ruleset.index("sand"))
    assert world.launch(ys, xs, 1.5, -0.5) == 4
    save_snapshot(world, tmp_path / "now.npz")
    with np.load(tmp_path / "now.npz") as data:
        arrays = {key: data[key] for key in data.files}
    arrays["carry"] = arrays["carry"].astype(np.uint8)
    np.savez_compressed(tmp_path / "old.npz", **arrays)
    old = World(ruleset, 16, 16)
    assert load_snapshot(old, tmp_path / "old.npz") == []
    assert old.state.carry.dtype == np.uint16 and (old.state.carry == world.state.carry).all()
    for _ in range(30):
        world.step()
        old.step()
    same_state(old, world)


def test_cli_continues_from_a_snapshot_to_the_same_last_frame(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    world = str(EXAMPLES / "demolition.toml")
    assert invoke("render", world, "--frames", "70", "-o", "all.gif", "--still", "all.png", "-q").exit_code == 0
    result = invoke("render", world, "--frames", "30", "-o", "a.gif", "--save-snapshot", "mid.npz")
    assert result.exit_code == 0 and result.stdout.rstrip().endswith(", snapshot mid.npz")
    result = invoke("render", world, "--frames", "40", "-o", "b.gif", "--from-snapshot", "mid.npz", "--still", "b.png", "-q")
    assert result.exit_code == 0, result.output
    with Image.open("all.png") as full, Image.open("b.png") as resumed:
        assert np.array_equal(np.asarray(full), np.asarray(resumed))


def test_bad_snapshots_are_named_and_nothing_is_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    world = str(EXAMPLES / "hourglass.toml")
    Path("text.npz").write_text("not a snapshot")
    small = World(load_ruleset(["sand"]), 8, 8)
    save_snapshot(small, Path("small.npz"))
    cases = {
        "text.npz": "text.npz: not a sandmod snapshot (write one with 'sandmod render --save-snapshot FILE.npz')",
        "gone.npz": "gone.npz: no such snapshot file",
        "small.npz": "small.npz: made for a 8x8 world; this world is 100x124",
    }
    for name, message in cases.items():
        result = invoke("render", world, "--from-snapshot", name, "-o", "out.gif")
        assert result.exit_code == 2 and result.stderr.strip() == message
    assert not Path("out.gif").exists()
