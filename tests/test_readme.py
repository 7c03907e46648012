"""The README's examples are real: its mod and world load, its commands name real files."""

from __future__ import annotations

import re
from pathlib import Path

from sandmod.world.loading import load_ruleset, load_world

ROOT = Path(__file__).parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")


def toml_blocks() -> list[str]:
    return re.findall(r"```toml\n(.*?)```", README, re.S)


def test_the_readme_mod_and_world_load_and_render_a_frame(tmp_path):
    mod = next(b for b in toml_blocks() if "[mod]" in b)
    world = next(b for b in toml_blocks() if "[world]" in b)
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "mud.toml").write_text(mod)
    (tmp_path / "world.toml").write_text(world)
    (tmp_path / "level.png").write_bytes((ROOT / "examples" / "level.png").read_bytes())
    ruleset = load_ruleset(["mud"], [tmp_path / "mods"])
    assert ruleset.elements[ruleset.index("mud")].spec.lifetime.becomes == "sand"
    loaded = load_world(tmp_path / "world.toml")  # it names only sand and water
    assert "mud:mud" not in {e.id for e in loaded.ruleset.elements}
    assert loaded.warnings == []  # its made_with matches the bundled mods
    for _ in range(250):  # past every timeline event
        loaded.world.step()
    assert loaded.world.counts()["water:water"] > 0


def test_the_readme_mod_test_passes(registry, tmp_path):
    from sandmod.rules.modset import find_mods
    from sandmod.jobs.modtests import TestRunner

    test = next(b for b in toml_blocks() if "[[tests]]" in b)
    (tmp_path / "mods").mkdir()
    (tmp_path / "mods" / "readme.toml").write_text('[mod]\nname = "readme"\nrequires = ["sand"]\n\n' + test)
    runner = TestRunner(find_mods(registry, [tmp_path / "mods"]))
    (case,) = runner.cases(["readme"])
    assert runner.run(case).passed


def test_the_readme_commands_use_files_that_exist():
    assert "pip install . && sandmod render examples/hourglass.toml" in README
    assert 'pip install -e ".[test]" && pytest' in README
    for path in re.findall(r"\((examples/[\w.]+|docs/[\w.]+|core/[\w.]+|mods/|plugins/)\)", README):
        assert (ROOT / path).exists(), path
