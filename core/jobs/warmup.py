"""Compiling the kernels before a run needs them: their parts side by side, one process each,
saying on the terminal how far along it is.

numba compiles a function when it is first called, and caches what it
compiled on disk (:mod:`sandmod.engine.kernelcache`); a later process loads it in a
fraction of a second. The cell update's phases are compiled each on its own and
inlined by LLVM (:mod:`sandmod.engine.compiletime`), so :func:`compile_kernels`
compiles them side by side, each subtree of them (:data:`PARTS`) in a process
of its own, as many at once as there are CPUs, each part once those whose
functions it calls are cached, then steps a tiny world itself, linking what
they compiled: no function is compiled by two processes. Run as ``python -m
sandmod.jobs.warmup PART``, this module compiles one part.

Compiled only when a run needs it: the kernel that updates tiles on several
threads at once (:func:`compile_parallel`), for worlds large enough to use
more than one.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from typing import Callable

import numpy as np

#: The parts compiled side by side, each in a process of its own, and the parts each waits for. The
#: cell update's phases are compiled once each and cached (:data:`sandmod.engine.jit.inlined`): a part
#: that calls them loads them from the cache once the parts that compile them are done, so that two
#: processes do not compile the same function. In the order they start when their turn comes: the
#: longest chain first.
PARTS = {
    "moves": (),  # moves.move and everything it calls
    "fast loop": (),  # kernel._fast_cells: it calls a few of the moves (slumps, knocks), compiled here too if not yet cached
    "phases": (),  # heat and fire, lifetime, reactions, and heat's conduction
    "cells with the fast loop": ("moves", "fast loop", "phases"),  # the cell update, linking the above
    "cells without it": ("moves", "phases"),
    "pixels": (),
    "blasts": (),
    "taps and sprays": (),
    "neighbour rules": (),
}
#: The parts a step of a world links together (the rest are called on their own).
STEP_NEEDS = ("moves", "fast loop", "phases", "cells with the fast loop", "cells without it")


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
    signatures = {
        moves.move: (S, T, i, i, e, i, i, i, i, i, yes, i, i, i, i, i, ambient),
        fire.heat_and_fire: (S, T, i, i, e, i, i, counts, i),
        reactions.lifetime: (S, T, i, i, e, i),
        reactions.react: (S, T, i, i, e, i, i, i, i),
        kernel._fast_cells: (S, T, i, i, i, i, yes, i, i, i, ambient, i, i, i, i, i, box, box),
        heat.conduct: (S, T, i, typeof(world.awake), typeof(world._woken), typeof(world._even), typeof(world._stirred), i, i, i, i),
    }
    region = (S, T, i, i, i, i, typeof(world.awake), typeof(world._woken), typeof(world._stirred), counts, i, i, i, i, i, i, typeof(world._seen))
    return signatures | {kernel.step_region_fast: region, kernel.step_region_full: region}


def compile_part(part: str) -> None:
    """Compile one of :data:`PARTS` (into the cache): the phases for their callers' types, the rest by
    calling them on a tiny world."""
    from ..engine import fire, heat, kernel, moves, reactions

    world = _tiny_world()
    s, t = world.state, world.tables
    functions = {
        "moves": [moves.move],
        "fast loop": [kernel._fast_cells],
        "phases": [fire.heat_and_fire, reactions.lifetime, reactions.react, heat.conduct],
        "cells with the fast loop": [kernel.step_region_fast],
        "cells without it": [kernel.step_region_full],
    }
    if part in functions:
        signatures = phase_signatures(world)
        for function in functions[part]:
            function.compile(signatures[function])
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


def compile_kernels(ruleset=None, announce: Callable[[str], object] | None = None) -> float:
    """Compile (or load from the cache) every kernel a world on one thread uses: the
    :data:`PARTS` side by side in processes of their own, then a step of a tiny world of
    ``ruleset`` (default: the bundled mods') here; then note this version as compiled
    (:mod:`sandmod.engine.kernelcache`). ``announce`` hears how far along it is. Returns the seconds.

    A world compiles each kernel when it first needs it, so without this the first
    explosion after a new version would stop a render for a while, unannounced.
    """
    from ..engine import kernelcache

    started = time.perf_counter()
    say = announce or (lambda line: None)
    world = _tiny_world() if ruleset is None else _world_of(ruleset)
    world.threads = 1

    def put_together() -> None:  # a step links the cells' parts and heat: here, while the rest compile
        say("compiling the kernel: putting the parts together...")
        world.step()

    if not kernelcache.is_compiled():
        _compile_parts(lambda done: say(f"compiling the kernel: {done} of {len(PARTS)} parts done, {time.perf_counter() - started:.0f} s"), put_together)
    else:
        world.step()
    for part in PARTS:  # in the cache by now: loaded, not compiled
        if part not in STEP_NEEDS:
            compile_part(part)
    kernelcache.mark_compiled()
    return time.perf_counter() - started


def compile_new_kernels(ruleset=None, announce: Callable[[str], object] | None = None) -> None:
    """:func:`compile_kernels` if this version's are not compiled yet, first handing
    ``announce`` (when given) the notice to show (:data:`sandmod.engine.kernelcache.NOTICE`), then
    how far along it is."""
    from ..engine import kernelcache

    if kernelcache.is_compiled():
        return
    if announce is not None:
        announce(kernelcache.NOTICE)
    compile_kernels(ruleset, announce)


def compile_parallel(world=None, announce: Callable[[str], object] | None = None) -> None:
    """Compile (or load) the kernel that updates a pass's tiles on several threads at once,
    if ``world`` (any, if None) may step on several."""
    from ..engine.threads import MIN_TILES_A_PASS, available

    if available() < 2:
        return
    if world is not None and ((world.threads or 2) < 2 or len(world._detonations) // 4 < MIN_TILES_A_PASS):
        return
    if announce is not None and not _cached("step_at_once"):
        announce("compiling the kernel for several threads (once per version, some seconds)...")
    tiny = _tiny_world()
    tiny.threads = 2
    tiny.step()


def _world_of(ruleset):
    from ..engine.layout import CHUNK
    from ..world.world import World

    return World(ruleset, CHUNK, CHUNK)


def _cached(function: str) -> bool:
    from ..engine.kernelcache import kernel_cache_dir

    return any(kernel_cache_dir().rglob(f"kernel.{function}-*.nbi"))


def _compile_parts(progress: Callable[[int], object], once_stepped: Callable[[], object]) -> None:
    """Compile :data:`PARTS` in processes of their own, as many at once as there are CPUs, each once
    the parts it waits for are done; call ``once_stepped`` as soon as those a step needs
    (:data:`STEP_NEEDS`) are done, while the others compile (one process fewer meanwhile: it
    compiles too)."""
    waiting = list(PARTS)
    running: dict[subprocess.Popen, str] = {}
    finished: set[str] = set()
    most = max(1, min(os.cpu_count() or 1, len(PARTS)))
    env = os.environ | {"NUMBA_CACHE_DIR": str(_cache_dir())}
    try:
        while waiting or running:
            stepping = once_stepped is not None and finished.issuperset(STEP_NEEDS)  # this process is about to compile too
            ready = [part for part in waiting if finished.issuperset(PARTS[part])]
            while ready and len(running) < max(1, most - stepping):
                part = ready.pop(0)
                waiting.remove(part)
                command = [sys.executable, "-m", "sandmod.jobs.warmup", part]
                # What fails here fails again, and says why, when this process compiles it itself.
                running[subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)] = part
            if stepping:
                once_stepped()  # while the parts just started compile
                once_stepped = None
                continue
            time.sleep(0.05)
            for process in [p for p in running if p.poll() is not None]:
                finished.add(running.pop(process))
                progress(len(finished))
    finally:
        for process in running:
            process.kill()
    if once_stepped is not None:
        once_stepped()


def _cache_dir():
    from ..engine.kernelcache import kernel_cache_dir

    return kernel_cache_dir()


if __name__ == "__main__":
    compile_part(sys.argv[1])
