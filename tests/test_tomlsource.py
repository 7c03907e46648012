"""Key positions in TOML text, so problems can name their line."""

from __future__ import annotations

from sandmod.formats.tomlsource import TomlSource, index_lines

TEXT = '''\
# a comment
[mod]
name = "m"
description = """
fake = 1
"""

[elements.lava]
archetype = "liquid"
lifetime = { frames = 3, becomes = "stone" }

[elements."odd name"]
color.main = "#fff"

[[reactions]]
a = "x"

[[reactions]]
a = "y"
chance = 0.5
'''


def test_index_maps_headers_keys_and_array_entries():
    lines = index_lines(TEXT)
    assert lines[("mod",)] == 2
    assert lines[("mod", "description")] == 4
    assert ("fake",) not in lines and ("mod", "fake") not in lines  # inside a multi-line string
    assert lines[("elements", "lava")] == 8
    assert lines[("elements", "lava", "lifetime")] == 10
    assert lines[("elements", "odd name", "color", "main")] == 13
    assert lines[("reactions", 0, "a")] == 16
    assert lines[("reactions", 1)] == 18
    assert lines[("reactions", 1, "chance")] == 20


def test_line_of_falls_back_to_the_nearest_written_parent():
    source = TomlSource.parse(TEXT, "t.toml")
    assert source.line_of(("elements", "lava", "lifetime", "frames")) == 10
    assert source.line_of(("elements", "lava", "density")) == 8
    assert source.line_of(("nowhere",)) is None
    assert str(source.problem(("reactions", 1, "b"), "missing")) == "t.toml:18:1: reactions.1.b: missing"


def test_unreadable_file_is_a_problem_not_a_traceback(tmp_path):
    import pytest

    from sandmod.errors import ProblemsError

    with pytest.raises(ProblemsError) as caught:
        TomlSource.read(tmp_path / "absent.toml")
    assert "cannot read file" in str(caught.value)


def test_a_dotted_header_also_opens_its_parents():
    lines = index_lines("[mod]\n\n[elements.sand]\nx = 1\n")
    assert lines[("elements",)] == 3 and lines[("elements", "sand", "x")] == 4
