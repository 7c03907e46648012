"""A world, mod or snapshot from a stranger: confined, bounded, and every bad input a clean line."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from conftest import invoke, wait_for
from sandmod.formats.limits import BASELINE_BYTES, WORLD_BYTES_PER_CELL

SMALL = """
[world]
width = 32
height = 32
mods = ["sand"]

[[emitters]]
shape = "rect"
element = "sand"
x = 14
y = 0
width = 4
height = 2
"""


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def world(text: str = SMALL, name: str = "w.toml", folder: Path = Path(".")) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(text)
    return path


def everything(folder: Path = Path(".")) -> set[str]:
    return {str(p) for p in folder.rglob("*")}


def refused(result, *pieces: str) -> str:
    """The one line a refused command printed, checked for ``pieces``."""
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.stderr
    for piece in pieces:
        assert piece in result.stderr, result.stderr
    return result.stderr


# -- confinement ------------------------------------------------------------------------------


@pytest.mark.parametrize("output", ["../out.gif", "/tmp/sandmod-test-out.gif", "sub/../../out.gif"])
def test_a_world_file_cannot_render_outside_its_folder(output):
    path = world(SMALL + f'\n[render]\nframes = 2\noutput = "{output}"\n', folder=Path("home"))
    before = everything(Path(".."))
    refused(invoke("render", str(path)), "home/w.toml:", "render.output: the output must")
    assert everything(Path("..")) == before and not Path("/tmp/sandmod-test-out.gif").exists()


def test_a_world_file_cannot_render_over_itself_its_pictures_or_through_a_link(tmp_path):
    Image.new("RGB", (4, 4), "#ff0000").save("level.png")
    picture = '\n[[scene]]\nshape = "image"\nfile = "level.png"\nlegend = { "#ff0000" = "sand" }\n'
    for output in ("w.toml", "level.png"):
        world(SMALL + picture + f'\n[render]\nframes = 2\nformat = "apng"\noutput = "{output}"\n')
        refused(invoke("render", "w.toml"), "will not write here")
    outside = tmp_path.parent / f"{tmp_path.name}-outside.gif"
    Path("link.gif").symlink_to(outside)
    world(SMALL + '\n[render]\nframes = 2\noutput = "link.gif"\n')
    refused(invoke("render", "w.toml"), "render.output: the output must lie inside")
    refused(invoke("render", "w.toml", "-o", "link.gif"), "is a symlink")
    assert not outside.exists() and Image.open("level.png").size == (4, 4)


@pytest.mark.parametrize("file", ["../secret.png", "/etc/hostname", "link.png"])
def test_a_world_file_cannot_read_a_picture_outside_its_folder(file):
    Image.new("RGB", (4, 4), "#ff0000").save("secret.png")
    Path("home").mkdir()
    Path("home/link.png").symlink_to(Path("secret.png").resolve())
    picture = f'\n[[scene]]\nshape = "image"\nfile = "{file}"\nlegend = {{ "#ff0000" = "sand" }}\n'
    path = world(SMALL + picture, folder=Path("home"))
    refused(invoke("validate", str(path)), "scene.0.file: the picture must")


GOO = '[mod]\nname = "goo"\n\n[elements.goo]\narchetype = "liquid"\ncolor = "#00ff00"\ndensity = 900\ndispersion = 2\n'


@pytest.mark.parametrize("folder, says", [
    ("../secret-mods", "the mods folder must lie inside the world file's folder"),
    ("/tmp", "the mods folder must be relative to the world file's folder (got an absolute path)"),
    ("link", "the mods folder must lie inside the world file's folder"),
    ("missing", "no folder 'missing' in home"),
])
def test_a_world_file_reads_mods_only_from_folders_inside_its_own(folder, says):
    Path("secret-mods").mkdir()
    Path("secret-mods/goo.toml").write_text(GOO)
    Path("home").mkdir()
    Path("home/link").symlink_to(Path("secret-mods").resolve())
    path = world(SMALL.replace('mods = ["sand"]', f'mods = ["sand", "goo"]\nmod_folders = ["{folder}"]'), folder=Path("home"))
    message = refused(invoke("render", str(path), "-q"), f"home/w.toml:6:1: world.mod_folders.0: {says}")
    assert message.count("\n") == 1 and not Path("w.gif").exists()
    Path("home/mine").mkdir()
    Path("home/mine/goo.toml").write_text(GOO)
    path.write_text(path.read_text().replace(f'"{folder}"', '"mine"'))
    assert invoke("render", str(path), "-q", "--frames", "2").exit_code == 0  # inside: read


def test_a_symlinked_world_takes_its_pictures_and_output_from_the_links_folder():
    picture = '\n[[scene]]\nshape = "image"\nfile = "level.png"\nlegend = { "#ff0000" = "sand" }\n'
    world(SMALL + picture + '\n[render]\nframes = 2\noutput = "out.gif"\n', folder=Path("elsewhere"))
    Image.new("RGB", (4, 4), "#ff0000").save("elsewhere/level.png")
    Path("w.toml").symlink_to(Path("elsewhere/w.toml").resolve())
    refused(invoke("render", "w.toml", "-q"), "no such image: level.png")  # not the link target's picture
    Image.new("RGB", (4, 4), "#ff0000").save("level.png")
    assert invoke("render", "w.toml", "-q").exit_code == 0
    assert Path("out.gif").exists() and not Path("elsewhere/out.gif").exists()


# -- special files, parsers, escapes ----------------------------------------------------------


def test_special_files_and_symlink_loops_are_refused_at_once():
    os.mkfifo("fifo.toml")
    Path("a.toml").symlink_to("b.toml")
    Path("b.toml").symlink_to("a.toml")
    for path, why in (("/dev/zero", "not a regular file"), ("fifo.toml", "not a regular file"), ("a.toml", "a symlink loop")):
        refused(invoke("validate", path), f"cannot read file: {why}")
        refused(invoke("render", path), f"cannot read file: {why}")


def test_toml_the_parser_cannot_take_is_a_problem_line():
    world("a = " + "[" * 600 + "]" * 600 + "\n", "deep.toml")
    world("a = " + "9" * 5000 + "\n", "long.toml")
    refused(invoke("validate", "deep.toml"), "deep.toml: invalid TOML: arrays or tables nested too deeply")
    refused(invoke("validate", "long.toml"), "long.toml: invalid TOML: a number too long to read")


def test_escape_sequences_in_files_are_shown_escaped(tmp_path):
    world(SMALL + '\n"\\u001b]0;owned\\u0007" = 1\n')
    out = refused(invoke("validate", "w.toml"), "\\x1b]0;owned\\x07")
    assert "\x1b" not in out and "\x07" not in out
    mods = tmp_path / "mods"
    mods.mkdir()
    (mods / "evil.toml").write_text(
        '[mod]\nname = "evil"\nversion = "1.0.0"\n[elements.evil]\narchetype = "static"\ncolor = "#123456"\n'
        'description = "\\u001b[2J\\u001b]0;owned\\u0007 hi"\n'
    )
    listed = invoke("list", "--mods", str(mods))
    assert listed.exit_code == 0 and "\x1b" not in listed.output and "\\x1b[2J" in listed.output


def test_field_paths_never_hold_pydantics_labels():
    world(SMALL + '\n[[scene]]\nshape = "image"\nfile = "x.png"\nlegend = { "#ff0000" = { a = 1 } }\n')
    out = refused(invoke("validate", "w.toml"), "scene.0.legend.#ff0000: must be a valid string")
    assert "constrained" not in out and "str" not in out.split(":")[3]


# -- resources --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "shape",
    [
        'shape = "circle"\nelement = "sand"\nx = 100000000000000000000\ny = 1\nradius = 3',
        'shape = "circle"\nelement = "sand"\nx = 4294967296\ny = 4294967296\nradius = 3',
        'shape = "line"\nelement = "sand"\nfrom = [0, 0]\nto = [9223372036854775807, 5]',
        'shape = "image"\nfile = "x.png"\nx = -1000000000000\nlegend = { "#ff0000" = "sand" }',
    ],
)
def test_coordinates_are_bounded(shape):
    world(SMALL + f"\n[[scene]]\n{shape}\n")
    started = time.perf_counter()
    refused(invoke("validate", "w.toml"), "must be")
    assert time.perf_counter() - started < 60  # not drawn cell by cell (hours), on however busy a machine


def test_a_world_larger_than_the_memory_limit_is_refused_before_it_is_made():
    world(SMALL.replace("width = 32", "width = 16384").replace("height = 32", "height = 16384"))
    refused(invoke("render", "w.toml"), "world: a 16384x16384 world would take about", "raise it with --max-memory")
    assert everything() == {"w.toml"}


def test_renders_that_would_keep_too_many_images_or_too_large_ones_are_refused_before_they_run():
    world()
    refused(invoke("render", "w.toml", "--frames", "100000", "--scale", "16", "-o", "a.webp"), "a.webp: webp keeping 50001 images")
    tight = f"{(BASELINE_BYTES >> 20) + 4}M"  # room for the world and one frame, not for six kept
    refused(invoke("render", "w.toml", "--frames", "10", "--scale", "16", "-o", "b.webp", "--max-memory", tight), "b.webp: webp keeping 6 images")
    assert invoke("render", "w.toml", "--frames", "10", "--scale", "16", "-o", "b.gif", "--max-memory", tight).exit_code == 0  # streamed
    Path("b.gif").unlink()
    world(SMALL.replace("width = 32", "width = 4096"))
    refused(invoke("render", "w.toml", "--frames", "2", "--scale", "16"), "gif images are at most 65535 pixels a side")
    refused(invoke("render", "w.toml", "--frames", "2", "--scale", "4", "-o", "w.webp"), "webp images are at most 16383")
    assert everything() == {"w.toml"}


def test_a_picture_with_more_pixels_than_the_limit_allows_is_refused_from_its_header():
    Image.new("P", (2500, 2500)).save("big.png")
    world(SMALL + '\n[[scene]]\nshape = "image"\nfile = "big.png"\nmatch = "nearest"\nlegend = { "#000000" = "sand" }\n')
    limit = f"{(BASELINE_BYTES >> 20) + 300}M"  # the picture would take 2500 x 2500 x 72 bytes: 430 MB
    refused(invoke("render", "w.toml", "--max-memory", limit), "big.png has more pixels than the memory limit allows")


def test_timeline_paintings_keep_only_their_own_box():
    from sandmod.world.loading import load_world

    events = "".join(
        f'\n[[timeline]]\nframe = {i}\npaint = {{ shape = "rect", element = "sand", x = {i % 1000}, y = 10, width = 3, height = 3 }}\n'
        for i in range(3000)
    )
    world(SMALL.replace("width = 32", "width = 1024").replace("height = 32", "height = 1024") + events)
    loaded = load_world("w.toml")
    kept = loaded.memory.used - BASELINE_BYTES - 1024 * 1024 * WORLD_BYTES_PER_CELL
    assert kept < 300 * 2**20  # a whole-world mask each would be 3 GB


# -- snapshots --------------------------------------------------------------------------------


@pytest.fixture()
def snapshot():
    world()
    assert invoke("render", "w.toml", "--frames", "3", "-q", "-o", "a.gif", "--save-snapshot", "good.npz").exit_code == 0
    return dict(np.load("good.npz"))


def _save(name, arrays, **meta):
    arrays = dict(arrays)
    if meta:
        arrays["meta"] = np.array(json.dumps({**json.loads(str(arrays["meta"])), **meta}))
    np.savez_compressed(name, **arrays)


def test_bad_snapshots_are_clean_problems(snapshot):
    Path("empty.npz").write_bytes(b"")
    good = Path("good.npz").read_bytes()
    Path("corrupt.npz").write_bytes(good[:200] + bytes(100) + good[300:])
    _save("frame.npz", snapshot, frame="x")
    _save("huge_frame.npz", snapshot, frame=2**70)
    _save("negative.npz", snapshot, frame=-5)
    _save("awake.npz", {**snapshot, "awake": np.zeros((3, 3), np.uint16)})
    _save("heat.npz", {**snapshot, "heat": np.zeros(2**22, np.int32)})
    np.save("lone.npy", np.zeros(3))
    for name in ("empty.npz", "corrupt.npz", "frame.npz", "huge_frame.npz", "negative.npz", "awake.npz", "heat.npz", "lone.npy"):
        refused(invoke("render", "w.toml", "--frames", "2", "-o", "out.gif", "--from-snapshot", name), f"{name}: ")
    assert not Path("out.gif").exists()


def test_a_snapshot_member_claiming_a_huge_shape_or_a_deep_description_is_a_clean_problem(snapshot):
    # A .npy header may claim 2**40 cells in a member of a few bytes: refused before numpy allocates it.
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<u2", "fortran_order": False, "shape": (2**20, 2**20)})
    with zipfile.ZipFile("claims.npz", "w") as archive:
        for key, array in snapshot.items():
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, array, allow_pickle=False)
            archive.writestr(f"{key}.npy", header.getvalue() if key == "cells" else buffer.getvalue())
    deep = np.array("[" * 2000 + "]" * 2000)  # json.loads would recurse 2,000 deep
    np.savez_compressed("deep.npz", **{**snapshot, "meta": deep})
    for name in ("claims.npz", "deep.npz"):
        refused(invoke("render", "w.toml", "--frames", "2", "-o", "out.gif", "--from-snapshot", name), f"{name}: ")
    assert not Path("out.gif").exists()


def test_a_snapshot_with_a_negative_heat_capacity_keeps_the_temperatures_as_stored(snapshot):
    _save("caps.npz", {**snapshot, "heat_cap": -np.abs(snapshot["heat_cap"]) - 1})
    assert invoke("render", "w.toml", "--frames", "2", "-q", "-o", "out.gif", "--from-snapshot", "caps.npz").exit_code == 0


# -- faults -----------------------------------------------------------------------------------


def test_an_unwritable_snapshot_leaves_no_animation_and_a_failed_still_is_named():
    world()
    Path("blocker").write_text("a file where a folder should be")
    refused(invoke("render", "w.toml", "--frames", "2", "-o", "out.gif", "--save-snapshot", "blocker/s.npz"), "blocker/s.npz: cannot write")
    refused(invoke("render", "w.toml", "--frames", "2", "-o", "out.gif", "--still", "blocker/s.png"), "blocker/s.png: cannot write")
    assert everything() == {"w.toml", "blocker"}


def test_a_folder_output_is_not_replaced_when_a_file_was_added_to_it_meanwhile():
    from sandmod.formats.recording import atomic_folder

    Path("frames").mkdir()
    Path("frames/frame_00000.png").write_bytes(b"old")
    with pytest.raises(FileExistsError):
        with atomic_folder(Path("frames"), "frame_*.png") as tmp:
            (tmp / "frame_00000.png").write_bytes(b"new")
            Path("frames/notes.txt").write_text("mine")
    assert Path("frames/notes.txt").read_text() == "mine" and everything() == {"frames", "frames/notes.txt", "frames/frame_00000.png"}


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_leave_nothing_behind(signum):
    world(SMALL.replace("width = 32", "width = 256").replace("height = 32", "height = 256"))
    args = ["render", "w.toml", "--frames", "100000", "--every", "1", "--scale", "1", "-o", "out.gif", "--still", "s.png"]
    process = subprocess.Popen([sys.executable, "-m", "sandmod", *args], stderr=subprocess.PIPE, text=True)
    wait_for(lambda: list(Path(".").glob(".s.png.*.part")), process)  # the last temporary, made before the frames
    time.sleep(0.5)  # and on into the frames: the signal may land anywhere, this only makes the frames likelier
    process.send_signal(signum)
    assert process.wait(60) == 128 + signum
    assert everything() == {"w.toml"}, process.stderr.read()


def test_what_a_killed_run_left_is_removed_by_the_next_run_on_the_same_output():
    world()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    pid = int(dead.stdout)
    Path(f".out.gif.{pid}.abc.part").write_bytes(b"half")
    Path(f".other.gif.{pid}.abc.part").write_bytes(b"someone else's output")
    Path(f".out.gif.{os.getpid()}.abc.part").write_bytes(b"a live process's")
    assert invoke("render", "w.toml", "--frames", "2", "-q", "-o", "out.gif").exit_code == 0
    assert everything() == {"w.toml", "out.gif", f".other.gif.{pid}.abc.part", f".out.gif.{os.getpid()}.abc.part"}


# -- rough edges ------------------------------------------------------------------------------


def test_a_new_world_with_a_mod_that_is_not_there_is_an_error():
    result = invoke("new", "world", "w2", "--mod", "kerosen")
    assert result.exit_code == 2 and "no mod called 'kerosen'" in result.stderr and not Path("w2.toml").exists()


def test_validate_names_a_broken_mods_requires_in_the_same_pass():
    Path("mods").mkdir()
    Path("mods/kero.toml").write_text(
        '[mod]\nname = "kero"\nversion = "1.0.0"\nrequires = ["nothere"]\n'
        '[elements.kero]\narchetype = "liquid"\ndispersion = 3\ndensity = -1\ncolor = "#112233"\n'
    )
    out = refused(invoke("validate", "mods"), "elements.kero.density: must be > 0", "mod.requires.0: requires mod 'nothere', which was not found")
    assert len(out.splitlines()) == 2


def test_an_element_of_a_mod_the_world_does_not_load_names_that_mod():
    world(SMALL.replace('element = "sand"', 'element = "water"'))
    refused(invoke("validate", "w.toml"), "unknown element 'water'; mod 'water' has it: add \"water\" to [world] mods")


def test_the_summary_counts_the_distinct_images():
    world(SMALL.replace('[[emitters]]', '[[scene]]'))  # a few grains fall, then nothing moves
    result = invoke("render", "w.toml", "--frames", "80", "--every", "2", "-o", "out.gif")
    assert result.exit_code == 0 and "41 images (" in result.output and " distinct)" in result.output
