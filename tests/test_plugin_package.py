"""The example plugin package: found through its entry point, blocked by SANDMOD_DISABLE_PLUGINS; every hook documented."""

from __future__ import annotations

import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import installed_as_pip_would
from sandmod import hooks

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "examples" / "plugin-package"

PROBE = """
from sandmod.world.loading import load_registry
registry = load_registry()
print(sorted(registry.recorders), sorted(e.plugin for e in registry.mod_dirs))
"""


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The example package installed into a fresh folder, as pip would."""
    return installed_as_pip_would(PACKAGE, tmp_path_factory.mktemp("site"))


def test_every_folder_of_the_package_is_named_in_its_packages():
    """A folder left out of ``packages`` makes pip print a long warning, and its files may be left out."""
    import tomllib

    listed = set(tomllib.loads((PACKAGE / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    folders = {
        ".".join(d.relative_to(PACKAGE).parts)
        for d in (PACKAGE / "sandmod_ascii").rglob("*")
        if d.is_dir() and d.name != "__pycache__"
    } | {"sandmod_ascii"}
    assert folders == listed


def run(site: Path, *args: str, disable: str = "", cwd: Path | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(site), "SANDMOD_DISABLE_PLUGINS": disable}
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=300)


def test_the_installed_package_is_loaded_and_can_be_blocked(site):
    loaded = run(site, "-c", PROBE)
    assert loaded.returncode == 0, loaded.stderr
    assert loaded.stdout.strip() == "['apng', 'ascii', 'gif', 'png-frames', 'webp'] ['ascii', 'sandmod.plugins.toml_mods']"
    blocked = run(site, "-c", PROBE, disable="ascii")
    assert blocked.stdout.strip() == "['apng', 'gif', 'png-frames', 'webp'] ['sandmod.plugins.toml_mods']"


def test_its_mod_tests_pass_and_its_recorder_writes(site, tmp_path):
    tested = run(site, "-m", "sandmod", "test", "neon")
    assert tested.returncode == 0, tested.stdout + tested.stderr
    assert tested.stdout.splitlines()[0] == "neon:rises_to_the_ceiling ... ok"
    world = ROOT / "examples" / "piles.toml"
    rendered = run(site, "-m", "sandmod", "render", str(world), "-o", "piles.txt", "--frames", "4", "--every", "2", "-q", cwd=tmp_path)
    assert rendered.returncode == 0, rendered.stderr
    images = (tmp_path / "piles.txt").read_text().split("\n\n")
    assert len([i for i in images if i.strip()]) == 3  # frames 0, 2 and 4


def test_every_hook_has_a_section_in_the_plugin_docs():
    documented = set(re.findall(r"^## (\w+)$", (ROOT / "docs" / "how-to" / "plugins.md").read_text(), re.MULTILINE))
    specs = {name for name, f in inspect.getmembers(hooks, inspect.isfunction) if hasattr(f, "sandmod_spec")}
    assert specs and specs <= documented, f"undocumented hooks: {sorted(specs - documented)}"
