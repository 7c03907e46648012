"""The command line end to end: real GIFs, listings, validation, errors, drop-in mods."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageSequence

from conftest import invoke, write_mods

EXAMPLES = Path(__file__).parent.parent / "examples"

POURING = """
[world]
width = 40
height = 30
seed = 4

[[scene]]
shape = "rect"
element = "stone"
x = 0
y = 27
width = 40
height = 3

[[emitters]]
shape = "rect"
element = "{element}"
x = 18
y = 0
width = 4
height = 1
chance = 1.0

[render]
frames = 36
every = 4
scale = 2
fps = 10
"""


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def palette_colours(path: Path) -> set[tuple[int, int, int]]:
    with Image.open(path) as im:
        return {px for frame in ImageSequence.Iterator(im) for _, px in frame.convert("RGB").getcolors(1 << 16)}


def test_render_writes_a_gif_with_every_image(tmp_path):
    Path("pour.toml").write_text(POURING.format(element="sand"))
    result = invoke("render", "pour.toml", "-o", "out.gif")
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("wrote out.gif: 10 images of 80x60 from 36 frames")
    with Image.open("out.gif") as im:
        assert im.format == "GIF" and im.size == (80, 60)
        assert im.n_frames == 10  # the first image and one every 4 of 36 frames: all differ
        assert im.info["duration"] == 100 and im.info["loop"] == 0
        last = [frame.convert("RGB") for frame in ImageSequence.Iterator(im)][-1]
    sand = {(0xDC, 0xC3, 0x8A), (0xD2, 0xB4, 0x78), (0xE4, 0xCF, 0x9C)}
    near_sand = lambda c: any(sum(abs(a - b) for a, b in zip(c, s)) < 60 for s in sand)  # noqa: E731
    assert near_sand(last.getpixel((40, 50)))  # grains have landed in the middle of the floor
    assert not near_sand(last.getpixel((2, 2)))  # and not in the top-left corner


def test_render_options_override_the_world_file():
    Path("pour.toml").write_text(POURING.format(element="water"))
    result = invoke("render", "pour.toml", "--frames", "6", "--every", "2", "--scale", "1", "--seed", "9")
    assert result.exit_code == 0, result.output
    with Image.open("pour.gif") as im:
        assert im.size == (40, 30) and im.n_frames == 4


def test_same_seed_renders_the_same_file_twice():
    Path("pour.toml").write_text(POURING.format(element="water"))
    invoke("render", "pour.toml", "-o", "a.gif")
    invoke("render", "pour.toml", "-o", "b.gif")
    assert Path("a.gif").read_bytes() == Path("b.gif").read_bytes()


def test_render_threads_change_nothing_but_speed():
    import numba

    world = str(EXAMPLES / "forest_fire.toml")  # eight tiles, burning across its width
    for count in ("1", str(min(2, numba.config.NUMBA_NUM_THREADS)), "auto"):
        result = invoke("render", world, "-o", f"{count}.gif", "--frames", "60", "--scale", "1", "--threads", count)
        assert result.exit_code == 0, result.output
    assert Path("1.gif").read_bytes() == Path(f"{min(2, numba.config.NUMBA_NUM_THREADS)}.gif").read_bytes() == Path("auto.gif").read_bytes()
    result = invoke("render", world, "--threads", str(numba.config.NUMBA_NUM_THREADS + 1))
    assert result.exit_code == 2 and f"at most {numba.config.NUMBA_NUM_THREADS} in this process" in result.output
    result = invoke("render", world, "--threads", "some")
    assert result.exit_code == 2 and "'some' is neither a number of threads nor auto" in result.output


def test_bad_world_is_one_line_per_problem_exit_2_and_no_file():
    Path("bad.toml").write_text(
        textwrap.dedent(
            """
            [world]
            width = 40
            height = 0

            [[scene]]
            shape = "blob"
            element = "sand"
            """
        )
    )
    result = invoke("render", "bad.toml", "-o", "bad.gif")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "bad.toml:4:1: world.height: must be >= 4 (got 0)",
        "bad.toml:7:1: scene.0.shape: must be one of 'rect', 'circle', 'line', 'stroke', 'fill', 'image' (got 'blob')",
    ]
    assert "Traceback" not in result.output
    assert not list(Path(".").glob("*.gif*")) and not list(Path(".").glob(".bad.gif*"))


def test_unknown_elements_in_a_scene_are_named_with_their_line():
    Path("typo.toml").write_text(POURING.format(element="snad"))
    result = invoke("render", "typo.toml")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == ["typo.toml:17:1: emitters.0.element: unknown element 'snad' (did you mean 'sand'?)"]


def test_unknown_mod_and_output_format():
    Path("w.toml").write_text('[world]\nwidth = 10\nheight = 10\nmods = ["sand", "glitter"]\n')
    result = invoke("render", "w.toml")
    assert result.exit_code == 2
    assert result.stderr.startswith("w.toml:4:1: world.mods.1: mod 'glitter' was not found (found: acid, automata, base,")
    Path("w.toml").write_text("[world]\nwidth = 10\nheight = 10\n")
    result = invoke("render", "w.toml", "-o", "w.mp4")
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        "w.mp4: no recorder writes '.mp4' files (known: apng (.apng, .png), gif (.gif), "
        "png-frames (a folder), webp (.webp)); or give --format"
    )
    result = invoke("render", "w.toml", "--format", "mp4")
    assert result.exit_code == 2 and "Invalid value for '--format': unknown format 'mp4' (known: apng" in result.stderr
    Path("w.toml").write_text('[world]\nwidth = 10\nheight = 10\n[render]\nformat = "flv"\n')
    result = invoke("render", "w.toml")
    assert result.exit_code == 2 and result.stderr.startswith("w.toml:5:1: render.format: unknown format 'flv' (known: apng")


def test_missing_world_file():
    result = invoke("render", "nowhere.toml")
    assert result.exit_code == 2
    assert result.stderr.startswith("nowhere.toml: cannot read file")


def test_list_shows_elements_and_reactions():
    result = invoke("list")
    assert result.exit_code == 0
    lines = result.stdout.splitlines()
    assert lines[0].split() == ["ELEMENT", "ARCHETYPE", "DENSITY", "TAGS", "DESCRIPTION"]
    assert any(line.startswith("sand:sand") and "powder" in line for line in lines)
    assert any(line.startswith("fire + water") and "steam + (same)" in line for line in lines)


def test_list_json():
    data = json.loads(invoke("list", "--json").stdout)
    by_id = {e["id"]: e for e in data["elements"]}
    assert by_id["titanium:titanium"]["tags"] == ["metal", "acid_proof"]
    assert by_id["water:water"] | {"description": ""} == {
        "id": "water:water",
        "mod": "water",
        "archetype": "liquid",
        "density": 1000.0,
        "tags": [],
        "description": "",
        "plugin": "sandmod.plugins.toml_mods",
        "file": by_id["water:water"]["file"],
        "overrides": [],
    }
    assert by_id["water:water"]["file"].endswith("water.toml")
    stone = by_id["base:stone"]["overrides"]
    assert [(o["mod"], sorted(o["changes"])) for o in stone] == [("lava", ["description", "heated"])]
    assert {"mod": "fire", "a": "fire", "b": "water", "a_becomes": "steam", "b_becomes": None, "chance": 0.8} in data["reactions"]
    assert [m["name"] for m in data["mods"]][0] == "base"


def test_validate_accepts_good_files_and_reports_every_bad_one():
    result = invoke("validate", str(EXAMPLES / "hourglass.toml"), str(EXAMPLES / "acid_wall.toml"))
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("ok: 24 mods") and result.stdout.rstrip().endswith("2 worlds")
    write_mods(
        Path("mods"),
        {
            "a.toml": '[mod]\nname = "a"\n[elements.x]\narchetype = "powder"\ncolor = "#000000"\ndensity = -1\n',
            "b.toml": '[mod]\nname = "b"\n[elements.y]\narchetype = "gas"\ncolor = "#000000"\ndensity = 1\n',
        },
    )
    Path("notes.toml").write_text('title = "hello"\n')
    result = invoke("validate", "mods", "notes.toml")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "notes.toml:1: neither a mod (no [mod] table) nor a world (no [world] table)",
        "mods/a.toml:6:1: elements.x.density: must be > 0 (got -1)",
        "mods/b.toml:3:1: elements.y.dispersion: required field is missing",
    ]


def test_validate_checks_the_world_files_of_a_folder_as_worlds():
    result = invoke("validate", str(EXAMPLES))
    assert result.exit_code == 0, result.output
    sweeps = [p for p in EXAMPLES.glob("*.toml") if "\n[sweep]" in p.read_text()]
    assert sweeps and result.stdout.rstrip().endswith(f"{len(list(EXAMPLES.glob('*.toml'))) - len(sweeps)} worlds, {len(sweeps)} sweep")
    levels = Path("levels")  # worlds, with their mods beside them
    write_mods(levels / "mods", {"glow.toml": '[mod]\nname = "glow"\n[elements.glow]\narchetype = "gas"\ncolor = "#000000"\n'})
    (levels / "good.toml").write_text(POURING.format(element="glow"))
    (levels / "bad.toml").write_text(POURING.format(element="glow").replace("width = 40", "width = -40", 1))
    result = invoke("validate", "levels")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "levels/bad.toml:3:1: world.width: must be >= 4 (got -40)",
        "levels/mods/glow.toml:3:1: elements.glow.density: required field is missing",
        "levels/mods/glow.toml:3:1: elements.glow.dispersion: required field is missing",
    ]
    (levels / "bad.toml").unlink()
    (levels / "mods" / "glow.toml").write_text(
        '[mod]\nname = "glow"\n[elements.glow]\narchetype = "gas"\ncolor = "#000000"\ndensity = 0.5\ndispersion = 2\n'
    )
    result = invoke("validate", "levels")
    assert result.exit_code == 0, result.output
    assert result.stdout.rstrip().endswith("1 world")
    result = invoke("render", "levels/good.toml", "--mods", "levels", "--frames", "4", "-q")  # a world among mods is not one
    assert result.exit_code == 0, result.output


def test_a_dropped_in_mod_appears_in_list_and_render():
    write_mods(
        Path("mods"),
        {
            "glitter.toml": """
                [mod]
                name = "glitter"

                [elements.glitter]
                archetype = "powder"
                color = "#ff00ff"
                shade = 0.0
                density = 1200
            """
        },
    )
    Path("world.toml").write_text(POURING.format(element="glitter"))
    listed = json.loads(invoke("list", "--json", "--mods", "mods").stdout)
    assert "glitter:glitter" in {e["id"] for e in listed["elements"]}
    result = invoke("render", "world.toml", "-o", "glitter.gif")  # mods/ beside the world file
    assert result.exit_code == 0, result.output
    assert (255, 0, 255) in palette_colours(Path("glitter.gif"))
    # Also from any folder, with --mods.
    Path("elsewhere").mkdir()
    Path("mods").rename("elsewhere/mods2")
    Path("world.toml").rename("elsewhere/world.toml")
    assert invoke("render", "elsewhere/world.toml", "-o", "g2.gif").exit_code == 2
    assert invoke("render", "elsewhere/world.toml", "-o", "g2.gif", "--mods", "elsewhere/mods2").exit_code == 0


def test_every_command_reads_the_mods_folder_where_it_runs():
    # list shows ./mods' elements, so render, validate and bench take them too, wherever the world file is.
    write_mods(
        Path("mods"),
        {"glitter.toml": '[mod]\nname = "glitter"\n[elements.glitter]\narchetype = "powder"\ncolor = "#ff00ff"\nshade = 0.0\ndensity = 1200\n'},
    )
    Path("worlds").mkdir()
    Path("worlds/world.toml").write_text(POURING.format(element="glitter"))
    assert "glitter:glitter" in {e["id"] for e in json.loads(invoke("list", "--json").stdout)["elements"]}
    assert invoke("validate", "worlds/world.toml").exit_code == 0
    result = invoke("render", "worlds/world.toml", "-o", "glitter.gif")
    assert result.exit_code == 0, result.output
    assert (255, 0, 255) in palette_colours(Path("glitter.gif"))
    assert invoke("bench", "--world", "worlds/world.toml", "--steps", "2", "--threads", "1").exit_code == 0


def test_commands_that_do_not_simulate_do_not_import_numba(tmp_path):
    code = textwrap.dedent(
        f"""
        import sys
        from click.testing import CliRunner
        from sandmod.tools.cli import cli
        for args in (["list"], ["validate", {str(EXAMPLES / "hourglass.toml")!r}], ["validate"], ["schema"], ["list", "--provenance"],
                     ["palette", "-o", {str(tmp_path / "p.png")!r}], ["validate", {str(EXAMPLES / "picture_level.toml")!r}]):
            result = CliRunner().invoke(cli, args)
            assert result.exit_code == 0, result.output
        assert "numba" not in sys.modules, "numba was imported"
        """
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_console_script_is_installed():
    result = subprocess.run([Path(sys.executable).parent / "sandmod", "--version"], capture_output=True, text=True)
    assert result.returncode == 0 and "sandmod" in result.stdout


def gif_colour_tables(data: bytes) -> tuple[bool, int, int]:
    """(has a global colour table, image count, local colour table count) of a GIF file."""
    flags = data[10]
    i = 13 + (3 * 2 ** ((flags & 7) + 1) if flags & 0x80 else 0)
    images = local = 0
    while data[i] != 0x3B:  # trailer
        if data[i] == 0x21:  # extension: label, then sub-blocks
            i += 2
        else:  # image descriptor, optional local table, LZW code size, then sub-blocks
            images += 1
            packed = data[i + 9]
            i += 10
            if packed & 0x80:
                local += 1
                i += 3 * 2 ** ((packed & 7) + 1)
            i += 1
        while data[i]:
            i += data[i] + 1
        i += 1
    return bool(flags & 0x80), images, local


def test_rendered_frames_share_one_global_colour_table():
    # with sand's mods alone: every bundled mod together has more colours than one table holds
    Path("pour.toml").write_text(POURING.format(element="sand").replace("seed = 4\n", 'seed = 4\nmods = ["sand"]\n'))
    invoke("render", "pour.toml", "-o", "p.gif")
    assert gif_colour_tables(Path("p.gif").read_bytes()) == (True, 10, 0)
    with Image.open("p.gif") as im:
        assert im.mode == "P" and np.asarray(im).dtype == np.uint8


def test_a_mod_given_as_a_world_says_so():
    write_mods(Path("mods"), {"m.toml": '[mod]\nname = "m"\n'})
    result = invoke("render", "mods/m.toml")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "mods/m.toml:1:1: mod: this is a mod ([mod]), not a world ([world]); put it in a mods/ folder beside your world"
    ]


def test_an_unwritable_output_is_a_problem_not_a_traceback():
    Path("pour.toml").write_text(POURING.format(element="sand"))
    Path("blocker").write_text("a file where a folder should be")
    result = invoke("render", "pour.toml", "-o", "blocker/out.gif", "--frames", "2")
    assert result.exit_code == 2
    assert result.stderr.startswith("blocker/out.gif: cannot write: ")


def test_a_shape_outside_the_world_is_an_error():
    Path("w.toml").write_text(
        '[world]\nwidth = 10\nheight = 10\n\n[[scene]]\nshape = "rect"\nelement = "sand"\nx = 50\ny = 0\nwidth = 3\nheight = 3\n'
    )
    result = invoke("validate", "w.toml")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == ["w.toml:5:1: scene.0: the shape lies outside the 10x10 world"]


def test_bad_gravity_and_sprays_are_named_with_their_lines():
    Path("spray.toml").write_text(
        textwrap.dedent(
            """
            [world]
            width = 40
            height = 30
            gravity = -1

            [[sprays]]
            element = "water"
            at = [5, 5]
            speed = [5, 2]

            [[sprays]]
            element = "water"
            at = [5, 5]
            speed = 40
            rate = 0
            """
        ).lstrip()
    )
    result = invoke("render", "spray.toml")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "spray.toml:4:1: world.gravity: must be >= 0 (got -1)",
        "spray.toml:9:1: sprays.0.speed: give [slowest, fastest]",
        "spray.toml:14:1: sprays.1.speed: must be <= 16 (got 40)",
        "spray.toml:15:1: sprays.1.rate: must be > 0 (got 0)",
    ]


def test_a_spray_must_start_inside_the_world_and_name_a_known_element():
    Path("spray.toml").write_text(
        '[world]\nwidth = 40\nheight = 30\n\n[[sprays]]\nelement = "watr"\nat = [5, 5]\nspeed = 3\n\n'
        '[[sprays]]\nelement = "water"\nat = [50, 5]\nspeed = 3\n'
    )
    result = invoke("render", "spray.toml")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "spray.toml:6:1: sprays.0.element: unknown element 'watr' (did you mean 'water'?)",
        "spray.toml:12:1: sprays.1.at: the start lies outside the 40x30 world",
    ]
    Path("spray.toml").write_text('[world]\nwidth = 40\nheight = 30\n\n[[sprays]]\nelement = "empty"\nat = [5, 5]\nspeed = 3\n')
    assert invoke("render", "spray.toml").stderr.splitlines() == ["spray.toml:6:1: sprays.0.element: spray an element, not 'empty'"]


def test_a_spray_fires_particles_that_land_as_their_element():
    Path("spray.toml").write_text(
        POURING.format(element="water").replace("[[emitters]]", "[[sprays]]\nelement = \"sand\"\nat = [4, 20]\n"
        "radius = 2\ndirection = 45\nspread = 10\nspeed = [2, 3]\nrate = 2\nstop = 10\n\n[[emitters]]")
    )
    from sandmod.world.loading import load_world

    world = load_world("spray.toml").world
    world.step()
    assert world.counts()["base:particle"] >= 1 and world.counts(carried=True)["sand:sand"] == world.counts()["base:particle"]
    for _ in range(80):
        world.step()
    sand = world.counts()["sand:sand"]
    assert 12 <= sand <= 20 and "base:particle" not in world.counts()
    assert np.nonzero(world.cells == world.ruleset.index("sand"))[1].min() > 3  # they flew right, away from the nozzle


def test_explosions_and_temperatures_in_world_files_are_checked():
    Path("blast.toml").write_text(
        '[world]\nwidth = 40\nheight = 30\n\n[[scene]]\nshape = "rect"\nelement = "stone"\nx = 0\ny = 0\n'
        "width = 4\nheight = 4\ntemperature = -300\n\n"
        "[[explosions]]\nframe = 3\nat = [5, 15]\nradius = 50\nstrength = -1\n"
    )
    result = invoke("render", "blast.toml")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "blast.toml:12:1: scene.0.temperature: must be >= -273 (got -300)",
        "blast.toml:17:1: explosions.0.radius: must be <= 32 (got 50)",
        "blast.toml:18:1: explosions.0.strength: must be > 0 (got -1)",
    ]
    Path("blast.toml").write_text(
        '[world]\nwidth = 40\nheight = 30\n\n[[explosions]]\nframe = 3\nat = [50, 15]\nradius = 5\nstrength = 1\n'
        'leaves = "fyre"\n\n[[explosions]]\nframe = 3\nat = [5, 15]\nradius = 5\nstrength = 1\nleaves = "smok"\n'
    )
    result = invoke("render", "blast.toml")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "blast.toml:7:1: explosions.0.at: the centre lies outside the 40x30 world",
        "blast.toml:17:1: explosions.1.leaves: unknown element 'smok' (did you mean 'smoke'?)",
    ]
    assert not list(Path(".").glob("blast*.gif"))


def test_new_mod_takes_every_name_the_mod_format_does():
    result = invoke("new", "mod", "my-mod")
    assert result.exit_code == 0, result.output
    assert invoke("validate", "mods").exit_code == 0
    assert "[elements.my_mod]" in Path("mods/my-mod.toml").read_text()
