"""Where compiled kernels are kept: a folder per version of the kernel's sources."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from sandmod.engine import kernelcache

CORE = Path(kernelcache.__file__).parent


def test_the_version_covers_every_module_of_the_engine():
    """Numba keeps globals from other modules as they were when it compiled: each must be hashed."""
    assert set(kernelcache.kernel_sources()) == {path.name for path in CORE.glob("*.py")}
    assert "kernel.py" in kernelcache.kernel_sources()


def test_a_change_to_any_kernel_source_or_their_place_is_another_version(tmp_path):
    for name in kernelcache.kernel_sources():
        shutil.copy(CORE / name, tmp_path / name)
    assert kernelcache.version_hash(tmp_path) != kernelcache.version_hash()  # the same sources elsewhere
    seen = {kernelcache.version_hash(tmp_path)}
    for name in kernelcache.kernel_sources():
        copy = tmp_path / name
        original = copy.read_bytes()
        copy.write_bytes(original + b"\n# edited\n")
        kernelcache.version_hash.cache_clear()
        seen.add(kernelcache.version_hash(tmp_path))
        copy.write_bytes(original)
    assert len(seen) == len(kernelcache.kernel_sources()) + 1


def test_kernels_are_kept_in_a_folder_of_their_version_unless_numba_is_told_where(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert kernelcache.kernel_cache_dir() == tmp_path / "sandmod" / "numba" / kernelcache.version_hash()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    assert kernelcache.kernel_cache_dir() == tmp_path / "mine"


def test_compiling_removes_the_kernels_of_this_copys_older_versions_only(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    versions = tmp_path / "sandmod" / "numba"
    current = kernelcache.version_hash()
    earlier = ["0" * 16, "4" * 16, "5" * 16]  # compiled in this order, before edits
    for age, version in enumerate(earlier):
        with monkeypatch.context() as before_an_edit:
            before_an_edit.setattr(kernelcache, "version_hash", lambda folder=kernelcache.SOURCES: version)
            kernelcache.mark_compiled()
        (versions / version / "kernel.step.nbi").write_bytes(b"compiled code")
        os.utime(versions / version / f"compiled-{version}", (1_000_000 + age, 1_000_000 + age))
    other_copy = versions / ("1" * 16)  # another checkout, or this one under another numba
    other_copy.mkdir()
    (other_copy / f"compiled-{'1' * 16}").write_text("(3, 11) 0.1.0 /elsewhere/core", encoding="utf-8")
    compiling = versions / ("2" * 16)  # no stamp yet
    compiling.mkdir()
    unmarked = versions / ("3" * 16)  # stamped before stamps named their setting
    unmarked.mkdir()
    (unmarked / f"compiled-{'3' * 16}").touch()

    kernelcache.mark_compiled()

    assert kernelcache.is_compiled() and kernelcache.KEPT_VERSIONS == 2
    kept = [current, "1" * 16, "2" * 16, "3" * 16, "4" * 16, "5" * 16]  # the oldest of this copy's went
    assert sorted(p.name for p in versions.iterdir()) == sorted(kept)


def test_a_cache_folder_numba_was_told_to_use_is_left_as_it_is(tmp_path, monkeypatch):
    with monkeypatch.context() as before_an_edit:
        before_an_edit.setattr(kernelcache, "version_hash", lambda folder=kernelcache.SOURCES: "0" * 16)
        before_an_edit.setenv("NUMBA_CACHE_DIR", str(tmp_path / ("0" * 16)))
        kernelcache.mark_compiled()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    kernelcache.mark_compiled()
    assert kernelcache.is_compiled() and (tmp_path / ("0" * 16) / f"compiled-{'0' * 16}").exists()
