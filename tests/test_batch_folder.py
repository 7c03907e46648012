"""``sandmod batch``'s output folder: locked, never someone else's files overwritten, tampered runs
done again, interruptions that leave the table of the runs done and nothing half-written."""

from __future__ import annotations

import csv
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import wait_for
from sandmod.jobs import batch as batching
from test_batch import SWEEP, WORLD, invoke, same_files, table


@pytest.fixture
def sweep(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("worlds").mkdir()
    Path("worlds/heap.toml").write_text(WORLD)
    text = SWEEP.replace('worlds = ["*.toml"]', 'worlds = ["heap.toml"]').replace('format = "gif"', 'format = "none"')
    Path("worlds/sweep.toml").write_text(text)
    return Path("worlds/sweep.toml")


def test_a_second_batch_into_a_folder_in_use_is_refused_and_deletes_nothing(sweep):
    first = batching.OutputFolder(Path("out"))
    first.claim(resume=False, force=False)
    part = Path("out/runs/.abc.123.part")
    part.mkdir()
    try:
        result = invoke("batch", str(sweep), "-o", "out", "--resume")
        assert result.exit_code == 2 and "another batch is writing into this folder" in result.output
        assert part.is_dir()
    finally:
        first.release()


def test_a_folder_of_other_files_is_refused_unless_forced(sweep):
    Path("out").mkdir()
    Path("out/results.csv").write_text("mine\n")
    Path("out/notes.txt").write_text("mine\n")
    result = invoke("batch", str(sweep), "-o", "out")
    assert result.exit_code == 2 and "holds files sandmod batch did not write (notes.txt, results.csv)" in result.output
    assert Path("out/results.csv").read_text() == "mine\n" and sorted(os.listdir("out")) == ["notes.txt", "results.csv"]
    result = invoke("batch", str(sweep), "-o", "out", "--force")
    assert result.exit_code == 0 and Path("out/notes.txt").read_text() == "mine\n", result.output
    result = invoke("batch", str(sweep), "-o", "out", "--force")
    assert result.exit_code == 2 and "holds the runs of an earlier batch: --resume" in result.output


def test_tampered_run_folders_are_done_again_and_a_link_is_never_followed(sweep, tmp_path):
    assert invoke("batch", str(sweep), "-o", "whole").exit_code == 0
    shutil.copytree("whole", "out")
    runs = sorted(p for p in Path("out/runs").iterdir())
    (runs[0] / "last.png").unlink()
    (runs[1] / "last.png").write_bytes(b"\x89PNG\r\n\x1a\n broken")
    shutil.copy(runs[3] / "row.json", runs[2] / "row.json")
    outside = tmp_path / "outside"
    shutil.move(runs[4], outside)
    os.symlink(outside, runs[4])
    (runs[5] / "row.json").write_text("[1, 2]")
    before = sorted((p.name, p.read_bytes()) for p in outside.iterdir())
    result = invoke("batch", str(sweep), "-o", "out", "--resume")
    assert result.exit_code == 0 and "(3 done before)" in result.output, result.output
    assert table(Path("whole/results.csv")) == table(Path("out/results.csv"))
    assert same_files(Path("whole/runs"), Path("out/runs")) and not runs[4].is_symlink()
    assert sorted((p.name, p.read_bytes()) for p in outside.iterdir()) == before


@pytest.mark.parametrize("signum, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupted_batch_writes_the_table_of_its_runs_done_and_resumes(sweep, signum, status):
    assert invoke("batch", str(sweep), "-o", "whole", "-j", "1").exit_code == 0
    child = subprocess.Popen([sys.executable, "-m", "sandmod", "batch", str(sweep), "-o", "out", "-j", "2"],
                             stderr=subprocess.PIPE, text=True, start_new_session=True)
    runs = Path("out/runs")
    wait_for(lambda: runs.is_dir() and any(p.name[0] != "." for p in runs.iterdir()), child)
    os.killpg(child.pid, signum)  # as a terminal's Ctrl-C or a scheduler's SIGTERM reach the whole group
    _, err = child.communicate(timeout=60)
    assert child.returncode == status and "Traceback" not in err and "--resume" in err, err
    done = [p for p in runs.iterdir() if not p.name.startswith(".")]
    rows = list(csv.DictReader(open("out/results.csv")))
    assert 1 <= len(rows) == len(done) and {r["id"] for r in rows} == {p.name for p in done}
    assert not list(runs.glob(".*"))
    result = invoke("batch", str(sweep), "-o", "out", "--resume")
    assert result.exit_code == 0 and table(Path("whole/results.csv")) == table(Path("out/results.csv"))


@pytest.mark.parametrize("address", ["nonsense", pytest.param("tcp://127.0.0.1:1", marks=pytest.mark.slow)])  # waits out dask's 10 s
def test_a_scheduler_that_does_not_answer_is_one_line(sweep, address):
    pytest.importorskip("dask.distributed")
    result = invoke("batch", str(sweep), "-o", "out", "--executor", "dask", "--scheduler", address)
    assert result.exit_code == 2 and f"no Dask scheduler answers at {address!r}" in result.output
    assert len(result.output.strip().splitlines()) == 1


def test_the_contact_sheet_has_a_row_per_combination_and_shows_failures_and_huge_frames_bounded(sweep):
    from PIL import Image

    assert invoke("batch", str(sweep), "-o", "out").exit_code == 0
    with Image.open("out/contact_sheet.png") as sheet:
        scale = batching.sheet.TILE // 48  # the 48x40 world, a whole number of pixels a cell
        assert sheet.height == 4 * (40 * scale + batching.sheet.GAP + batching.sheet.LINE) + batching.sheet.GAP  # 2 frictions x 2 gravities
    rows = list(csv.DictReader(open("out/results.csv")))
    huge = Image.new("P", (12000, 12000))
    huge.save(Path("out/runs") / rows[0]["id"] / "last.png", optimize=True)
    sweep_runs = batching.read_sweep(sweep, Path("out")).runs
    rows[1]["status"] = "failed"
    path = batching.contact_sheet(rows, sweep_runs, Path("out"))
    with Image.open(path) as sheet:
        pixels = sheet.convert("RGB")
        assert batching.sheet._FAILED in {colour for _, colour in pixels.getcolors(2**20)}


@pytest.mark.parametrize("module", ["sandmod.tools.cli", "click", "numpy"])
def test_ctrl_c_while_a_command_loads_is_a_quiet_exit_130(tmp_path, module):
    """The console script's ``main``, Ctrl-C landing as loading the command line reaches ``module``:
    the child says when it gets there and waits for the test, so no timing decides where the signal
    lands (one before ``main`` starts, while Python itself starts, is Python's to report)."""
    code = (
        "import importlib.abc, sys\n"
        "class Pause(importlib.abc.MetaPathFinder):\n"
        "    def find_spec(self, name, path, target=None):\n"
        f"        if name == {module!r}:\n"
        "            print('loading', flush=True)\n"
        "            sys.stdin.read()  # until the test has sent Ctrl-C and closed it\n"
        "sys.meta_path.insert(0, Pause())\n"
        "sys.argv = ['sandmod', 'validate', 'nothing.toml']\n"
        "from sandmod.tools.entry import main\n"
        "sys.exit(main())\n"
    )
    child = subprocess.Popen([sys.executable, "-c", code], cwd=tmp_path, text=True,
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert child.stdout.readline() == "loading\n"
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=300)
    assert (child.returncode, out, err) == (130, "", "interrupted\n")


def test_ctrl_c_while_the_formats_load_is_noted_and_loading_finishes_whole():
    """Raised inside pydantic building a validator, a KeyboardInterrupt is swallowed and leaves the
    validator broken (CI once saw good bundled mods refused); so while the command line loads, Ctrl-C
    is only noted, and the command exits 130 once loading is done."""
    code = (
        "import importlib.abc, signal, sys\n"
        "class Interrupt(importlib.abc.MetaPathFinder):\n"
        "    def find_spec(self, name, path, target=None):\n"
        "        if name == 'sandmod.formats.modspec':\n"
        "            signal.raise_signal(signal.SIGINT)\n"
        "sys.meta_path.insert(0, Interrupt())\n"
        "from sandmod.tools.entry import _load_interrupted\n"
        "print(_load_interrupted())\n"
        "from sandmod.world.loading import load_ruleset\n"
        "print(len(load_ruleset().elements) > 10)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert (done.returncode, done.stdout, done.stderr) == (0, "True\nTrue\n", "")
