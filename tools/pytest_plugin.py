"""pytest plugin: the ``[[tests]]`` of every mod in a ``mods/`` folder are pytest items.

Installed with sandmod (entry point ``pytest11``), so a mod author's
repository needs no conftest: ``pytest`` finds ``mods/*.toml`` and runs each
test of each mod as an item named ``mod:test``. A failure shows the file and
line, the scene and the expected and actual grids, without a Python
traceback. ``pytest --pyargs sandmod.mods`` runs the bundled mods' tests.
"""

from __future__ import annotations

from pathlib import Path

import pytest

#: Mod files are collected from folders with this name.
MODS_FOLDER = "mods"

_runners = pytest.StashKey[dict]()


def pytest_configure(config: pytest.Config) -> None:
    config.stash[_runners] = {}


def pytest_collect_file(file_path: Path, parent: pytest.Collector):
    if file_path.suffix == ".toml" and file_path.parent.name == MODS_FOLDER and _looks_like_mod(file_path):
        return ModTestFile.from_parent(parent, path=file_path)
    return None


def pytest_collection_finish(session: pytest.Session) -> None:
    """Compile a new version's kernels before the first mod test, saying so, rather than stall in it."""
    if not any(isinstance(item, ModTestItem) for item in session.items):
        return
    from sandmod.jobs.warmup import compile_new_kernels

    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    say = None if reporter is None else lambda notice: reporter.write_line(f"sandmod: {notice}")
    compile_new_kernels(announce=say, several_threads=True)  # tests run worlds on several threads too


def _looks_like_mod(path: Path) -> bool:
    """Every TOML file in a mods/ folder is a mod, unless it is a world; one that does not even
    parse is collected too, so that its problems fail the run instead of passing unseen."""
    import tomllib

    from sandmod.rules.modset import is_world

    try:
        return not is_world(tomllib.loads(path.read_text(encoding="utf-8")))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):  # ValueError covers TOMLDecodeError
        return True


def _runner_for(config: pytest.Config, folder: Path):
    """A test runner over the bundled mods, the plugins' mods and ``folder``, made once per folder."""
    from sandmod.world.loading import load_registry
    from sandmod.rules.modset import discover_mods
    from sandmod.jobs.modtests import TestRunner

    runners = config.stash[_runners]
    if folder not in runners:
        registry = runners.setdefault(None, load_registry())
        modset, problems = discover_mods(registry, [folder])
        runners[folder] = (TestRunner(modset), problems)
    return runners[folder]


class ModTestFile(pytest.File):
    """A mod file; its items are its tests."""

    def collect(self):
        from sandmod.errors import display_path
        from sandmod.jobs.modtests import TestCase

        runner, problems = _runner_for(self.config, self.path.parent)
        shown = display_path(self.path)
        mine = [str(p) for p in problems if p.file == shown]
        if mine:
            raise self.CollectError("\n".join(mine))
        mod = next((m for m in runner.modset.mods.values() if m.source.path == self.path.resolve()), None)
        if mod is None:
            return  # not loaded: a copy of a mod found elsewhere first (e.g. the bundled folder itself)
        for number, spec in enumerate(mod.spec.tests):
            case = TestCase(mod, number, spec)
            yield ModTestItem.from_parent(self, name=case.id, case=case, runner=runner)


class ModTestFailed(Exception):
    """A mod test's expectations did not hold."""


class ModTestItem(pytest.Item):
    """One ``[[tests]]`` entry of a mod."""

    def __init__(self, *, case, runner, **kwargs):
        super().__init__(**kwargs)
        self.case = case
        self.runner = runner

    def runtest(self) -> None:
        outcome = self.runner.run(self.case)
        if not outcome.passed:
            raise ModTestFailed(outcome.report())

    def repr_failure(self, excinfo, style=None):
        from sandmod.errors import ProblemsError

        if isinstance(excinfo.value, (ModTestFailed, ProblemsError)):
            return str(excinfo.value)
        return super().repr_failure(excinfo, style)

    def reportinfo(self):
        return self.path, (self.case.line or 1) - 1, f"mod test {self.case.id}"
