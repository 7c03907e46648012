"""The public Python API: what ``import sandmod`` and ``sandmod.api`` give."""

from __future__ import annotations

import io
import subprocess
import sys
import types
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


def _public_namespace() -> dict:
    """What a reader of the reference can import: sandmod's and sandmod.api's names, and the
    standard library's and numpy's that signatures use."""
    from typing import Any, Callable, Iterable, Mapping, Sequence

    from sandmod import api

    public = {name: getattr(sandmod, name) for name in sandmod.__all__} | {name: getattr(api, name) for name in api.__all__}
    return {"np": np, "Path": Path, "Any": Any, "Callable": Callable, "Iterable": Iterable, "Mapping": Mapping, "Sequence": Sequence, **public}


def _signed() -> list[tuple[str, object]]:
    """Every public function, method, constructor and hook spec, by name."""
    import inspect

    from pydantic import BaseModel

    from sandmod import api, hooks

    found = [(name, getattr(hooks, name)) for name, value in vars(hooks).items() if hasattr(value, "sandmod_spec")]
    for module in (sandmod, api):
        for name in module.__all__:
            thing = getattr(module, name)
            if inspect.isfunction(thing):
                found.append((name, thing))
            elif inspect.isclass(thing) and thing.__module__.startswith("sandmod"):
                made_by_sandmod = name in ("LoadedWorld", "Ruleset") or issubclass(thing, (BaseModel, tuple))  # no constructor of the caller's
                methods = {k: v for k, v in vars(thing).items() if inspect.isfunction(v) and (not k.startswith("_") or k == "__init__" and not made_by_sandmod)}
                found += [(f"{name}.{k}", v) for k, v in methods.items()]
    return found


def test_every_type_a_public_signature_or_hook_names_is_importable_from_sandmod_or_sandmod_api():
    import typing

    namespace = _public_namespace()
    signed = _signed()
    assert len(signed) >= 40 and "register_metrics" in dict(signed)
    for name, function in signed:
        shown = {k: v for k, v in function.__annotations__.items() if k not in ("salt", "registry")}  # the engine's and the CLI's, not shown
        try:
            typing.get_type_hints(types.SimpleNamespace(__annotations__=shown), globalns=namespace, localns=namespace)
        except NameError as missing:
            raise AssertionError(f"{name}: {missing}, not importable from sandmod or sandmod.api") from None
