"""Interaction tests written in mod files: the runner, its report, the pytest plugin, `sandmod test`."""

from __future__ import annotations

import textwrap

import pytest
from click.testing import CliRunner

from sandmod.errors import ProblemsError
from sandmod.rules.modset import find_mods
from sandmod.jobs.modtests import TestRunner
from sandmod.tools.cli import cli

from conftest import write_mods

FIZZ = '''
[mod]
name = "fizz"
requires = ["sand"]

[elements.foam]
archetype = "liquid"
color = "#eeeeff"
density = 900
dispersion = 2

[[reactions]]
a = "foam"
b = "sand"
b_becomes = "foam"
chance = 1.0

[[tests]]
name = "foam_eats_sand"
frames = 3
legend = { F = "foam", S = "sand", "#" = "stone" }
scene = """
#FS#
####
"""
count = { foam = 2, sand = 0 }

[[tests]]
name = "wrong_on_purpose"
frames = 3
legend = { F = "foam", S = "sand", "#" = "stone" }
scene = """
#FS#
####
"""
expect = """
#FS#
####
"""
count = { sand = [1, 5] }
present = ["sand"]
absent = ["foam"]
temperature = { foam = { max = 10 } }
'''


@pytest.fixture()
def fizz_runner(registry, tmp_path):
    return TestRunner(find_mods(registry, [write_mods(tmp_path / "mods", {"fizz.toml": FIZZ})]))


def test_a_passing_test_and_a_failing_one(fizz_runner):
    passing, failing = (fizz_runner.run(case) for case in fizz_runner.cases(["fizz"]))
    assert passing.passed and passing.case.id == "fizz:foam_eats_sand"
    assert not failing.passed
    assert failing.failures == [
        "1 cell differs from expect, the first at row 1, column 3",
        "count of sand: expected 1 to 5, got 0",
        "sand should be present, but there is none",
        "foam should be absent, but there are 2 cells",
        "temperature of foam: expected at most 10, the hottest cell is 20.0",
    ]
    report = failing.report().splitlines()
    assert report[0].endswith("fizz.toml:27: tests.1 (fizz:wrong_on_purpose): after 3 frames, seed 0")
    assert report[1:4] == ["  scene   expected   actual", "  #FS#    #FS#       #FF#  <", "  ####    ####       ####"]
    assert report[-1] == "  key: . base:empty, F fizz:foam, S sand:sand, # base:stone"


def test_every_bundled_mod_carries_tests_that_pass(registry):
    runner = TestRunner(find_mods(registry))
    cases = runner.cases()
    assert {case.mod.name for case in cases} == set(runner.modset.mods)
    failed = [outcome.report() for outcome in map(runner.run, cases) if not outcome.passed]
    assert not failed, "\n".join(failed)


def test_bundled_tests_can_fail(registry, tmp_path):
    """Titanium that acid may eat fails the acid test: the tests check what they say."""
    import dataclasses

    from sandmod.formats.modspec import ModFile
    from sandmod.formats.tomlsource import TomlSource
    from sandmod.formats.validation import validate

    modset = find_mods(registry)
    titanium = modset.mods["titanium"]
    text = titanium.source.text.replace('tags = ["metal", "acid_proof"]', 'tags = ["metal"]')
    source = TomlSource.parse(text, titanium.source.name)
    modset.mods["titanium"] = dataclasses.replace(titanium, spec=validate(ModFile, source), source=source)
    runner = TestRunner(modset)
    (case,) = [c for c in runner.cases(["acid"]) if c.spec.name == "eats_stone_not_titanium"]
    outcome = runner.run(case)
    assert not outcome.passed and outcome.failures[0].startswith("count of titanium: expected 12, got ")


def test_unknown_names_in_a_test_are_problems_with_lines(registry, tmp_path):
    text = FIZZ.replace('legend = { F = "foam", S = "sand", "#" = "stone" }\nscene = """\n#FS#\n####\n"""\ncount', 'legend = { F = "foam", S = "snad", "#" = "stone" }\nscene = """\n#FS#\n####\n"""\ncount', 1)
    runner = TestRunner(find_mods(registry, [write_mods(tmp_path / "mods", {"fizz.toml": text})]))
    with pytest.raises(ProblemsError) as caught:
        runner.run(runner.cases(["fizz"])[0])
    assert [str(p).split("/")[-1] for p in caught.value.problems] == [
        "fizz.toml:20:24: tests.0.legend.S: unknown element 'snad' (did you mean 'sand'?)"
    ]


@pytest.mark.parametrize(
    "change, message",
    [
        ('scene = """\n#FS#\n####\n"""\ncount', 'scene = """\n#FS#\n###\n"""\ncount'),
        ('scene = """\n#FS#\n####\n"""\ncount', 'scene = """\n#FX#\n####\n"""\ncount'),
    ],
)
def test_drawn_rows_that_do_not_fit_name_their_line(registry, tmp_path, change, message):
    folder = write_mods(tmp_path / "mods", {"fizz.toml": FIZZ.replace(change, message, 1)})
    with pytest.raises(ProblemsError) as caught:
        find_mods(registry, [folder])
    (problem,) = caught.value.problems
    assert str(problem).split("/")[-1] in (
        "fizz.toml:23:1: tests.0.scene: row 2 has 3 cells; the scene's first row has 4",
        "fizz.toml:22:1: tests.0.scene: row 1: 'X' not in the legend",
    )


def test_sandmod_test_command(tmp_path, monkeypatch):
    write_mods(tmp_path / "mods", {"fizz.toml": FIZZ})
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(cli, ["test", "fizz"])
    assert result.exit_code == 1
    lines = result.stdout.splitlines()
    assert lines[0] == "fizz:foam_eats_sand ... ok"
    assert lines[1] == "fizz:wrong_on_purpose ... FAILED"
    assert lines[-1].startswith("1 passed, 1 failed in ")
    ok = CliRunner().invoke(cli, ["test", "sand", "water"])
    assert ok.exit_code == 0 and ok.stdout.splitlines()[-1].startswith(f"{ok.stdout.count(' ... ok')} passed, 0 failed")
    missing = CliRunner().invoke(cli, ["test", "nosuch"])
    assert missing.exit_code == 2 and "mod 'nosuch' was not found" in missing.stderr


def test_pytest_collects_mod_tests_without_a_conftest(pytester):
    pytester.makefile(".toml", **{"mods/fizz": textwrap.dedent(FIZZ)})
    result = pytester.runpytest("-v")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(
        [
            "mods/fizz.toml::fizz:foam_eats_sand PASSED*",
            "mods/fizz.toml::fizz:wrong_on_purpose FAILED*",
            "*mods/fizz.toml:27: tests.1 (fizz:wrong_on_purpose): after 3 frames, seed 0",
            "*#FS#    #FS#       #FF#  <",
            "*count of sand: expected 1 to 5, got 0",
        ]
    )
    assert "Traceback" not in result.stdout.str() and "def runtest" not in result.stdout.str()


@pytest.mark.slow  # compiles the kernel anew
def test_pytest_compiles_a_new_versions_kernels_before_the_mod_tests_and_says_so(pytester, monkeypatch):
    from sandmod.engine import kernelcache

    pytester.makefile(".toml", **{"mods/fizz": textwrap.dedent(FIZZ)})
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(pytester.path / "cache"))  # no stamp there: as on a first run
    first = pytester.runpytest_inprocess()
    first.stdout.fnmatch_lines([f"sandmod: {kernelcache.NOTICE}"])
    assert kernelcache.is_compiled()
    again = pytester.runpytest_inprocess()
    assert "compiling" not in again.stdout.str()


def test_pytest_reports_a_broken_mod_file_as_one_clean_error(pytester):
    pytester.makefile(".toml", **{"mods/fizz": textwrap.dedent(FIZZ).replace("density = 900", "density = -1")})
    result = pytester.runpytest()
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(["mods/fizz.toml:8:1: elements.foam.density: must be > 0 (got -1)"])
    assert "Traceback" not in result.stdout.str()
