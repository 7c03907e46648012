"""The public Python API: what ``import sandmod`` and ``sandmod.api`` give."""

from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import sandmod

EXAMPLES = Path(__file__).parent.parent / "examples"


def test_importing_sandmod_loads_nothing_heavy():
    code = "import sys, sandmod; print(sorted(m for m in ('numba', 'numpy', 'pydantic') if m in sys.modules))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
    assert set(sandmod.__all__) >= {"load_world", "load_ruleset", "World", "Ruleset", "Problem", "ProblemsError"}


def test_a_world_from_python_paints_steps_counts_and_shows_itself():
    world = sandmod.load_world(EXAMPLES / "hourglass.toml").world
    before = world.counts()
    painted = world.paint_shape(shape="circle", element="water", x=50, y=20, radius=3)
    assert painted > 0 and world.counts()["water:water"] == before["water:water"] + painted
    world.run(5)
    assert world.frame == 5 and world.temperature().shape == (world.height, world.width)
    image = Image.open(io.BytesIO(world._repr_png_()))
    assert image.size[0] % world.width == 0 and image.size[0] // world.width == image.size[1] // world.height >= 1


def test_paint_shape_takes_a_table_and_names_its_mistakes():
    world = sandmod.load_world(EXAMPLES / "hourglass.toml").world
    assert world.paint_shape({"shape": "rect", "element": "sand", "x": 0, "y": 0, "width": 2, "height": 2}) == 4
    with pytest.raises(sandmod.ProblemsError) as caught:
        world.paint_shape(shape="rect", element="sand", x=0, y=0, width=0, height=2)
    assert str(caught.value) == "paint_shape: shape.width: must be >= 1 (got 0)"
    with pytest.raises(sandmod.ProblemsError) as caught:
        world.paint_shape(shape="circle", element="sandd", x=3, y=3, radius=2)
    assert "unknown element 'sandd'" in str(caught.value)


def test_a_snapshot_saved_from_python_loads_back_into_the_same_frames(tmp_path):
    first = sandmod.load_world(EXAMPLES / "hourglass.toml").world
    first.run(20)
    first.save_snapshot(tmp_path / "s.npz")
    second = sandmod.load_world(EXAMPLES / "hourglass.toml").world
    assert second.load_snapshot(tmp_path / "s.npz") == []
    first.run(10)
    second.run(10)
    assert np.array_equal(first.cells, second.cells) and second.frame == 30


def test_the_plugin_api_names_what_it_exports():
    from sandmod import api

    assert all(getattr(api, name) is not None for name in api.__all__)
    assert api.RecorderSpec.__module__ == "sandmod.formats.recording"
