"""The example plugin with behaviours, installed as pip would: its mod tests, its own tests (render,
play, batch), its entry point blocked; and the kernel loaded from its cache while it runs."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import installed_as_pip_would

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "examples" / "garden-plugin"


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The package installed into a fresh folder, as pip would."""
    return installed_as_pip_would(PACKAGE, tmp_path_factory.mktemp("site"))


def run(site: Path, *args: str, cwd: Path | None = None, **env: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(site), "SANDMOD_DISABLE_PLUGINS": "", **env}
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=600)


def test_its_mod_tests_pass_and_blocked_it_is_gone(site):
    tested = run(site, "-m", "sandmod", "test", "garden")
    assert tested.returncode == 0, tested.stdout + tested.stderr
    assert tested.stdout.splitlines()[:2] == ["garden:seed_sprouts_on_dirt ... ok", "garden:seed_on_stone_stays_a_seed ... ok"]
    blocked = run(site, "-m", "sandmod", "test", "garden", SANDMOD_DISABLE_PLUGINS="garden")
    assert blocked.returncode == 2 and "mod 'garden' was not found" in blocked.stderr


def test_its_own_tests_pass_render_play_and_batch(site, tmp_path):
    """The package's tests/ (render, play headless and batch among them), from a copy, with the package installed."""
    shutil.copytree(PACKAGE, tmp_path / "garden", ignore=shutil.ignore_patterns("__pycache__", "sandmod_garden"))
    done = run(site, "-m", "pytest", "-q", "-p", "no:cacheprovider", cwd=tmp_path / "garden")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "5 passed" in done.stdout


def test_render_loads_the_kernel_from_its_cache(site, tmp_path):
    """numba's cache log of a render of the garden: every kernel function loaded, none compiled or saved."""
    run(site, "-m", "sandmod", "render", str(PACKAGE / "garden.toml"), "-o", "warm.gif", "--frames", "2", "-q", cwd=tmp_path)
    done = run(site, "-m", "sandmod", "render", str(PACKAGE / "garden.toml"), "-o", "garden.gif", "--frames", "30", "-q", cwd=tmp_path, NUMBA_DEBUG_CACHE="1")
    assert done.returncode == 0, done.stderr
    log = [line for line in (done.stdout + done.stderr).splitlines() if line.startswith("[cache]")]
    kernel = [line for line in log if "/engine_" in line]  # numba files the engine's cache in a folder named after it
    assert any("kernel.step-" in line and "data loaded" in line for line in kernel)
    assert any("pass_" in line and "data loaded" in line for line in log)  # the garden's pass, from its own cache
    assert not [line for line in log if "saved" in line]
