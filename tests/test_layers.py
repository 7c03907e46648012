"""The import rule of docs/architecture.md: each part of sandmod imports only the parts below it."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: Each part, and the parts it may import (its own modules aside). The pipeline runs
#: formats -> rules -> engine -> passes -> world -> jobs; the engine, at the bottom, imports nothing.
BELOW = {
    "errors": set(),
    "engine": set(),
    "formats": {"engine", "errors"},
    "hooks": {"formats", "errors"},
    "registry": {"hooks", "formats", "errors"},
    "rules": {"registry", "hooks", "formats", "engine", "errors"},
    "passes": {"formats", "engine", "errors"},  # work on the cells after the kernel's step: the world hands it what it needs
    "world": {"passes", "rules", "registry", "hooks", "formats", "engine", "errors"},
    "jobs": {"world", "passes", "rules", "registry", "hooks", "formats", "engine", "errors"},
    "plugins": {"api"},  # the built-in plugins import what a third party's would
}
FOLDERS = {"core": "", "plugins": "plugins"}


def _part(path: Path) -> str:
    """The part a source file belongs to: a package of core/, a top-level module, or the plugins."""
    relative = path.relative_to(ROOT)
    if relative.parts[0] == "plugins":
        return "plugins"
    inside = relative.parts[1:]
    return inside[0] if len(inside) > 1 else inside[0].removesuffix(".py")


def _module_name(path: Path) -> str:
    relative = path.relative_to(ROOT).with_suffix("")
    parts = list(relative.parts)
    parts[0] = "sandmod" if parts[0] == "core" else "sandmod.plugins"
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imported(path: Path) -> set[str]:
    """Every sandmod module a file imports, at its top or inside a function, as an absolute name."""
    here = _module_name(path)
    package = here if path.name == "__init__.py" else here.rsplit(".", 1)[0]
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                module = f"{base}.{node.module}" if node.module else base
            else:
                module = node.module or ""
            names.add(module)
            names |= {f"{module}.{alias.name}" for alias in node.names}  # `from . import kernel` names a module
    return {name for name in names if name.split(".")[0] == "sandmod"}


def _part_of(module: str) -> str | None:
    """The part an absolute module name is in (None: sandmod itself, or not a part)."""
    parts = module.split(".")[1:]
    if not parts:
        return None
    if parts[0] in BELOW or parts[0] == "api":
        return parts[0]
    return None


SOURCES = sorted(p for folder in FOLDERS for p in (ROOT / folder).rglob("*.py") if _part(p) in BELOW)


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(ROOT)))
def test_each_part_imports_only_the_parts_below_it(path: Path):
    part = _part(path)
    wrong = sorted(m for m in _imported(path) if (other := _part_of(m)) not in (None, part) and other not in BELOW[part])
    assert not wrong, f"{part} may import {sorted(BELOW[part]) or 'nothing'} of sandmod, not {wrong}"


def test_the_rule_covers_every_module():
    parts = {_part(p) for folder in FOLDERS for p in (ROOT / folder).rglob("*.py")}
    assert parts - set(BELOW) == {"__init__", "__main__", "api"}  # the public API sits above everything


def test_a_wrong_import_is_caught(tmp_path, monkeypatch):
    engine = ROOT / "core" / "engine" / "kernel.py"
    assert "sandmod.world.world" not in _imported(engine)
    fake = tmp_path / "core" / "engine" / "fake.py"
    fake.parent.mkdir(parents=True)
    fake.write_text("def f():\n    from ..world import world\n", encoding="utf-8")
    monkeypatch.setattr(__import__(__name__), "ROOT", tmp_path)
    assert _part(fake) == "engine" and _part_of("sandmod.world.world") == "world"
    assert "sandmod.world.world" in _imported(fake)
