"""Shared helpers: worlds drawn as text, rulesets from extra mod files."""

from __future__ import annotations

import subprocess
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from sandmod.rules.compiler import Ruleset
from sandmod.world.loading import load_registry, load_ruleset
from sandmod.world.world import World

pytest_plugins = ["pytester"]  # to test sandmod's own pytest plugin

LEGEND = {
    ".": "empty",
    "#": "stone",
    "S": "sand",
    "W": "water",
    "L": "lava",
    "A": "acid",
    "T": "titanium",
    "G": "steam",
    "I": "ice",
    "w": "wood",
    "O": "oil",
    "P": "gunpowder",
    "X": "tnt",
    "F": "fire",
    "K": "smoke",
    "g": "glass",
    "a": "ash",
    "B": "basalt",
}


@pytest.fixture(scope="session")
def registry():
    return load_registry()


@pytest.fixture(scope="session")
def ruleset(registry) -> Ruleset:
    """Every bundled mod."""
    return load_ruleset(registry=registry)


def write_mods(folder: Path, files: dict[str, str]) -> Path:
    """Write mod files (dedented) into ``folder``; returns the folder."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    return folder


def walls_mod(name: str, count: int, more: str = "") -> str:
    """A mod of ``count`` static elements (``e000`` on), each its own colour, and ``more`` (TOML)."""
    walls = "".join(f'[elements.e{k:03d}]\narchetype = "static"\ncolor = "#{(k * 7919) % 0xFFFFFF:06x}"\nshade = 0.2\n\n' for k in range(count))
    return f'[mod]\nname = "{name}"\n\n{more}\n{walls}'


#: A mod whose seed grows a stalk upwards (a reaction on one side); with SEED_ROOTS, roots below and beside it too.
SEED = """
[mod]
name = "g"
[elements.seed]
archetype = "static"
color = "#30a030"
[elements.root]
archetype = "static"
color = "#805020"
[[reactions]]
a = "seed"
b = "empty"
b_becomes = "seed"
where = ["above"]
chance = 1
"""
SEED_ROOTS = SEED + '[[reactions]]\na = "seed"\nb = "empty"\nb_becomes = "root"\nwhere = ["below", "sides"]\nchance = 1\n'


def packaged_files(package: Path) -> list[Path]:
    """What setuptools puts in the wheel of the project in ``package``: each listed package's
    modules, and its package data."""
    import tomllib

    setuptools = tomllib.loads((package / "pyproject.toml").read_text())["tool"]["setuptools"]
    files = []
    for name in setuptools["packages"]:
        folder = package.joinpath(*name.split("."))
        files += folder.glob("*.py")
        for pattern in setuptools.get("package-data", {}).get(name, []):
            files += folder.glob(pattern)
    return files


def installed_as_pip_would(package: Path, folder: Path) -> Path:
    """The project in ``package`` installed into ``folder`` (to put on PYTHONPATH): its code and a
    dist-info with its entry points, which is what pip would write, without the network or a build."""
    import shutil
    import tomllib

    for source in packaged_files(package):
        target = folder / source.relative_to(package)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(source, target)
    project = tomllib.loads((package / "pyproject.toml").read_text())["project"]
    info = folder / f"{project['name'].replace('-', '_')}-{project['version']}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {project['name']}\nVersion: {project['version']}\n")
    groups = project["entry-points"]
    (info / "entry_points.txt").write_text(
        "".join(f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in points.items()) for group, points in groups.items())
    )
    return folder


def make_world(ruleset: Ruleset, rows: list[str], legend: dict[str, str] = LEGEND, seed: int = 0) -> World:
    """A world painted from text rows, one character per cell."""
    world = World(ruleset, len(rows[0]), len(rows), seed)
    chars = np.array([list(row) for row in rows])
    for char, name in legend.items():
        if name != "empty" and (chars == char).any():
            world.paint(chars == char, ruleset.index(name))
    return world


def as_rows(world: World, legend: dict[str, str] = LEGEND) -> list[str]:
    """The world as text rows (the inverse of :func:`make_world`)."""
    char_of = {world.ruleset.index(name): char for char, name in legend.items()}
    return ["".join(char_of[int(e)] for e in row) for row in world.cells]


def run(world: World, frames: int) -> World:
    for _ in range(frames):
        world.step()
    return world


def wait_for(ready, child: subprocess.Popen, timeout: float = 600) -> None:
    """Poll until ``ready()`` while ``child`` runs, so that a test signals the child once it has got
    there, however busy the machine; fail if the child ends, or ``timeout`` passes, first."""
    deadline = time.monotonic() + timeout
    while not ready():
        assert child.poll() is None and time.monotonic() < deadline, f"never ready: exit {child.poll()}"
        time.sleep(0.02)


def invoke(*args: str):
    """Run the ``sandmod`` command line in this process; a crash is a test error, not an exit code."""
    from click.testing import CliRunner

    from sandmod.tools.cli import cli

    return CliRunner().invoke(cli, list(args), catch_exceptions=False)
