"""The README's examples are real: its mod and world load, its commands name real files."""

from __future__ import annotations

import re
from pathlib import Path

from sandmod.world.loading import load_ruleset, load_world

ROOT = Path(__file__).parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")


def toml_blocks() -> list[str]:
    return re.findall(r"```toml\n(.*?)```", README, re.S)


def test_the_readme_mod_and_world_load_and_step(tmp_path):
    mod = next(b for b in toml_blocks() if "[mod]" in b)
    world = next(b for b in toml_blocks() if "[world]" in b)
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "mud.toml").write_text(mod)
    (tmp_path / "world.toml").write_text(world)
    ruleset = load_ruleset(["mud"], [tmp_path / "mods"])
    assert ruleset.elements[ruleset.index("mud")].spec.lifetime.becomes == "sand"
    loaded = load_world(tmp_path / "world.toml")  # it names only sand and water
    assert "mud:mud" not in {e.id for e in loaded.ruleset.elements}
    assert loaded.warnings == []
    for _ in range(160):  # past the timeline's event
        loaded.world.step()
    counts = loaded.world.counts()
    assert counts["water:water"] > 0 and counts["sand:sand"] > 0


def test_the_readme_mod_test_passes(registry, tmp_path):
    from sandmod.rules.modset import find_mods
    from sandmod.jobs.modtests import TestRunner

    test = next(b for b in toml_blocks() if "[[tests]]" in b)
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "readme.toml").write_text('[mod]\nname = "readme"\nrequires = ["sand"]\n\n' + test)
    runner = TestRunner(find_mods(registry, [tmp_path / "mods"]))
    (case,) = runner.cases(["readme"])
    assert runner.run(case).passed


def test_the_readme_commands_and_links_name_files_that_exist():
    assert "pip install . && sandmod render examples/hourglass.toml" in README
    assert 'pip install -e ".[test]" && pytest' in README
    links = re.findall(r"\]\(([^)#:]+)\)", README)
    assert len(links) >= 15
    for path in links:
        assert (ROOT / path).exists(), path


def test_the_readme_python_runs_and_prints_what_it_says(monkeypatch, capsys):
    code = next(b for b in re.findall(r"```python\n(.*?)```", README, re.S) if "import sandmod" in b)
    monkeypatch.chdir(ROOT)
    exec(compile(code, "README.md", "exec"), {})
    said = re.search(r"print\(world.counts\(\)\)\s+# (.*)", code).group(1)
    assert capsys.readouterr().out.strip() == said


def test_the_package_docstring_shows_the_counts_its_example_gives():
    import sandmod

    said = re.search(r"world.counts\(\)\s+# (.*)", sandmod.__doc__).group(1)
    assert said == next(b for b in re.findall(r"```python\n(.*?)```", README, re.S) if "import sandmod" in b).split("# ")[-1].strip()


def test_the_readme_says_what_the_mistake_line_says(tmp_path):
    """The README's example of a mistake is what validate prints for it."""
    mod = next(b for b in toml_blocks() if "[mod]" in b).replace("density = 1700 ", "density = -5   ")
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "mud.toml").write_text(mod)
    shown = re.search(r"`(mods/mud.toml:\d+:\d+: [^`]+)`", README).group(1)
    from click.testing import CliRunner

    from sandmod.tools.cli import cli

    result = CliRunner().invoke(cli, ["validate", str(tmp_path / "mods")])
    assert result.exit_code == 2 and shown.replace("mods/", f"{tmp_path}/mods/") in result.output
