"""The tutorial runs as written: in a fresh folder, its files are written and its commands run, in order."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parent.parent
TUTORIAL = (ROOT / "docs" / "tutorial.md").read_text(encoding="utf-8")
BLOCK = re.compile(r'```(\w+)(?: title="([^"]+)")?\n(.*?)```', re.S)


def _run(command: str, folder: Path) -> subprocess.CompletedProcess:
    """A command as a user types it, with this environment's sandmod and python first on the PATH."""
    path = f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"
    return subprocess.run(command, shell=True, cwd=folder, env={**os.environ, "PATH": path}, capture_output=True, text=True)


def test_the_tutorial_runs_as_written(tmp_path):
    outputs = {}
    for language, title, body in BLOCK.findall(TUTORIAL):
        if title:  # a file the reader writes
            (tmp_path / title).parent.mkdir(parents=True, exist_ok=True)
            (tmp_path / title).write_text(body, encoding="utf-8")
        elif language == "bash":
            for line in body.splitlines():
                command = line.split(" #")[0].strip()
                if not command or command.startswith("pip install"):  # installed already: it is what the tests run in
                    continue
                done = _run(command, tmp_path)
                assert done.returncode == 0, f"{command}\n{done.stdout}\n{done.stderr}"
                outputs[command] = done.stdout + done.stderr
    _prints_what_the_page_says(outputs, tmp_path)


def _prints_what_the_page_says(outputs: dict[str, str], folder: Path) -> None:
    assert "snow:snow" in outputs["sandmod list"]
    assert outputs["sandmod test snow"].splitlines()[:2] == ["snow:stays_frozen ... ok", "snow:melts_in_warm_water ... ok"]
    shown = next(body for language, _, body in BLOCK.findall(TUTORIAL) if body.startswith("wrote snowfall.gif"))
    assert outputs["sandmod render snowfall.toml"].split(" in ")[0] == shown.split(" in ")[0]
    assert (folder / "snowfall.gif").stat().st_size > 0


@pytest.mark.slow
def test_the_tutorial_runs_word_for_word_in_a_fresh_environment(tmp_path):
    """As a new user runs it: a fresh virtual environment, sandmod installed from a copy of the
    checkout (not editable), and every command of the page, pip's included, in a folder of its own."""
    checkout, work, venv = tmp_path / "checkout", tmp_path / "work", tmp_path / "venv"
    shutil.copytree(ROOT, checkout, ignore=shutil.ignore_patterns(".git", ".venv", "venv", "build", "site", "*.egg-info", "__pycache__", ".*_cache", ".hypothesis"))
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    work.mkdir()
    scripts = venv / ("Scripts" if os.name == "nt" else "bin")
    env = {**{k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}, "VIRTUAL_ENV": str(venv),
           "PATH": f"{scripts}{os.pathsep}{os.environ.get('PATH', '')}"}
    outputs = {}
    for language, title, body in BLOCK.findall(TUTORIAL):
        if title:
            (work / title).parent.mkdir(parents=True, exist_ok=True)
            (work / title).write_text(body, encoding="utf-8")
        elif language == "bash":
            for line in body.splitlines():
                command = line.split(" #")[0].strip()
                if command:
                    folder = checkout if command == "pip install ." else work  # the page: from a checkout, then a folder of your own
                    done = subprocess.run(command, shell=True, cwd=folder, env=env, capture_output=True, text=True)
                    assert done.returncode == 0, f"{command}\n{done.stdout}\n{done.stderr}"
                    outputs[command] = done.stdout + done.stderr
    assert str(venv) in subprocess.run(["python", "-c", "import sandmod; print(sandmod.__file__)"], env=env, capture_output=True, text=True).stdout
    assert "2 passed" in outputs["python -m pytest mods/ -q"]
    _prints_what_the_page_says(outputs, work)


def test_the_tutorials_example_of_a_mistake_is_what_validate_says(tmp_path):
    mod = next(body for _, title, body in BLOCK.findall(TUTORIAL) if title == "mods/snow.toml")
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "snow.toml").write_text(mod.replace("density = 300 ", "density = -300"), encoding="utf-8")
    done = _run("sandmod validate mods/", tmp_path)
    shown = next(body for language, _, body in BLOCK.findall(TUTORIAL) if body.startswith("mods/snow.toml:"))
    assert done.returncode == 2 and done.stdout + done.stderr == shown


def test_every_image_in_the_docs_exists_and_says_how_it_was_made():
    for page in [ROOT / "README.md", *(ROOT / "docs").rglob("*.md")]:
        text = page.read_text(encoding="utf-8")
        for image in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text):
            assert (page.parent / image).is_file(), f"{page.name}: {image}"
            made = [line for line in text.splitlines() if ("sandmod " in line or "python tools/" in line) and Path(image).stem in line]
            assert made, f"{page.name}: no command says how {image} was made"


def test_every_world_and_mod_in_the_how_tos_that_is_whole_validates():
    """A how-to's TOML block with a [world] or [mod] table is a whole file: it must be a valid one."""
    from pydantic import ValidationError

    from sandmod.formats.modspec import ModFile
    from sandmod.formats.tomlsource import TomlSource
    from sandmod.formats.worldspec import WorldFile

    checked = 0
    for page in (ROOT / "docs" / "how-to").glob("*.md"):
        for language, _, body in BLOCK.findall(page.read_text(encoding="utf-8")):
            if language != "toml" or not ("[world]" in body or "[mod]" in body):
                continue
            data = TomlSource.parse(body, page.name).data
            try:
                (WorldFile if "world" in data else ModFile).model_validate(data)
            except ValidationError as error:
                raise AssertionError(f"{page.name}: {error}") from None
            checked += 1
    assert checked >= 3


def test_the_sweep_in_the_batch_how_to_is_the_one_in_the_repository():
    from sandmod.formats.tomlsource import TomlSource

    page = (ROOT / "docs" / "how-to" / "batch.md").read_text(encoding="utf-8")
    shown = next(body for language, _, body in BLOCK.findall(page) if language == "toml" and "[sweep]" in body)
    sweep = ROOT / "docs" / "sweeps" / "friction.toml"
    assert TomlSource.parse(shown, "batch.md").data == TomlSource.read(sweep).data
