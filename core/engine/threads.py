"""How many threads a world steps on: more only where they pay, measured as the world runs.

The frames are the same on any number of threads, so the number is free to
change from frame to frame. A world whose passes hold few tiles (smaller
than 256 x 256 cells, like the example worlds) steps on one, and then never
compiles or starts numba's parallel code at all. A larger one starts on all of them and
every :data:`PERIOD` frames steps a few on the other count: it keeps
whichever ran faster. On a busy machine (another program on a core) that
is one thread, on an idle one all of them.

numba's threads come from its threading layer: OpenMP where it is there
(Linux's GNU OpenMP with the numba wheels), else its own work queue.
Waiting threads of GNU OpenMP spin for a long while before they sleep,
which steals the core from whatever else runs on it, and from the very
thread they wait for; so unless you set ``OMP_WAIT_POLICY`` or
``GOMP_SPINCOUNT`` yourself, they spin briefly (:data:`SPIN`). Set
``NUMBA_THREADING_LAYER`` to choose another layer (``workqueue`` or
``tbb``). GNU OpenMP cannot run in a process forked after it started: such
a child steps its worlds on one thread.

Import this module before numba (``sandmod.engine.kernel`` does): the settings are
read when numba and OpenMP start.
"""

from __future__ import annotations

import os

#: GNU OpenMP's spin before a waiting thread sleeps, unless the user sets one: a few microseconds.
SPIN = "1000"
#: Frames before the first trial of the other thread count, between trials, and in each trial.
FIRST, PERIOD, TRIAL = 4, 64, 4
#: The other count is kept when its frames took less than this share of the current count's.
BETTER = 0.95
#: Worlds with fewer tiles in a pass (smaller than 256 x 256 cells) step on one thread: what a
#: second saves them is a fraction of a second a render, less than compiling its kernel costs.
MIN_TILES_A_PASS = 4

if "OMP_WAIT_POLICY" not in os.environ:
    os.environ.setdefault("GOMP_SPINCOUNT", SPIN)

_forked_after_threads = False


def _after_fork_in_child() -> None:
    global _forked_after_threads
    import sys

    parallel = sys.modules.get("numba.np.ufunc.parallel")
    if parallel is not None and parallel._is_initialized:
        _forked_after_threads = True


os.register_at_fork(after_in_child=_after_fork_in_child)


def available() -> int:
    """The most threads a world may step on in this process."""
    if _forked_after_threads:
        return 1
    import numba

    return numba.config.NUMBA_NUM_THREADS


class Chooser:
    """Picks each frame's thread count for one world, by trial.

    The first trial comes after :data:`FIRST` frames, then one every
    :data:`PERIOD`; a trial steps :data:`TRIAL` frames on the other count, and
    its time is set against the :data:`TRIAL` frames just before it.
    """

    def __init__(self, tiles_a_pass: int):
        self.most = min(available(), tiles_a_pass) if tiles_a_pass >= MIN_TILES_A_PASS else 1
        self.current = self.most
        self._frame = 0
        self._recent: list[float] = []  # the seconds of the last 2 x TRIAL frames

    def count(self) -> int:
        """How many threads the next frame steps on."""
        if self.most == 1 or available() == 1:
            return 1
        return self._other() if self._in_trial(self._frame) else self.current

    def timed(self, seconds: float) -> None:
        """Note how long the frame just stepped took; after a trial, keep the faster count."""
        if self.most == 1:
            return
        self._recent = (self._recent + [seconds])[-2 * TRIAL :]
        self._frame += 1
        if self._in_trial(self._frame - 1) and not self._in_trial(self._frame) and len(self._recent) == 2 * TRIAL:
            before, trial = sum(self._recent[:TRIAL]), sum(self._recent[TRIAL:])
            if trial < BETTER * before:
                self.current = self._other()

    def _in_trial(self, frame: int) -> bool:
        return frame >= FIRST and (frame - FIRST) % PERIOD < TRIAL

    def _other(self) -> int:
        return 1 if self.current > 1 else self.most
