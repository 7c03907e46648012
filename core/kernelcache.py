"""Where compiled kernels are kept, and whether this version's are there yet.

Nothing here imports numba, so commands that do not simulate can ask
without paying for it.
"""

from __future__ import annotations

import hashlib
import os
import sys
from importlib import metadata
from pathlib import Path

#: What the commands (and the pytest plugin) say before they compile a new version's kernels.
NOTICE = "compiling the kernel (once per version, about a minute)..."

# The files whose code or constants the compiled kernels contain.
_KERNEL_SOURCES = ("kernel.py", "hashing.py", "traversal.py", "world.py", "compiler.py")


def kernel_cache_dir() -> Path:
    """Where compiled kernels are kept: ``$NUMBA_CACHE_DIR``, else the user's cache folder.

    Not beside the installed package, where numba would put them by default:
    files pip did not install would survive an uninstall there, leaving a
    stray ``sandmod`` folder that shadows a later editable install.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.environ.get("LOCALAPPDATA") or Path.home() / ".cache"
    return Path(base) / "sandmod" / "numba"


def _stamp() -> Path:
    """A file that exists once kernels of exactly this code, numba and Python have been compiled."""
    h = hashlib.sha256(f"{sys.version_info[:2]} {metadata.version('numba')}".encode())
    here = Path(__file__).parent
    for name in _KERNEL_SOURCES:
        h.update((here / name).read_bytes())
    return kernel_cache_dir() / f"compiled-{h.hexdigest()[:16]}"


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
