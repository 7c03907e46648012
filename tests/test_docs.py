"""The docs are true word for word: the tutorial, each how-to and each gallery page run as written
(their files written, their commands and scripts run, in order) and print what they say."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from pages import BLOCK, prints_what_it_shows, refreshed, steps

ROOT = Path(__file__).parent.parent
TUTORIAL = (ROOT / "docs" / "tutorial.md").read_text(encoding="utf-8")
HOW_TOS = sorted((ROOT / "docs" / "how-to").glob("*.md"))
GALLERY = sorted(page for page in (ROOT / "docs" / "gallery").glob("*.md") if page.stem != "index")

#: Commands a page shows that a test cannot run, and why.
NOT_RUN = {
    "sandmod play": "opens a window and waits for its player",
    "sandmod play examples/forest_fire.toml --scale 3": "opens a window and waits for its player",
    "sandmod batch docs/sweeps/friction.toml -o friction-cluster --executor dask --scheduler tcp://scheduler:8786": "needs a Dask cluster",
}


def _copy_checkout(to: Path) -> Path:
    shutil.copytree(ROOT, to, ignore=shutil.ignore_patterns(".git", ".venv", "venv", "build", "site", "*.egg-info", "__pycache__", ".*_cache", ".hypothesis"))
    return to


def follow(page: Path | str, folder: Path, env: dict[str, str], checkout: Path | None = None, installs: bool = True) -> dict[str, str]:
    """Take a page's steps in ``folder``: write its files, run its commands and scripts with
    ``env``, each of which must succeed and print what the page shows. ``pip install .``-style
    commands run in ``checkout`` (the page says "from a checkout"), or are left out where not
    ``installs``. Returns what each command printed."""
    outputs: dict[str, str] = {}
    for number, step in enumerate(steps(page)):
        if step.kind == "file":
            (folder / step.path).parent.mkdir(parents=True, exist_ok=True)
            (folder / step.path).write_text(step.text, encoding="utf-8")
        elif step.kind == "prints":
            assert prints_what_it_shows(step.text, outputs[step.path]), f"{step.path} printed\n{outputs[step.path]}\nnot\n{step.text}"
        elif step.kind == "command" and step.text not in NOT_RUN and (installs or not step.text.startswith("pip install")):
            where = checkout if checkout and re.fullmatch(r'pip install "?\.(\[\w+\])?"?', step.text) else folder
            outputs[step.text] = _run(step.text, where, env)
        elif step.kind == "script":
            script = folder.parent / f"{folder.name}-script-{number}.py"
            script.write_text(step.text, encoding="utf-8")
            outputs[step.text] = _run(f'python "{script}"', folder, env)
    return outputs


def _run(command: str, folder: Path, env: dict[str, str]) -> str:
    done = subprocess.run(command, shell=True, cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert done.returncode == 0, f"{command} (in {folder}) exited {done.returncode}:\n{done.stdout}"
    return done.stdout


def _this_environment() -> dict[str, str]:
    """This environment's sandmod and python first on the PATH."""
    return {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}


def test_the_tutorial_runs_as_written(tmp_path):
    outputs = follow(ROOT / "docs" / "tutorial.md", tmp_path, _this_environment(), installs=False)
    _prints_what_the_tutorial_says(outputs, tmp_path)
    shown = re.search(r"\*`(sandmod render snowfall.toml -o snowfall.webp)`", TUTORIAL).group(1)
    _run(shown, tmp_path, _this_environment())
    assert _frames(tmp_path / "snowfall.webp") == _frames(ROOT / "docs" / "images" / "snowfall.webp"), f"docs/images/snowfall.webp is not what {shown} draws now"


def _frames(path: Path) -> list[bytes]:
    """An image's frames as RGB pixels."""
    from PIL import Image, ImageSequence

    with Image.open(path) as image:
        return [frame.convert("RGB").tobytes() for frame in ImageSequence.Iterator(image)]


def _prints_what_the_tutorial_says(outputs: dict[str, str], folder: Path) -> None:
    assert "snow:snow" in outputs["sandmod list"]
    assert "2 passed" in outputs["python -m pytest mods/ -q"]
    assert (folder / "snowfall.gif").stat().st_size > 0


def test_the_pages_show_what_commands_print_and_name_what_is_not_run():
    pages = [ROOT / "docs" / "tutorial.md", *HOW_TOS]
    shown = [step for page in pages for step in steps(page)]
    assert sum(step.kind == "prints" for step in shown) >= 4
    assert sum(step.kind == "script" for step in shown) >= 1
    commands = {step.text for step in shown if step.kind == "command"}
    assert set(NOT_RUN) <= commands, set(NOT_RUN) - commands


def test_a_pages_figures_are_made_again_from_what_its_commands_print():
    """What tools/dev/pages.py writes: each shown line becomes the printed one, figures and all."""
    page = "Run it:\n\n```bash\nsandmod render w.toml\n```\n\n```text\nwrote w.gif in 0.4 s (1.00 MB)\n```\n\nThen more.\n"
    printed = {"sandmod render w.toml": "compiling...\nwrote w.gif in 1.3 s (1.02 MB)\n"}
    assert refreshed(page, printed) == page.replace("0.4 s (1.00", "1.3 s (1.02")
    assert refreshed(page, {}) == page  # a command not run: left as it is
    with pytest.raises(ValueError, match="printed"):
        refreshed(page, {"sandmod render w.toml": "wrote x.gif in 1.3 s (1.02 MB)\n"})  # more than figures differ


def test_every_piece_of_python_on_a_page_is_python():
    """The pieces of a larger file (a plugin's hooks) are not run, but each must at least compile
    (the Python reference's signatures are not statements)."""
    for page in [ROOT / "README.md", *(ROOT / "docs").glob("*.md"), *HOW_TOS]:
        for language, _, body in BLOCK.findall(page.read_text(encoding="utf-8")):
            if language == "python":
                compile(body, str(page), "exec")


@dataclass
class Fresh:
    """A fresh virtual environment with sandmod installed (not editable) from a copy of the checkout."""

    checkout: Path
    env: dict[str, str]


@pytest.fixture(scope="module")
def fresh(tmp_path_factory) -> Fresh:
    base = tmp_path_factory.mktemp("fresh")
    checkout, venv = _copy_checkout(base / "checkout"), base / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    scripts = venv / ("Scripts" if os.name == "nt" else "bin")
    env = {**{k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "NUMBA_CACHE_DIR")}, "VIRTUAL_ENV": str(venv),
           "PATH": f"{scripts}{os.pathsep}{os.environ.get('PATH', '')}",
           "XDG_CACHE_HOME": str(base / "cache"),  # compiled kernels of a copy that is gone after the tests: not in the user's cache
           "PIP_CACHE_DIR": os.environ.get("PIP_CACHE_DIR") or str(Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "pip")}
    _run("pip install -q .", checkout, env)
    assert str(venv) in _run('python -c "import sandmod; print(sandmod.__file__)"', base, env)
    return Fresh(checkout, env)


@pytest.mark.slow
def test_the_tutorial_runs_word_for_word_in_a_fresh_environment(fresh, tmp_path):
    """As a new user runs it: every command of the page, pip's included, in a folder of its own."""
    outputs = follow(ROOT / "docs" / "tutorial.md", tmp_path, fresh.env, checkout=fresh.checkout)
    _prints_what_the_tutorial_says(outputs, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("page", [page for page in HOW_TOS + GALLERY if any(step.kind != "file" for step in steps(page))],
                         ids=lambda page: f"{page.parent.name}/{page.stem}")
def test_each_how_to_and_gallery_page_runs_word_for_word_in_a_fresh_environment(fresh, page, tmp_path):
    """A page's commands run in a checkout of its own, as the how-tos and the gallery say."""
    follow(page, _copy_checkout(tmp_path / "checkout"), fresh.env, checkout=None)


def test_the_tutorials_example_of_a_mistake_is_what_validate_says(tmp_path):
    mod = next(body for _, title, body in BLOCK.findall(TUTORIAL) if title == "mods/snow.toml")
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "snow.toml").write_text(mod.replace("density = 300 ", "density = -300"), encoding="utf-8")
    done = subprocess.run("sandmod validate mods/", shell=True, cwd=tmp_path, env=_this_environment(), capture_output=True, text=True)
    shown = next(body for language, _, body in BLOCK.findall(TUTORIAL) if body.startswith("mods/snow.toml:"))
    assert done.returncode == 2 and done.stdout + done.stderr == shown


def test_every_image_in_the_docs_exists_and_says_how_it_was_made():
    for page in [ROOT / "README.md", *(ROOT / "docs").rglob("*.md")]:
        text = page.read_text(encoding="utf-8")
        for image in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text):
            assert (page.parent / image).is_file(), f"{page.name}: {image}"
            made = [line for line in text.splitlines() if ("sandmod " in line or "python tools/" in line) and Path(image).stem in line]
            assert made, f"{page.name}: no command says how {image} was made"


FIGURE = re.compile(r"sandmod (?:render|palette)[^`\n]*-o (docs/images/[a-z_]+\.(?:webp|png))")


@pytest.mark.slow  # renders every figure again
def test_every_figure_of_a_world_is_what_its_command_makes_now(tmp_path):
    """The pages' figures drawn by sandmod (the example worlds' animations, the palette) are current:
    each command, run again into another folder, draws the same pixels, frame for frame."""
    commands = {match.group(0): match.group(1) for page in [ROOT / "README.md", *(ROOT / "docs").rglob("*.md")]
                for match in FIGURE.finditer(page.read_text(encoding="utf-8"))}
    assert len(set(commands.values())) >= 12
    for command, figure in commands.items():
        _run(command.replace("docs/images/", f"{tmp_path}/") + " -q" * ("render" in command), ROOT, _this_environment())
        assert _frames(ROOT / figure) == _frames(tmp_path / Path(figure).name), f"{figure} is not what the code draws now: run {command}"


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


@pytest.mark.slow
def test_a_fresh_install_keeps_its_compiled_kernels_in_the_users_cache_not_in_the_package(fresh, tmp_path):
    """Files pip did not install would outlive an uninstall (and shadow a later editable install)."""
    step = 'import sandmod; sandmod.load_world("examples/hourglass.toml").world.step()'
    _run(f"python -c '{step}'", fresh.checkout, fresh.env)
    cached = list((Path(fresh.env["XDG_CACHE_HOME"]) / "sandmod" / "numba").rglob("*.nbi"))
    assert any("kernel.step" in path.name for path in cached)
    package = Path(_run('python -c "import sandmod; print(sandmod.__file__)"', tmp_path, fresh.env).strip()).parent
    assert package.is_relative_to(fresh.env["VIRTUAL_ENV"]) and not list(package.rglob("*.nbi"))
