"""Fuzzing: mutated mods, worlds and snapshots through validate, render and the snapshot loader.

Whatever the mutation, the command ends with exit 0 or 2, never a traceback,
and leaves nothing but its finished outputs behind. Bounded in examples and
derandomized, so CI runs the same cases in about a minute.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import invoke

EXAMPLES = Path(__file__).parent.parent / "examples"
MOD = """
[mod]
name = "fuzzed"
version = "1.0.0"
requires = ["water"]

[elements.goo]
archetype = "liquid"
density = 1.2
dispersion = 3
color = ["#44aa33", "#3d9a2e"]
description = "Green and slow."
viscosity = 0.5

[[reactions]]
a = "goo"
b = "water:water"
a_becomes = "sand"
chance = 0.1

[[tests]]
name = "goo sinks"
frames = 10
scene = '''
.G.
.W.
'''
legend = { G = "goo", W = "water" }
expect = { cells = '''
.?.
.?.
''' }
"""
WORLD = (EXAMPLES / "hourglass.toml").read_text()
VALUES = ["-1", "0", "2147483648", "9223372036854775808", "1e308", "-1000000000000", "3.5", '"x"', "[1, 2]", "{ a = 1 }",
          "true", "nan", '"\\u001b[2J"', '"../../etc/passwd"', '"/dev/zero"']
META_VALUES = ["-5", "1e30", '"x"', "[]", "{}", "null", "99999999999999999999"]
KEYS = ["x", "y", "width", "height", "radius", "frames", "element", "shape", "file", "output", "density", "archetype",
        "mods", "requires", "name", "version", "legend", "points", "from", "to", "at", "seed", "crop", "scale"]

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


@st.composite
def mutated(draw, text: str) -> str:
    """``text`` with a few of: a value, a key or a line replaced, a line dropped or doubled, junk inserted."""
    for _ in range(draw(st.integers(1, 4))):
        lines = text.splitlines()
        number = draw(st.integers(0, len(lines) - 1))
        kind = draw(st.sampled_from(["value", "key", "drop", "double", "junk"]))
        line = lines[number]
        if kind == "value" and "=" in line:
            lines[number] = line.split("=", 1)[0] + "= " + draw(st.sampled_from(VALUES))
        elif kind == "key" and "=" in line:
            lines[number] = draw(st.sampled_from(KEYS)) + " =" + line.split("=", 1)[1]
        elif kind == "drop":
            del lines[number]
        elif kind == "double":
            lines.insert(number, line)
        else:
            at = draw(st.integers(0, len(line)))
            lines[number] = line[:at] + draw(st.text(max_size=12)) + line[at:]
        text = "\n".join(lines) + "\n"
    return text


def _finished_only(*expected: str) -> None:
    left = {p.name for p in Path(".").iterdir()}
    assert not [name for name in left if name.endswith((".part", ".old"))], left
    assert left <= set(expected), left


def _clean_exit(result) -> None:
    assert result.exit_code in (0, 2), result.output
    assert "Traceback" not in result.output


@pytest.mark.slow  # 40 files, over ten seconds
@SETTINGS
@given(text=mutated(MOD))
def test_mutated_mods_validate_cleanly(text):
    Path("mods").mkdir(exist_ok=True)
    Path("mods/fuzzed.toml").write_text(text, encoding="utf-8", errors="surrogatepass")
    _clean_exit(invoke("validate", "mods"))
    _finished_only("mods")


@pytest.mark.slow  # 40 files, over ten seconds
@SETTINGS
@given(text=mutated(WORLD))
def test_mutated_worlds_validate_and_render_cleanly(text):
    Path("w.toml").write_text(text, encoding="utf-8", errors="surrogatepass")
    _clean_exit(invoke("validate", "w.toml"))
    result = invoke("render", "w.toml", "--frames", "3", "-q", "-o", "out.gif", "--max-memory", "1G")
    _clean_exit(result)
    assert Path("out.gif").exists() == (result.exit_code == 0)
    _finished_only("w.toml", "out.gif")
    Path("out.gif").unlink(missing_ok=True)


@pytest.fixture(scope="module")
def snapshot_bytes(tmp_path_factory) -> bytes:
    folder = tmp_path_factory.mktemp("snapshot")
    (folder / "w.toml").write_text(WORLD)
    result = invoke("render", str(folder / "w.toml"), "--frames", "5", "-q", "-o", str(folder / "a.gif"),
                    "--save-snapshot", str(folder / "s.npz"))
    assert result.exit_code == 0
    return (folder / "s.npz").read_bytes()


@SETTINGS
@given(data=st.data())
def test_mutated_snapshots_load_cleanly(snapshot_bytes, data):
    raw = bytearray(snapshot_bytes)
    if data.draw(st.booleans()):  # bytes flipped or cut anywhere
        for _ in range(data.draw(st.integers(1, 8))):
            raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
        raw = raw[: data.draw(st.integers(0, len(raw)))]
        Path("s.npz").write_bytes(bytes(raw))
    else:  # a well-formed archive whose description or arrays are wrong
        Path("good.npz").write_bytes(snapshot_bytes)
        arrays = dict(np.load("good.npz"))
        Path("good.npz").unlink()
        meta = arrays["meta"].item()
        key = data.draw(st.sampled_from(["frame", "seed", "width", "height", "format", "elements", "mods"]))
        value = data.draw(st.sampled_from(META_VALUES))
        meta = re.sub(rf'"{key}": [^,}}]+', f'"{key}": {value}', meta, count=1)
        arrays["meta"] = np.array(meta)
        name = data.draw(st.sampled_from(sorted(arrays)))
        if name != "meta" and data.draw(st.booleans()):
            arrays[name] = arrays[name].astype(data.draw(st.sampled_from([np.float64, np.int8, np.uint32])))[..., : data.draw(st.integers(0, 3))]
        np.savez_compressed("s.npz", **arrays)
    Path("w.toml").write_text(WORLD)
    result = invoke("render", "w.toml", "--frames", "2", "-q", "-o", "out.gif", "--from-snapshot", "s.npz")
    _clean_exit(result)
    _finished_only("w.toml", "s.npz", "out.gif")
    Path("out.gif").unlink(missing_ok=True)


SWEEP_WORLD = """
[world]
width = 24
height = 20
mods = ["sand"]

[[scene]]
shape = "rect"
element = "stone"
x = 0
y = 17
width = 24
height = 3

[[emitters]]
shape = "rect"
element = "sand"
x = 10
y = 0
width = 4
height = 1
stop = 10

[render]
frames = 20
"""
SWEEP = """
[sweep]
worlds = ["*.toml"]
seeds = [0, 1]
frames = 12

[parameters]
"elements.sand.friction" = [0.3, 1.2]
"world.gravity" = [1.0, 0.5]
"render.scale" = [1, 2]

[record]
format = "gif"
snapshots = [6]

[metrics]
frames = [6, 12]
names = ["counts", "extent"]
"""


@pytest.mark.slow  # 40 files, over ten seconds
@SETTINGS
@given(text=mutated(SWEEP))
def test_mutated_sweeps_are_refused_before_any_run_or_run_whole(text):
    shutil.rmtree("out", ignore_errors=True)
    Path("worlds").mkdir(exist_ok=True)
    Path("worlds/heap.toml").write_text(SWEEP_WORLD)
    Path("worlds/sweep.toml").write_text(text, encoding="utf-8", errors="surrogatepass")
    checked = invoke("validate", "worlds/sweep.toml")
    _clean_exit(checked)
    planned = invoke("batch", "worlds/sweep.toml", "--dry-run")
    _clean_exit(planned)
    assert (planned.exit_code == 0) == (checked.exit_code == 0), (checked.output, planned.output)
    if planned.exit_code == 0 and int(planned.output.split()[-2]) <= 16:
        result = invoke("batch", "worlds/sweep.toml", "-o", "out", "-j", "1", "-q")
        assert result.exit_code == 0, result.output  # a sweep that passed its checks has no run fail
    _finished_only("worlds", "out")
