"""Where compiled kernels are kept, and whether this version's are there yet.

Nothing here imports numba, so commands that do not simulate can ask
without paying for it.
"""

from __future__ import annotations

import functools
import hashlib
import os
import sys
from importlib import metadata
from pathlib import Path

#: What the commands (and the pytest plugin) say before they compile a new version's kernels.
NOTICE = "compiling the kernel (once per version, about a minute)..."

#: The files whose code or constants the compiled kernels contain: every module kernel.py takes
#: names from. Numba notices a change to a kernel's own file only (it keeps the values of globals
#: taken from other modules as they were when it compiled), so the cache folder is named after them.
KERNEL_SOURCES = ("kernel.py", "hashing.py", "traversal.py", "world.py", "compiler.py", "modspec.py")


@functools.cache
def version_hash(folder: Path = Path(__file__).parent) -> str:
    """A hash of the kernel sources in ``folder``, where they are, and numba's and Python's versions:
    compiled kernels are good for exactly these (numba files its cache by the source's path)."""
    h = hashlib.sha256(f"{sys.version_info[:2]} {metadata.version('numba')} {folder.resolve()}".encode())
    for name in KERNEL_SOURCES:
        h.update((folder / name).read_bytes())
    return h.hexdigest()[:16]


def kernel_cache_dir() -> Path:
    """Where compiled kernels are kept: ``$NUMBA_CACHE_DIR``, else a folder of the user's cache
    named after :func:`version_hash`, so that a change to any kernel source compiles them anew.

    Not beside the installed package, where numba would put them by default:
    files pip did not install would survive an uninstall there, leaving a
    stray ``sandmod`` folder that shadows a later editable install.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.environ.get("LOCALAPPDATA") or Path.home() / ".cache"
    return Path(base) / "sandmod" / "numba" / version_hash()


def _stamp() -> Path:
    """A file that exists once kernels of exactly this code, numba and Python have been compiled."""
    return kernel_cache_dir() / f"compiled-{version_hash()}"


def is_compiled() -> bool:
    """Have this version's kernels been compiled and cached (so a start takes a second, not a minute)?"""
    return _stamp().exists()


def mark_compiled() -> None:
    """Note that the kernels are compiled and cached (:func:`sandmod.world.compile_kernels` does)."""
    try:
        stamp = _stamp()
        stamp.parent.mkdir(parents=True, exist_ok=True)
        stamp.touch()
    except OSError:
        pass  # a read-only cache only costs the message being shown again
