"""A batch's output folder: what is in it, and who may write there.

A batch holds a lock on the folder while it runs, so a second batch into the same folder is
refused instead of deleting the first one's work. A folder that holds files batch did not write is
refused (a researcher's own ``results.csv``) unless the user says ``--force``, and one that holds
an earlier batch's runs unless ``--resume``. A run's folder counts as done only when it is a real
folder (never followed through a link) whose row is this run's and whose files are all there;
anything else is cleared and the run done again.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

from ...errors import Problem, ProblemsError, display_path
from ...formats.userfiles import Refused, read_bytes
from .run import LOGS, RUNS, Run

MARK = ".sandmod-batch"  # written into every batch's folder: it says the folder is a batch's
#: Everything a batch writes into its folder.
WRITTEN = {RUNS, LOGS, MARK, "results.csv", "results.parquet", "summary.csv", "results_long.csv", "contact_sheet.png"}

try:
    import fcntl
except ImportError:  # Windows: no lock (two batches into one folder are the user's to avoid)
    fcntl = None


class OutputFolder:
    """``path``, claimed for one batch: locked, checked, its leftovers cleared."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path).absolute()
        self.runs = self.path / RUNS
        self._lock = None

    def claim(self, *, resume: bool, force: bool) -> None:
        """Lock the folder and check that this batch may write in it; ProblemsError if not. What a
        killed batch was writing (``.part`` folders) is cleared, under the lock."""
        where = display_path(self.path)
        if self.path.exists() and not self.path.is_dir():
            raise ProblemsError([Problem(where, None, "", "is a file, not a folder: another -o")])
        self.path.mkdir(parents=True, exist_ok=True)
        self._take_lock(where)
        try:
            self._check(where, resume=resume, force=force)
        except BaseException:
            self.release()
            raise
        (self.path / MARK).write_text("written by sandmod batch\n", encoding="utf-8")
        self.runs.mkdir(exist_ok=True)
        self.clear_parts()

    def _check(self, where: str, *, resume: bool, force: bool) -> None:
        entries = {p.name for p in self.path.iterdir()}
        # a batch's folder holds only what batches write; any other folder is the user's
        theirs = sorted(entries - WRITTEN) if MARK in entries or resume else sorted(entries)
        if theirs and not force:
            named = ", ".join(theirs[:4]) + (", ..." if len(theirs) > 4 else "")
            raise ProblemsError([Problem(where, None, "", f"holds files sandmod batch did not write ({named}): another -o, or --force to write beside them")])
        if self.runs.is_dir() and any(not p.name.startswith(".") for p in self.runs.iterdir()) and not resume:
            raise ProblemsError([Problem(where, None, "", "holds the runs of an earlier batch: --resume to go on with them, or another -o")])

    def _take_lock(self, where: str) -> None:
        """Lock the folder itself (no lock file to leave behind); the lock goes with the process."""
        if fcntl is None:
            return
        lock = os.open(self.path, os.O_RDONLY)
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(lock)
            raise ProblemsError([Problem(where, None, "", "another batch is writing into this folder: wait for it to end, or another -o")]) from None
        self._lock = lock

    def release(self) -> None:
        if self._lock is not None:
            os.close(self._lock)
            self._lock = None

    def clear_parts(self) -> None:
        """Remove the half-written runs (only this batch writes here: it holds the lock)."""
        if self.runs.is_dir():
            for stale in self.runs.glob(".*.part"):
                shutil.rmtree(stale, ignore_errors=True)

    def done_row(self, run: Run, *, clear: bool = True) -> dict[str, Any] | None:
        """The row of a run whose folder is complete and this run's, or None (and with ``clear``,
        the folder, if any, removed: the run is done again)."""
        row = _complete_row(run)
        if clear and row is None and (run.folder.is_symlink() or run.folder.exists()):
            if run.folder.is_symlink() or not run.folder.is_dir():
                run.folder.unlink()
            else:
                shutil.rmtree(run.folder)
        return row


def _complete_row(run: Run) -> dict[str, Any] | None:
    folder = run.folder
    if folder.is_symlink() or not folder.is_dir():
        return None
    try:
        row = json.loads(read_bytes(folder / "row.json", 2**20))
    except (Refused, ValueError):
        return None
    expected = {"id": run.id, "world": run.world, "seed": run.seed, "status": "done", "frames": run.frames}
    if not isinstance(row, dict) or any(row.get(k) != v for k, v in expected.items()) or not isinstance(row.get("outputs"), str):
        return None
    if any(row.get(f"parameter.{k}") != v for k, v in run.parameters.items()):
        return None
    for name in row["outputs"].split(";"):
        path = folder / name
        if path.is_symlink() or not path.exists() or (name != f"animation.{run.record['format']}" and not path.is_file()):
            return None
    return row if _readable_png(folder / "last.png") else None


def _readable_png(path: Path) -> bool:
    from PIL import Image

    try:
        with Image.open(path) as image:
            if image.format != "PNG":
                return False
            image.verify()
        return True
    except Exception:  # anything Pillow says about a broken file
        return False
