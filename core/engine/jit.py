"""numba, set up for sandmod's compiled code: its threads' settings (:mod:`sandmod.engine.threads`)
and its cache folder (:mod:`sandmod.engine.kernelcache`) fixed before numba starts, then the
decorators every compiled module uses. Import numba through here."""

from __future__ import annotations

import os

from . import threads  # noqa: F401  (its settings for numba's threads come before numba)
from .kernelcache import kernel_cache_dir

os.environ.setdefault("NUMBA_CACHE_DIR", str(kernel_cache_dir()))  # read when numba is first imported

import numba  # noqa: E402
from numba import njit, prange  # noqa: E402, F401

numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]  # in case numba was imported before us
