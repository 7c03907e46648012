"""The behaviours pass: after the kernel's step, each cell whose element names a plugin behaviour runs it.

One numba function walks the cells for the set of behaviours a ruleset uses: its
source (:mod:`.generated`) is written into the kernels' cache folder, named by a
hash of the behaviours' sources and of sandmod's, numba's and Python's versions,
and compiled with ``cache=True`` (a few seconds, once per set; the kernel is not
compiled again). A behaviour that does not compile is one problem naming its
plugin, at the first step.

The walk is serial, rows bottom-up and each left to right, so the frames are the
same on any number of threads. It visits the chunks that held behaviour cells
after the last pass, and the chunks awake before or after the step in the tiles
next to one whose updated rows held a behaviour's element (the kernel's mask,
``World._seen``; a cell the step moved lies within a tile of where it was seen).
Those hold every behaviour cell but one made after the step (by a blast or a
neighbour rule), which first runs on the next frame.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import re
import sys
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..engine.kernelcache import kernel_cache_dir
from ..engine.layout import CHUNK, TILE, mask_bit
from ..errors import Problem, ProblemsError
from ..formats.behaviour import View
from . import generated

#: A ruleset's behaviours (sandmod.rules.behaviours.Behaviours; the world hands them over).
Behaviours = Any

#: The salt of the behaviours' frame key (see sandmod.engine.hashing).
SALT_BEHAVIOUR = 0x3A8F05C5
#: The behaviours' functions of each pass being imported, by its key (its module takes them from here).
_GIVEN: dict[str, list[Callable]] = {}
#: Each pass compiled (or loaded) in this process, by its key.
_LOADED: dict[str, Callable] = {}
#: The files whose code a pass is compiled from, besides the behaviours'.
_OWN = [Path(__file__).parent / name for name in ("generated.py", "helpers.py", "visit.py")] + [Path(__file__).parent.parent / "formats" / "behaviour.py"]


def functions_for(key: str) -> list[Callable]:
    """The behaviours' functions, in code order, for the generated module of ``key``."""
    return _GIVEN[key]


def pass_key(table: Behaviours) -> str:
    """A name for the pass of ``table``'s behaviours: a hash of everything it is compiled from."""
    from importlib import metadata

    h = hashlib.sha256(f"{sys.version_info[:2]} {metadata.version('numba')} {table.names}".encode())
    for path in _OWN:
        h.update(path.read_bytes())
    for given in table.given:
        h.update(given.value.source_hash().encode())
    return h.hexdigest()[:16]


def compiled_pass(table: Behaviours) -> Callable:
    """The pass's ``run`` (compiled on its first call, or loaded from the cache)."""
    key = pass_key(table)
    if key not in _LOADED:
        from . import helpers

        helpers.register_marked()
        path = kernel_cache_dir() / "behaviours" / f"pass_{key}.py"
        if not path.exists():  # written once: numba's cache goes by the file's time
            path.parent.mkdir(parents=True, exist_ok=True)
            partial = path.with_suffix(f".{os.getpid()}.tmp")
            partial.write_text(generated.source(key, table.names), encoding="utf-8")
            partial.replace(path)
        _GIVEN[key] = [given.value.function for given in table.given]
        name = f"sandmod_behaviours_{key}"
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        _LOADED[key] = module.run
    return _LOADED[key]


class Walker:
    """One world's behaviours pass: what it remembers between frames."""

    def __init__(self, table: Behaviours, shape: tuple[int, int], chunks: tuple[int, int]):
        self.table = table
        self.stamp = np.zeros(shape, np.uint32)  # frame + 1 where a behaviour changed the cell
        self.held = np.zeros(chunks, np.uint8)  # chunks that hold behaviour cells (exactly, after each pass)
        self._run: Callable | None = None  # the compiled pass, once found
        self.mask = 0  # the element-mask bits of the elements with a behaviour
        for element in np.flatnonzero(table.codes):
            self.mask |= 1 << mask_bit(int(element))
        self.tiles = (-(-shape[0] // TILE), -(-shape[1] // TILE))

    def visited(self, world, before: np.ndarray) -> np.ndarray:
        """The chunks to walk: those that held behaviour cells, and those awake before or after
        the step within a tile of one whose updated rows held a behaviour's element."""
        seen = (world._seen.reshape(self.tiles) & np.int64(self.mask)) != 0
        near = seen.copy()
        near[1:] |= seen[:-1]
        near[:-1] |= seen[1:]
        around = near.copy()
        around[:, 1:] |= near[:, :-1]
        around[:, :-1] |= near[:, 1:]
        per = TILE // CHUNK
        chunks = np.repeat(np.repeat(around, per, 0), per, 1)[: self.held.shape[0], : self.held.shape[1]]
        return (((before != 0) | (world.awake != 0)) & chunks | (self.held != 0)).astype(np.uint8)

    def hold(self, cells: np.ndarray) -> None:
        """Mark the chunks that hold behaviour cells now (when a walker starts: on a world's first
        step, or the first after a snapshot is loaded, it is what the last pass would have left)."""
        behaving = self.table.codes[cells] != 0
        rows = np.add.reduceat(behaving, np.arange(0, cells.shape[0], CHUNK), axis=0)
        self.held[:] = np.add.reduceat(rows, np.arange(0, cells.shape[1], CHUNK), axis=1) != 0

    def run(self, world, before: np.ndarray, key: int) -> None:
        """Run the behaviours of ``world``'s cells (``before``: its wake marks before the step)."""
        visit = self.visited(world, before)
        if not visit.any():
            return
        run = self._run = self._run or compiled_pass(self.table)
        s, t = world.state, world.tables
        arrays = (*s, t.life_frames, t.life_jitter, t.heat_cap, t.heat_recip, t.temp_start, t.remembers, self.table.codes, self.table.args, self.stamp, world.awake, world._even, self.held)
        if run.signatures:
            run(*arrays, visit, key, world.frame)
            return
        from numba.core.errors import NumbaError

        try:
            run(*arrays, visit, key, world.frame)
        except NumbaError as exc:
            raise ProblemsError(_diagnose(self.table, arrays, key, world.frame, exc)) from None


def _diagnose(table: Behaviours, arrays: tuple, key: int, frame: int, failure: Exception) -> list[Problem]:
    """Which behaviours do not compile, each one problem naming its plugin; compiled alone."""
    import numba

    view = View(*arrays[:-3], *arrays[-3:], np.zeros(1, np.uint32), np.int64(key), np.int64(frame), np.int64(0), np.int64(0), np.int64(0))
    problems = []
    for name, given in zip(table.names, table.given):
        try:
            numba.njit(given.value.function).compile((numba.typeof(view),))
        except numba.core.errors.NumbaError as exc:
            problems.append(Problem(given.plugin, None, f"behaviour {name}", f"does not compile: {summary(exc)}"))
    plugins = ", ".join(sorted({g.plugin for g in table.given}))
    return problems or [Problem(plugins, None, "behaviours", f"do not compile together: {summary(failure)}")]


_ANSI = re.compile(r"\x1b\[[0-9;]*m")
_WHERE = re.compile(r'File "([^"]+)", line (\d+)')


def summary(exc: Exception) -> str:
    """A numba error as one line: what is wrong, and where in the behaviour's file."""
    text = _ANSI.sub("", str(exc))
    lines = [line.strip() for line in text.splitlines()]
    what = next((line for line in lines if line and not line.startswith(("Failed in", "During:", "File ", "- ", "Resolution failure", ">>>"))), text.strip())
    what = re.sub(r"View\(.*\)", "View", what)  # the view's type is a screenful
    where = [(f, n) for f, n in _WHERE.findall(text) if "numba" not in f and "sandmod_behaviours" not in f and "/passes/" not in f]
    return f"{what} ({where[0][0]}:{where[0][1]})" if where else what
