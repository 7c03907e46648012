"""Compiling the kernels before a run needs them: their parts side by side, in worker processes,
saying on the terminal how far along it is.

numba compiles a function when it is first called, and caches what it
compiled on disk (:mod:`sandmod.engine.kernelcache`); a later process loads it in a
fraction of a second. The cell update's phases are compiled each on its own and
inlined by LLVM, and the update without its fast loop on its own too, called by name by a
quick step (:mod:`sandmod.engine.compiletime`), so :func:`compile_kernels`
compiles them side by side, each subtree of them (:data:`PARTS`) handed to one of as many worker
processes as there are CPUs (``python -m sandmod.jobs.warmup --serve``), each part
once those whose functions it calls are cached, then steps a tiny world itself with
the quick step (``kernel.step_soon``), linking what they compiled: no function is
compiled by two processes. The step a world takes once the version is compiled
(``kernel.step``, faster) optimizes the update's two versions, with and without the
fast loop, again as part of itself, a part of its own. Given the world a command is about to run,
:func:`compile_kernels` returns once that world's first frame can be drawn with the
quick step, the parts it does not use at first, and the best step, still compiling
(:func:`finish_later`).
Run as ``python -m sandmod.jobs.warmup PART``, this module compiles one part.

Compiled only when a run needs it: the kernel that updates tiles on several
threads at once (:func:`compile_parallel`), for worlds large enough to use
more than one.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import threading
import time
from typing import Callable

import numpy as np

#: The parts compiled side by side, in worker processes, and the parts each waits for. The
#: cell update's phases are compiled once each and cached (:data:`sandmod.engine.jit.inlined`): a part
#: that calls them loads them from the cache once the parts that compile them are done, so that two
#: processes do not compile the same function. In the order they start when their turn comes: the
#: longest chain first.
PARTS = {
    "moves": (),  # moves.move and everything it calls
    "phases": (),  # heat and fire, lifetime, reactions, heat's conduction, and the step's lists of tiles
    "cells": ("moves", "phases"),  # the cell update without its fast loop, which the quick step calls by name
    "pixels": (),
    "fast loop": ("moves", "phases"),  # kernel._fast_cells, and the update with it: for the best step
    "step": ("cells", "fast loop"),  # the best step: the update inlined, both versions
    "several threads": ("cells", "fast loop"),  # the step on several threads at once: only where asked (ASKED)
    "blasts": (),
    "taps and sprays": (),
    "neighbour rules": (),
}
#: The parts the quick step (``kernel.step_soon``) links together, compiled before it here (the rest are called on their own, or later).
STEP_NEEDS = ("moves", "phases", "cells")
#: The parts a world may not use as it starts: they may go on compiling while it runs (:func:`unused_at_first`).
LATER = ("fast loop", "step", "blasts", "taps and sprays", "neighbour rules")
#: The parts compiled only where :func:`compile_kernels` is asked to (``several_threads``): a command compiles
#: the kernel for several threads when its world may use them (:func:`compile_parallel`).
ASKED = ("several threads",)


def _tiny_world():
    from ..engine.layout import CHUNK
    from ..world.loading import load_ruleset
    from ..world.world import World

    return World(load_ruleset(), CHUNK, CHUNK)


def phase_signatures(world) -> dict:
    """The phases of the cell update and the update itself, each with the types its caller hands it
    (as :func:`sandmod.engine.kernel.step_region` or ``_update_tile`` calls it): compiled for these, each is found in the
    cache when the cell update compiles. (A type that differs costs a compile, not a wrong result:
    the update compiles the phase for its own types; ``tests/test_compiletime.py`` checks they agree.)"""
    from numba import typeof, types

    from ..engine import fire, heat, kernel, moves, reactions

    s, t = world.state, world.tables
    S, T, i, yes = typeof(s), typeof(t), types.int64, types.boolean
    e, ambient, box = typeof(s.cells[0, 0]), typeof(t.temp_start[0]), types.UniTuple(types.int64, 4)
    counts = typeof(world._detonations)
    tiles = typeof(np.empty(1, np.int64))
    signatures = {
        moves.move: (S, T, i, i, e, i, i, i, i, i, yes, i, i, i, i, i, ambient),
        fire.heat_and_fire: (S, T, i, i, e, i, i, counts, i),
        reactions.lifetime: (S, T, i, i, e, i),
        reactions.react: (S, T, i, i, e, i, i, i, i),
        kernel._fast_cells: (S, T, i, i, i, i, yes, i, i, i, ambient, i, i, i, i, i, box, box),
        heat.conduct: (S, T, i, typeof(world.awake), typeof(world._woken), typeof(world._even), typeof(world._stirred), i, i, i, i),
        kernel.clear_marks: (typeof(s.flags), typeof(world.awake)),
        kernel._tiles_of_pass: (typeof(world.awake), typeof(world._woken), i, i, i, tiles, tiles),
    }
    region = (S, T, i, i, i, i, typeof(world.awake), typeof(world._woken), typeof(world._stirred), counts, i, i, i, i, i, i, typeof(world._seen))
    return signatures | {kernel.step_region_fast: region, kernel.step_region_full: region, kernel.step_region_full_by_name: region}


def compile_part(part: str) -> None:
    """Compile one of :data:`PARTS` (into the cache): the phases for their callers' types, the rest by
    calling them on a tiny world."""
    from ..engine import fire, heat, kernel, moves, reactions

    world = _tiny_world()
    s, t = world.state, world.tables
    functions = {
        "moves": [moves.move],
        "phases": [fire.heat_and_fire, reactions.lifetime, reactions.react, heat.conduct, kernel.clear_marks, kernel._tiles_of_pass],
        "cells": [kernel.step_region_full_by_name],
        "fast loop": [kernel._fast_cells, kernel.step_region_fast],
    }
    if part in functions:
        signatures = phase_signatures(world)
        for function in functions[part]:
            function.compile(signatures[function])
    elif part == "step":
        world.threads = 1
        kernel.step(*world._step_arguments(1))
    elif part == "several threads":
        world.threads = 2
        world.step()
    elif part == "blasts":
        world._explode(kernel.take_detonations(s, t, world._detonations), 0)
    elif part == "taps and sprays":
        world.spawn_particles(np.zeros(1, np.int64), np.zeros(1, np.int64), 0, 0.0, 0.0)
    elif part == "neighbour rules":
        from ..passes.counts import compile_pass

        compile_pass(world)
    elif part == "pixels":
        world.image(rgb=np.empty((world.height, world.width, 3), np.uint8))
        world.heat_image()
    else:
        raise ValueError(f"no part {part!r}")


def compile_kernels(ruleset=None, announce: Callable[[str], object] | None = None, *, first_frame_of=None, several_threads: bool = False) -> float:
    """Compile (or load from the cache) every kernel a world on one thread uses: the
    :data:`PARTS` side by side in processes of their own, then a step of a tiny world of
    ``ruleset`` (default: the bundled mods') here; then note this version as compiled
    (:mod:`sandmod.engine.kernelcache`). ``announce`` hears how far along it is. Returns the seconds.
    With ``several_threads``, the kernel for several threads too (:data:`ASKED`), side by side with the
    rest, where there are several CPUs (:func:`compile_parallel` would compile it alone, after).

    A world compiles each kernel when it first needs it, so without this the first
    explosion after a new version would stop a render for a while, unannounced. Given a
    world, ``first_frame_of``, it returns once that world's first frame can be drawn: the parts
    it does not use at first (:func:`unused_at_first`) go on compiling meanwhile, and
    :func:`finish_later` waits for them (the command line does, as it exits).
    """
    from ..engine import kernelcache

    started = time.perf_counter()
    say = announce or (lambda line: None)
    world = _tiny_world() if ruleset is None else _world_of(ruleset)
    world.threads = 1
    parts = [part for part in PARTS if part not in ASKED or (several_threads and _several_cpus())]
    if kernelcache.is_compiled():
        world.step()
    else:
        later = () if first_frame_of is None else unused_at_first(first_frame_of)
        first = [part for part in parts if part not in later]
        compiling = _Compiling(lambda done: say(f"compiling the kernel: {done} of {len(first)} parts done, {time.perf_counter() - started:.0f} s"), first, parts=parts)
        try:
            with compiling.here_after(STEP_NEEDS):  # a step links the cells' parts and heat: here, while the rest compile
                say("compiling the kernel: putting the parts together...")
                world.step()
            compiling.wait_for(first)
        except BaseException:
            compiling.stop()
            raise
        if later and not compiling.done():
            _LATER.append((compiling, announce))
            return time.perf_counter() - started
        compiling.join()
    for part in parts:  # in the cache by now: loaded, not compiled
        if part not in STEP_NEEDS:
            compile_part(part)
    kernelcache.mark_compiled()
    return time.perf_counter() - started


def unused_at_first(world) -> tuple[str, ...]:
    """The parts of :data:`LATER` that ``world`` does not use as it starts: the best step and its fast loop (a
    first run steps with the quick step), and where it has no explosive in its rules and none set off by its
    file, no sprays, no neighbour rules, their parts. (A player may paint an explosive
    later: then the blasts compile as it goes off, if they have not yet.)"""
    used = {
        "fast loop": False,  # a first run steps with the quick step, which has none
        "step": False,
        "blasts": bool(world.scheduled) or bool(world.tables.blast.any()),
        "taps and sprays": bool(world.sprays),
        "neighbour rules": world.ruleset.neighbours is not None,
    }
    return tuple(part for part in LATER if not used[part])


#: The kernels' parts still compiling after :func:`compile_kernels` returned (its ``first_frame_of``).
_LATER: list[tuple[_Compiling, Callable[[str], object] | None]] = []


def finish_later() -> None:
    """Wait for the parts :func:`compile_kernels` left compiling (its ``first_frame_of``), saying so
    to its ``announce`` if they are not done yet; then note this version as compiled, if they all were."""
    from ..engine import kernelcache

    while _LATER:
        compiling, announce = _LATER.pop()
        if not compiling.done() and announce is not None:
            announce("compiling the kernel's other parts (its faster step, explosions, taps, neighbour rules) for later runs...")
        compiling.join()
        if compiling.succeeded():
            kernelcache.mark_compiled()


def abandon_later() -> None:
    """Stop the parts :func:`compile_kernels` left compiling: a later run compiles them."""
    while _LATER:
        _LATER.pop()[0].stop()


def compile_new_kernels(ruleset=None, announce: Callable[[str], object] | None = None, *, first_frame_of=None, several_threads: bool = False) -> None:
    """:func:`compile_kernels` if this version's are not compiled yet, first handing
    ``announce`` (when given) the notice to show (:data:`sandmod.engine.kernelcache.NOTICE`), then
    how far along it is."""
    from ..engine import kernelcache

    if kernelcache.is_compiled():
        return
    if announce is not None:
        announce(kernelcache.NOTICE)
    compile_kernels(ruleset, announce, first_frame_of=first_frame_of, several_threads=several_threads)


def compile_parallel(world=None, announce: Callable[[str], object] | None = None) -> bool:
    """Compile (or load) the kernel that updates a pass's tiles on several threads at once,
    if ``world`` (any, if None) may step on several; returns whether it compiled it (not cached yet)."""
    from ..engine.threads import MIN_TILES_A_PASS

    if not _several_cpus():
        return False
    if world is not None and ((world.threads or 2) < 2 or len(world._detonations) // 4 < MIN_TILES_A_PASS):
        return False
    new = not _cached("step_at_once")
    if announce is not None and new:
        announce("compiling the kernel for several threads (once per version, some seconds)...")
    tiny = _tiny_world()
    tiny.threads = 2
    tiny.step()
    return new


def _several_cpus() -> bool:
    from ..engine.threads import available

    return available() >= 2


def _world_of(ruleset):
    from ..engine.layout import CHUNK
    from ..world.world import World

    return World(ruleset, CHUNK, CHUNK)


def _cached(function: str) -> bool:
    from ..engine.kernelcache import kernel_cache_dir

    return any(kernel_cache_dir().rglob(f"kernel.{function}-*.nbi"))


class _Worker:
    """A process of its own that compiles parts, one after another, as it is told (``python -m
    sandmod.jobs.warmup --serve``): one start-up for many parts."""

    def __init__(self) -> None:
        command = [sys.executable, "-m", "sandmod.jobs.warmup", "--serve"]
        env = os.environ | {"NUMBA_CACHE_DIR": str(_cache_dir())}
        # What fails there fails again, and says why, when this process compiles it itself.
        self._process = subprocess.Popen(command, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)

    def compile(self, part: str) -> bool:
        """Compile ``part`` there; whether it did."""
        try:
            self._process.stdin.write(part + "\n")
            self._process.stdin.flush()
        except OSError:  # it is gone
            return False
        return self._process.stdout.readline() == f"compiled {part}\n"

    def close(self) -> None:
        self._process.kill()
        self._process.wait()


def _serve() -> None:
    """Compile each part named on stdin, one a line, and say on stdout when each is done."""
    for line in sys.stdin:
        part = line.strip()
        try:
            compile_part(part)
        except Exception:  # noqa: BLE001  (its caller compiles it again itself, and says why)
            print(f"failed {part}", flush=True)
        else:
            print(f"compiled {part}", flush=True)


class _Compiling:
    """:data:`PARTS` (or those of ``parts``) compiling in :class:`_Worker` processes, as many at once as there are CPUs (one
    fewer while this process compiles too: :meth:`here_after`), each part once those it waits for are
    done, the parts of ``told`` first (others while none of those is ready). ``progress`` hears how many of ``told`` are done, each time
    one of them is."""

    def __init__(self, progress: Callable[[int], object], told, worker: Callable[[], _Worker] | None = None, parts=None) -> None:
        self._progress, self._told, self._worker = progress, set(told), worker or _Worker
        self._parts = list(PARTS if parts is None else parts)
        self._most = max(1, min(os.cpu_count() or 1, len(self._parts)))
        self._waiting = list(self._parts)
        self._finished: dict[str, bool] = {}  # whether each part compiled
        self._compiling = 0
        self._here_after: set[str] | None = None  # this process compiles once these are done (here_after)
        self._stopping = False
        self._workers: list[_Worker] = []
        self._changed = threading.Condition()
        self._threads = [threading.Thread(target=self._work, name="sandmod compiling", daemon=True) for _ in range(self._most)]
        for thread in self._threads:
            thread.start()

    def _next(self) -> str | None:
        """A part to compile now, once there is one (under the lock); None: no more."""
        while not self._stopping and self._waiting:
            ready = [part for part in self._waiting if self._finished.keys() >= set(PARTS[part])]
            ready = [part for part in ready if part in self._told] or ready  # those waited for first
            here = self._here_after is not None and self._finished.keys() >= self._here_after
            if ready and self._compiling < max(1, self._most - here):
                self._waiting.remove(ready[0])
                self._compiling += 1
                return ready[0]
            self._changed.wait()
        return None

    def _work(self) -> None:
        worker = None
        try:
            while True:
                with self._changed:
                    part = self._next()
                    if part is None:
                        return
                    if worker is None:
                        worker = self._worker()
                        self._workers.append(worker)
                compiled = worker.compile(part)
                if compiled and part == "step":
                    from ..engine import kernelcache

                    kernelcache.mark_best_step_cached()  # a world on the quick step switches to it
                with self._changed:  # said before anyone waiting for it goes on
                    self._finished[part] = compiled
                    self._compiling -= 1
                    if part in self._told:
                        self._progress(len(self._told & self._finished.keys()))
                    self._changed.notify_all()
        finally:
            if worker is not None:
                worker.close()
            with self._changed:
                self._changed.notify_all()

    def wait_for(self, parts) -> None:
        """Wait until ``parts`` are done (or none will be)."""
        with self._changed:
            self._changed.wait_for(lambda: self.done() or self._finished.keys() >= set(parts))

    @contextlib.contextmanager
    def here_after(self, parts):
        """Wait for ``parts``, then compile in this process too: one process fewer from the moment they are done."""
        with self._changed:
            self._here_after = set(parts)
            self._changed.wait_for(lambda: self.done() or self._finished.keys() >= self._here_after)
        try:
            yield
        finally:
            with self._changed:
                self._here_after = None
                self._changed.notify_all()

    def done(self) -> bool:
        """Whether none is compiling or will be."""
        return not any(thread.is_alive() for thread in self._threads)

    def succeeded(self) -> bool:
        """Whether every part compiled."""
        return self._finished.keys() == set(self._parts) and all(self._finished.values())

    def join(self) -> None:
        for thread in self._threads:
            thread.join()

    def stop(self) -> None:
        """Stop the parts compiling and start no more."""
        with self._changed:
            self._stopping = True
            self._changed.notify_all()
            workers = list(self._workers)
        for worker in workers:
            worker.close()
        self.join()


def _cache_dir():
    from ..engine.kernelcache import kernel_cache_dir

    return kernel_cache_dir()


if __name__ == "__main__":
    _serve() if sys.argv[1:] == ["--serve"] else compile_part(sys.argv[1])
