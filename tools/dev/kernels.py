"""Another version of the kernel beside this one, and timing in turns on the same frames.

A developer's tool, run from a checkout (``python tools/dev/bench.py against
OLD.py``); it is not part of the installed package.

:func:`load_kernel` imports a kernel file from another revision (``git show
REV:core/engine/kernel.py > /tmp/old.py``) under a name of its own; its relative imports
name this sandmod's engine modules. :func:`stepping_with` makes worlds step with it.
:func:`in_turns` is the one timing loop: contenders take turns over short
stretches of frames, each stretch a few times from the same state, and each
one's best time counts, which on a machine whose speed drifts from second to
second compares them far more closely than whole runs one after another.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import sys
import time
from pathlib import Path
from types import ModuleType
from typing import Callable, Iterator, Protocol, Sequence

import numpy as np

from sandmod.jobs.benchmark import Bench
from sandmod.world import world as world_module
from sandmod.world.world import World


class FramesDiffer(Exception):
    """Two kernels compared by :func:`compare` stepped a scene to different frames."""

    def __init__(self, frame: int):
        super().__init__(f"the frames differ by frame {frame}")
        self.frame = frame


class _OlderKernel:
    """A kernel whose ``step`` was written for fewer arguments, or for the chunk marks ``woken``
    and ``stirred`` before they had a cache line each as a third axis (entry ``[cy, cx, 0]``):
    its ``step`` is handed the arguments, and the (rows, cols) views of the marks, it was written for.
    A kernel from before ``step_at_once`` has one ``step``, parallel: it serves as both."""

    def __init__(self, module: ModuleType, takes: int, flat: bool):
        self.module, self.takes, self.flat = module, takes, flat

    def __getattr__(self, name: str):
        return getattr(self.module, name)

    def step(self, *args):
        args = args[: self.takes]
        if self.flat:
            args = tuple(a[:, :, 0] if isinstance(a, np.ndarray) and a.ndim == 3 else a for a in args)
        return self.module.step(*args)

    @property
    def step_at_once(self):
        return getattr(self.module, "step_at_once", self.step)


def load_kernel(path) -> ModuleType | _OlderKernel:
    """Another version of the engine's ``kernel.py``, importable beside this one. Raises ValueError if it is none."""
    module = _import_kernel(path)
    from sandmod.engine import kernel

    takes = _arguments(module.step)
    flat = not hasattr(module, "_mark")
    fits = takes >= _arguments(kernel.step) and not flat and hasattr(module, "step_at_once")
    return module if fits else _OlderKernel(module, takes, flat)


def _arguments(function) -> int:
    """How many arguments a (numba-compiled or plain) function takes."""
    return getattr(function, "py_func", function).__code__.co_argcount


def _import_kernel(path) -> ModuleType:
    from sandmod.engine import kernel

    if Path(path).resolve() == Path(kernel.__file__).resolve():
        # Itself: imported again under another name, it would share numba's cache files with this
        # kernel, and a compile of it (after an edit) would leave this kernel's cached code naming
        # a module that later processes cannot import.
        return kernel
    # One name per file, the same in every process, and registered: numba's cache records the module
    # of what it compiled and imports it by that name when it loads the cached code.
    name = "sandmod.engine._kernel_" + hashlib.sha1(str(Path(path).resolve()).encode()).hexdigest()[:12]
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ValueError(f"{path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as error:  # its code is older or newer than this sandmod: say why, not where
        del sys.modules[name]
        raise ValueError(f"{path}: cannot be imported beside this sandmod ({type(error).__name__}: {error})") from None
    missing = [f for f in ("step", "take_detonations", "explode") if not callable(getattr(module, f, None))]
    if missing:
        raise ValueError(f"{path}: not a sandmod kernel (no {', '.join(missing)})")
    return module


@contextlib.contextmanager
def stepping_with(kernel) -> Iterator[None]:
    """Worlds step with ``kernel`` (a module, or :func:`load_kernel`'s) until the block ends."""
    before = world_module._kernel
    world_module._kernel = lambda: kernel
    try:
        yield
    finally:
        world_module._kernel = before


def _use(world: World, count: int | None, parallel_step: bool) -> None:
    """Step ``world`` on ``count`` threads. A kernel from before ``step_at_once`` has one ``step``,
    parallel: numba's thread count is set for it here, or it would run on all of numba's threads
    whatever ``count`` says (the world sets numba's count only for more than one)."""
    world.threads = count
    if count is not None and parallel_step:
        import numba

        numba.set_num_threads(max(1, min(count, numba.config.NUMBA_NUM_THREADS)))


def _arrays(world: World) -> tuple[np.ndarray, ...]:
    """Everything a step reads or writes: the cells' state and the chunks' marks."""
    return (*world.state, world.awake, world._woken, world._even, world._stirred, world._detonations, world._fast_gain, world._seen)


def saved(world: World) -> list[np.ndarray]:
    return [a.copy() for a in _arrays(world)]


def restore(world: World, state: list[np.ndarray], frame: int) -> None:
    for array, copy in zip(_arrays(world), state):
        array[...] = copy
    world.frame = frame


class Contender(Protocol):
    """One side of :func:`in_turns`: it goes back to its stretch's start, and runs the stretch's frames."""

    def rewind(self) -> None: ...

    def run(self, frames: range) -> None: ...


def in_turns(
    contenders: Sequence[Contender], steps: int, *, segment: int = 25, repeats: int = 3, after: Callable[[range], None] = lambda frames: None
) -> list[float]:
    """Seconds each contender takes for ``steps`` frames: stretches of ``segment`` frames, each run
    ``repeats`` times by every contender in turn (the order reversed every other time), the best
    of each counted. ``after(frames)`` is called at each stretch's end: it checks what the
    contenders reached and sets where they rewind to next."""
    best = [0.0] * len(contenders)
    for first in range(0, steps, segment):
        frames = range(first, min(first + segment, steps))
        times = [float("inf")] * len(contenders)
        order = list(range(len(contenders)))
        for repeat in range(repeats):
            for k in order if repeat % 2 == 0 else reversed(order):
                contenders[k].rewind()
                began = time.perf_counter()
                contenders[k].run(frames)
                times[k] = min(times[k], time.perf_counter() - began)
        after(frames)
        best = [b + t for b, t in zip(best, times)]
    return best


class _KernelRun:
    """A kernel on a thread count stepping the shared world, from its own start; ``end``: where its first run ended."""

    def __init__(self, world: World, kernel, count: int | None):
        self.world, self.kernel, self.count = world, kernel, count
        self.start, self.frame, self.end = saved(world), world.frame, None

    def rewind(self) -> None:
        restore(self.world, self.start, self.frame)
        _use(self.world, self.count, isinstance(self.kernel, _OlderKernel))

    def run(self, frames: range) -> None:
        with stepping_with(self.kernel):
            for _ in frames:
                self.world.step()
        if self.end is None:
            self.end = saved(self.world)

    def warm(self) -> None:
        """Compile its kernel, or load it from the cache, before it is timed: a step, forgotten."""
        self.rewind()
        self.run(range(1))
        self.end = None

    def go_on_from(self, state: list[np.ndarray]) -> None:
        self.start, self.frame, self.end = state, self.world.frame, None


def compare(
    bench: Bench,
    steps: int,
    threads: int | None | Sequence[int | None],
    kernels: Sequence,
    *,
    segment: int = 25,
    repeats: int = 3,
    own_frames: bool = False,
) -> list[float]:
    """Seconds each kernel module takes to step ``bench``'s world for ``steps`` steps, on the same frames.

    ``threads`` is one count for all, or one per kernel: the same kernel
    listed twice with two counts times them against each other (a count of
    None lets the world choose). The kernels must reach the same frames
    (every cell's state) at the end of every stretch, or
    :class:`FramesDiffer` is raised; the next stretch starts from the first
    kernel's state, wake marks included (any kernel accepts another's marks:
    they only ever cover more than is needed). With ``own_frames`` (kernels
    whose rules differ), each goes on from its own state instead.
    """
    counts = list(threads) if isinstance(threads, (list, tuple)) else [threads] * len(kernels)
    world = bench.make()
    runs = [_KernelRun(world, kernel, count) for kernel, count in zip(kernels, counts)]
    for run in runs:
        run.warm()
    restore(world, runs[0].start, runs[0].frame)
    cells = len(world.state)  # the chunks' marks may differ, as one kernel may wake finer than another

    def after(frames: range) -> None:
        ends = [run.end for run in runs]
        if not own_frames and any(not all(np.array_equal(a, b) for a, b in zip(ends[0][:cells], end[:cells])) for end in ends[1:]):
            raise FramesDiffer(runs[0].frame + len(frames))
        for run, end in zip(runs, ends):
            run.go_on_from(end if own_frames else ends[0])

    return in_turns(runs, steps, segment=segment, repeats=repeats, after=after)


def _by_id(world: World, into: World) -> np.ndarray:
    """``world``'s element numbers as ``into``'s ruleset numbers them (-1: not loaded there)."""
    ids = {e.id: e.index for e in into.ruleset.elements}
    return np.array([ids.get(e.id, -1) for e in world.ruleset.elements], np.int64)


def same_cells(world: World, other: World) -> bool:
    """Whether two worlds of different rulesets hold the same cells, element by element id."""
    remap = _by_id(other, world)
    for name, mine, theirs in zip(world.state._fields, world.state, other.state):
        if not np.array_equal(mine, remap[theirs] if name in ("cells", "carry") else theirs):
            return False
    return True


def compare_worlds(benches: Sequence[Bench], steps: int, threads: int | None, *, segment: int = 25, repeats: int = 3) -> list[float]:
    """Seconds each of ``benches`` (one scene, each world of its own ruleset) takes for ``steps``
    steps with this kernel, in turns; :class:`FramesDiffer` unless they reach the same cells,
    element by id, at the end of every stretch."""
    from sandmod.engine import kernel

    runs = [_KernelRun(bench.make(), kernel, threads) for bench in benches]
    for run in runs:
        run.warm()

    def after(frames: range) -> None:
        for run in runs:
            restore(run.world, run.end, run.frame + len(frames))
        if not all(same_cells(runs[0].world, run.world) for run in runs[1:]):
            raise FramesDiffer(runs[0].frame + len(frames))
        for run in runs:
            run.go_on_from(run.end)

    return in_turns(runs, steps, segment=segment, repeats=repeats, after=after)
