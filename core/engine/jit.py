"""numba, set up for sandmod's compiled code: its threads' settings (:mod:`sandmod.engine.threads`)
and its cache folder (:mod:`sandmod.engine.kernelcache`) fixed before numba starts, then the
decorators every compiled function takes (the numba flags, in one place). Import numba through here.

- :data:`compiled`: a function of its own, called. For those that take plain numbers (LLVM
  inlines them where it pays), and for rare work that takes arrays.
- :func:`inlined`: compiled once, on its own, without numba's reference counting, and inlined
  by LLVM into every caller (:mod:`.compiletime`): for the phases of the per-cell update, which
  take arrays. Called, each call would count references to every array it is handed, and at a
  few hundred million cells a second that costs more than the physics (17 times slower,
  measured); copied into each caller by numba, as before, the update compiled as one huge
  function, twice (with and without its fast loop), each time in full. These have no machine
  code of their own and cannot be called from Python. Where numba is not as
  :mod:`.compiletime` expects, numba copies them into each caller instead (``inline="always"``).
- :func:`called`: compiled once, with machine code of its own, which every caller calls by name
  (:mod:`.compiletime`) instead of linking in a copy and optimizing it again: for the update without its
  fast loop, called once a tile by the quick step of a first run, so that it is compiled in a process
  of its own, and the step that calls it in seconds.
- :func:`quick`: optimized by LLVM at -O1, not -O3 (:mod:`.compiletime`): for the quick step
  and what it calls by name, which so compile in less time and ran as fast.
- :data:`copied`: copied into each caller by numba (``inline="always"``): for ``_step_passes``,
  whose constant ``at_once`` keeps the parallel kernel out of the serial step.
- :data:`in_place`: a function that updates the arrays it is handed and makes none, compiled
  without numba's reference counting (``_nrt=False``), called.
- :data:`parallel`: a function whose ``prange`` loops run on numba's threads.
"""

from __future__ import annotations

import os

from . import threads  # noqa: F401  (its settings for numba's threads come before numba)
from .kernelcache import kernel_cache_dir

os.environ.setdefault("NUMBA_CACHE_DIR", str(kernel_cache_dir()))  # read when numba is first imported

import numba  # noqa: E402
from numba import njit, prange  # noqa: E402, F401
from numba.core.dispatcher import Dispatcher  # noqa: E402

from . import compiletime  # noqa: E402

numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]  # in case numba was imported before us
compiletime.install()  # the cell update compiles in a quarter of the time (see the module)

compiled = njit(cache=True)
copied = njit(cache=True, inline="always")


def inlined(function, *, cache: bool = True):
    """Compiled once, on its own and without reference counting, and inlined by LLVM into every
    caller; where numba is not as :mod:`.compiletime` expects, copied into each caller by numba instead."""
    if not compiletime.LLVM_INLINES:
        return njit(cache=cache, inline="always")(function)
    compiletime.inline_everywhere(function)
    dispatcher = njit(cache=cache, _nrt=False, no_cpython_wrapper=True, no_cfunc_wrapper=True)(function)
    return compiletime.jit_only(dispatcher) if isinstance(dispatcher, Dispatcher) else dispatcher


def called(function):
    """Compiled once, with machine code of its own, which every compiled caller calls by name; optimized
    lightly, as :func:`quick`."""
    if compiletime.CALLS_BY_NAME:
        compiletime.call_by_name(function)
    return quick(function)


def quick(function, *, cache: bool = True):
    """Compiled with LLVM's light optimization (:data:`.compiletime.QUICK_OPT`): for the quick step of a first run."""
    compiletime.optimize_lightly(function)
    return njit(cache=cache)(function)


in_place = njit(cache=True, _nrt=False)
parallel = njit(cache=True, parallel=True)
