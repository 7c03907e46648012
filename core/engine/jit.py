"""numba, set up for sandmod's compiled code: its threads' settings (:mod:`sandmod.engine.threads`)
and its cache folder (:mod:`sandmod.engine.kernelcache`) fixed before numba starts, then the
decorators every compiled function takes (the numba flags, in one place). Import numba through here.

- :data:`compiled`: a function of its own, called. For those that take plain numbers (LLVM
  inlines them where it pays), and for rare work that takes arrays.
- :data:`inlined`: compiled into each caller by numba (``inline="always"``). For the phases of
  the per-cell update, which take arrays: called, each call would count references to every
  array it is handed, and at a few hundred million cells a second that costs more than the physics.
- :data:`in_place`: a function that updates the arrays it is handed and makes none, compiled
  without numba's reference counting (``_nrt=False``). The per-cell update is one: each
  phase inlined into it would otherwise count a reference to each array it takes, for every
  cell (17 times slower, measured).
- :data:`parallel`: a function whose ``prange`` loops run on numba's threads.
"""

from __future__ import annotations

import os

from . import threads  # noqa: F401  (its settings for numba's threads come before numba)
from .kernelcache import kernel_cache_dir

os.environ.setdefault("NUMBA_CACHE_DIR", str(kernel_cache_dir()))  # read when numba is first imported

import numba  # noqa: E402
from numba import njit, prange  # noqa: E402, F401

from . import compiletime  # noqa: E402

numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]  # in case numba was imported before us
compiletime.install()  # the cell update compiles in a quarter of the time (see the module)

compiled = njit(cache=True)
copied = njit(cache=True, inline="always")
_inlined = njit(cache=True, _nrt=False)


def inlined(function):
    """Compiled on its own, without reference counting, and inlined by LLVM into every caller."""
    compiletime.inline_everywhere(function)
    return _inlined(function)


in_place = njit(cache=True, _nrt=False)
parallel = njit(cache=True, parallel=True)
