"""Where compiled kernels are kept, and whether this version's are there yet.

Nothing here imports numba, so commands that do not simulate can ask
without paying for it.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import sys
from importlib import metadata
from pathlib import Path

#: What the commands (and the pytest plugin) say before they compile a new version's kernels.
NOTICE = "compiling the kernel (once per version, about 17 s on two cores)..."

#: The engine package: the files whose code or constants the compiled kernels contain. Numba
#: notices a change to a kernel's own file only (it keeps the values of globals taken from other
#: modules as they were when it compiled), so the cache folder is named after all of them; the
#: engine imports nothing outside itself, so an edit anywhere else compiles nothing anew.

#: How many earlier versions of these sources keep their compiled kernels (about 5 MB each).
KEPT_VERSIONS = 2

SOURCES = Path(__file__).parent


def kernel_sources(folder: Path = SOURCES) -> list[str]:
    """The engine's modules in ``folder``, by name."""
    return sorted(path.name for path in folder.glob("*.py"))


def _setting(folder: Path) -> str:
    """What compiled kernels are good for besides the sources' contents: Python's and numba's
    versions, and where the sources are (numba files its cache by the source's path)."""
    return f"{sys.version_info[:2]} {metadata.version('numba')} {folder.resolve()}"


@functools.cache
def version_hash(folder: Path = SOURCES) -> str:
    """A hash of the kernel sources in ``folder`` and of :func:`_setting`: a version of the kernels."""
    h = hashlib.sha256(_setting(folder).encode())
    for name in kernel_sources(folder):
        h.update((folder / name).read_bytes())
    return h.hexdigest()[:16]


def _versions() -> Path:
    """The folder of the version folders, in the user's cache."""
    base = os.environ.get("XDG_CACHE_HOME") or os.environ.get("LOCALAPPDATA") or Path.home() / ".cache"
    return Path(base) / "sandmod" / "numba"


def kernel_cache_dir() -> Path:
    """Where compiled kernels are kept: ``$NUMBA_CACHE_DIR``, else a folder of the user's cache
    named after :func:`version_hash`, so that a change to any kernel source compiles them anew.

    Not beside the installed package, where numba would put them by default:
    files pip did not install would survive an uninstall there, leaving a
    stray ``sandmod`` folder that shadows a later editable install.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"])
    return _versions() / version_hash()


def _stamp() -> Path:
    """A file that exists once kernels of exactly this code, numba and Python have been compiled."""
    return kernel_cache_dir() / f"compiled-{version_hash()}"


def is_compiled() -> bool:
    """Have this version's kernels been compiled and cached (so a start takes a second, not a minute)?"""
    return _stamp().exists()


_best_step_cached: Path | None = None  # the cache folder where the warm-up's part for the best step is done


def mark_best_step_cached() -> None:
    """Note that the best step (``kernel.step``) is in the cache before the rest is (the warm-up's part
    for it is done): a world on the quick step switches to it (:func:`best_step_cached`)."""
    global _best_step_cached
    _best_step_cached = kernel_cache_dir()


def best_step_cached() -> bool:
    """Is the best step in the cache: this version compiled, or its part done by this process's warm-up?"""
    return _best_step_cached == kernel_cache_dir() or is_compiled()


def mark_compiled() -> None:
    """Note that the kernels are compiled and cached (:func:`sandmod.jobs.warmup.compile_kernels` does),
    and remove the compiled kernels of this copy's older versions."""
    setting = _setting(SOURCES)
    try:
        stamp = _stamp()
        stamp.parent.mkdir(parents=True, exist_ok=True)
        stamp.write_text(setting, encoding="utf-8")
    except OSError:
        return  # a read-only cache only costs the message being shown again
    _forget_earlier_versions(setting)


def _forget_earlier_versions(setting: str) -> None:
    """Remove the version folders beside this one whose stamp names ``setting``, this one's: kernels of
    these sources as they were before an edit or an upgrade. The :data:`KEPT_VERSIONS` last compiled
    stay, so that going back (a branch, an undone edit) does not compile again.

    Other copies of sandmod, and this copy under another Python or numba, keep theirs, and so do
    folders without such a stamp (still compiling, or from before stamps named their setting).
    A folder that numba was told to use (``NUMBA_CACHE_DIR``) is not ours to tidy.
    """
    here = kernel_cache_dir()
    if here != _versions() / version_hash():
        return
    earlier = []
    for other in here.parent.iterdir():
        if other == here or not other.is_dir():
            continue
        stamp = other / f"compiled-{other.name}"
        try:
            if stamp.read_text(encoding="utf-8") == setting:
                earlier.append((stamp.stat().st_mtime, other))
        except (OSError, UnicodeDecodeError):
            continue
    for _, other in sorted(earlier, reverse=True)[KEPT_VERSIONS:]:
        shutil.rmtree(other, ignore_errors=True)
