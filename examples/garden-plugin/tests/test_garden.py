"""The garden plugin, installed: its behaviours are registered, grow vines, and work in render, play and batch."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from sandmod.tools.cli import cli
from sandmod.world.loading import load_registry, load_world

HERE = Path(__file__).resolve().parent.parent
GARDEN = HERE / "garden.toml"


def test_the_plugin_gives_two_behaviours():
    behaviours = load_registry().behaviours
    assert {name: b.plugin for name, b in behaviours.items() if name.startswith("garden:")} == {"garden:grow": "garden", "garden:sprout": "garden"}
    assert behaviours["garden:grow"].value.args == ("stem", "flower", "speed", "lean", "fork", "bloom")


def test_seeds_on_dirt_grow_vines_and_seeds_on_stone_do_not():
    world = load_world(GARDEN).world
    world.run(300)
    counts = world.counts()
    assert counts["garden:vine"] > 200 and counts["garden:flower"] > 5
    ledge = world.ruleset.index("garden:seed") == world.cells[49, 100:140]
    assert ledge.sum() >= 1  # seeds that fell on the stone ledge
    # Every vine cell grew from below: the lowest vine of each column stands on dirt, vine, seed or flower, or leans on one.
    vine = world.ruleset.index("garden:vine")
    assert (world.cells[87] == vine).sum() > 0  # vines start just above the dirt


def digest(world) -> str:
    h = hashlib.sha256()
    for array in world.state:
        h.update(array.tobytes())
    return h.hexdigest()


def test_the_garden_grows_the_same_every_time():
    runs = []
    for _ in range(2):
        world = load_world(GARDEN).world
        world.run(200)
        runs.append(digest(world))
    assert runs[0] == runs[1]


def test_render_and_batch(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    rendered = runner.invoke(cli, ["render", str(GARDEN), "-o", "garden.gif", "--frames", "120", "-q"])
    assert rendered.exit_code == 0, rendered.output
    assert Path("garden.gif").stat().st_size > 1000
    batch = runner.invoke(cli, ["batch", str(HERE / "garden_sweep.toml"), "-o", "runs", "-j", "1"])
    assert batch.exit_code == 0, batch.output
    rows = Path("runs/results.csv").read_text().splitlines()
    header = rows[0].split(",")
    column = header.index("count.garden:vine@300")
    assert len(rows) == 5 and all(float(row.split(",")[column]) > 100 for row in rows[1:])


def test_play(tmp_path, monkeypatch):
    pygame = pytest.importorskip("pygame")
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.chdir(tmp_path)
    from sandmod.jobs.play import Play
    from sandmod.jobs.session import Session

    play = Play(Session.open(GARDEN), scale=1, fixed_steps=1)
    for _ in range(150):
        play._one_frame()
    assert play.session.world.counts()["garden:vine"] > 50
    pygame.quit()
