"""Hundreds of elements from many packs (``tools/dev/packs.py``), loaded beside the bundled mods."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from kernels import same_cells
from packs import write_packs
from sandmod.engine.layout import MAX_ELEMENTS
from sandmod.errors import ProblemsError
from sandmod.jobs import benchmark
from sandmod.tools.cli import cli
from sandmod.world.loading import load_ruleset
from sandmod.world.world import World


@pytest.fixture(scope="module")
def packs(tmp_path_factory):
    """20 packs of 25 elements: 500, and the bundled mods' beside them."""
    folder = tmp_path_factory.mktemp("packs")
    write_packs(folder, 20, 25)
    return folder


def test_500_elements_from_20_packs_validate_with_the_bundled_mods(packs):
    result = CliRunner().invoke(cli, ["validate", "--mods", str(packs)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    bundled = len(load_ruleset().elements)
    assert f"({bundled + 500} elements" in result.output


def test_a_world_of_few_elements_steps_the_same_with_500_more_loaded(packs):
    """Loading elements a world does not use changes none of its cells (element numbers aside)."""
    worlds = []
    for ruleset in (load_ruleset(["sand", "water"]), load_ruleset(None, [packs])):
        world = World(ruleset, 96, 96, seed=3)
        benchmark.SCENES["mix"](world, ruleset)
        for _ in range(60):
            world.step()
        worlds.append(world)
    few, many = worlds
    assert len(many.ruleset.elements) > 500 and same_cells(few, many)


def test_a_hot_element_glows_with_500_more_loaded(packs):
    ruleset = load_ruleset(None, [packs])
    world = World(ruleset, 12, 3)
    bar = np.zeros((3, 12), bool)
    bar[1, 1:11] = True
    world.paint(bar, ruleset.index("stone"))
    world.set_temperature(bar, 1200.0)
    stone = ruleset.index("stone")
    assert (world.image()[bar] == ruleset.looks.glow[stone, 2]).all()  # (1200 - 525) // 300: yellow-white


def test_a_world_of_pack_elements_renders(packs, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "w.toml").write_text(
        '[world]\nwidth = 40\nheight = 30\n'
        '[[scene]]\nshape = "rect"\nelement = "pack03:p03e04"\nx = 5\ny = 2\nwidth = 10\nheight = 6\n'
        '[[scene]]\nshape = "rect"\nelement = "pack17:p17e01"\nx = 20\ny = 2\nwidth = 10\nheight = 6\n'
        '[[scene]]\nshape = "rect"\nelement = "stone"\nx = 0\ny = 28\nwidth = 40\nheight = 2\n'
        "[render]\nframes = 40\n"
    )
    result = CliRunner().invoke(cli, ["render", "w.toml", "--mods", str(packs)], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    assert (tmp_path / "w.gif").stat().st_size > 0


def test_the_most_elements_load_and_one_more_is_refused(tmp_path):
    bundled = len(load_ruleset().elements)
    packs = (MAX_ELEMENTS - bundled) // 99  # as many packs of 99 as fit beside the bundled mods (40 beside 118)
    write_packs(tmp_path, packs, 99)
    extra = MAX_ELEMENTS - bundled - packs * 99
    (tmp_path / "last.toml").write_text('[mod]\nname = "last"\n' + "".join(
        f'[elements.x{k}]\narchetype = "static"\ncolor = "#808080"\n' for k in range(extra)))
    ruleset = load_ruleset(None, [tmp_path])
    assert len(ruleset.elements) == MAX_ELEMENTS
    assert ruleset.tables.react_pair.nbytes + ruleset.tables.displace.nbytes == 3 * MAX_ELEMENTS**2  # 48 MB
    world = World(ruleset, 64, 64)
    world.paint(np.ones((64, 64), bool), ruleset.index("last:x0"))
    world.step()
    (tmp_path / "last.toml").write_text((tmp_path / "last.toml").read_text() + '[elements.one_more]\narchetype = "static"\ncolor = "#808080"\n')
    with pytest.raises(ProblemsError, match=f"{MAX_ELEMENTS + 1} elements loaded; at most {MAX_ELEMENTS}"):
        load_ruleset(None, [tmp_path])


def test_bench_loaded_times_a_scene_with_few_and_with_many_elements_on_the_same_cells():
    import bench

    result = CliRunner().invoke(bench.main, ["loaded", "--scene", "mix", "--size", "64", "--steps", "10", "--elements", "200", "--json"])
    assert result.exit_code == 0, result.output
    got = json.loads(result.output)
    bundled = len(load_ruleset().elements)
    few, packs = len(load_ruleset(["sand", "water"]).elements), max(1, -(-(200 - bundled) // 25))  # as bench.py counts them
    assert (got["few_elements"], got["elements"]) == (few, bundled + 25 * packs) and got["ratio"] > 0
