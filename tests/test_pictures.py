"""Levels drawn as pictures: colours map to elements by the legend; bad pictures are named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from sandmod.errors import ProblemsError
from sandmod.world.loading import load_world
from sandmod.formats.pictures import fit

EXAMPLES = Path(__file__).parent.parent / "examples"

RED, GREY, BLUE, CLEAR = (255, 0, 0, 255), (128, 128, 128, 255), (0, 0, 255, 255), (0, 0, 0, 0)
LEGEND = 'legend = { "#ff0000" = "lava", "#808080" = "stone", "#0000ff" = "water" }'


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def picture(name: str, rows: list[list[tuple]]) -> None:
    Image.fromarray(np.array(rows, np.uint8), "RGBA").save(name)


def world(scene: str, size: tuple[int, int] = (8, 6)):
    Path("w.toml").write_text(f"[world]\nwidth = {size[0]}\nheight = {size[1]}\n\n{scene}")
    return load_world("w.toml").world


def names(w) -> np.ndarray:
    return np.array([e.name for e in w.ruleset.elements])[w.cells]


def test_each_pixel_paints_its_element_scaled_to_the_world():
    picture("p.png", [[RED, GREY, BLUE, GREY], [GREY, GREY, GREY, GREY], [BLUE, BLUE, RED, RED]])
    w = world(f'[[scene]]\nshape = "image"\nfile = "p.png"\n{LEGEND}\n')
    expected = np.array([["lava", "stone", "water", "stone"], ["stone"] * 4, ["water", "water", "lava", "lava"]])
    assert (names(w) == expected.repeat(2, axis=0).repeat(2, axis=1)).all()


def test_transparent_pixels_keep_what_was_painted_and_the_box_places_it():
    picture("p.png", [[RED, CLEAR], [CLEAR, BLUE]])
    w = world(
        '[[scene]]\nshape = "rect"\nelement = "sand"\nx = 0\ny = 0\nwidth = 8\nheight = 6\n\n'
        f'[[scene]]\nshape = "image"\nfile = "p.png"\nx = 2\ny = 1\nwidth = 4\nheight = 4\n{LEGEND}\n'
    )
    expected = np.full((6, 8), "sand", object)
    expected[1:3, 2:4] = "lava"
    expected[3:5, 4:6] = "water"
    assert (names(w) == expected).all()


def test_nearest_matching_forgives_blurred_colours_and_exact_names_them():
    off = (250, 10, 5, 255)
    picture("p.png", [[off, GREY], [BLUE, (130, 126, 131, 255)]])
    w = world(f'[[scene]]\nshape = "image"\nfile = "p.png"\nmatch = "nearest"\n{LEGEND}\n', (4, 4))
    assert (names(w)[::2, ::2] == [["lava", "stone"], ["water", "stone"]]).all()
    with pytest.raises(ProblemsError) as caught:
        world(f'[[scene]]\nshape = "image"\nfile = "p.png"\n{LEGEND}\n', (4, 4))
    assert [str(p) for p in caught.value.problems] == [
        "w.toml:7:1: scene.0.file: colours not in the legend: #fa0a05 (1 pixels, first at x=0, y=0), "
        '#827e83 (1 pixels, first at x=1, y=1) (or use match = "nearest")'
    ]


def test_bad_pictures_and_legends_are_named_with_their_line():
    Path("junk.png").write_text("not a picture")
    picture("p.png", [[RED]])
    with pytest.raises(ProblemsError) as caught:
        world(
            '[[scene]]\nshape = "image"\nfile = "junk.png"\nlegend = { "#ff0000" = "lava" }\n\n'
            '[[scene]]\nshape = "image"\nfile = "gone.png"\nlegend = { "#ff0000" = "lava" }\n\n'
            '[[scene]]\nshape = "image"\nfile = "p.png"\nlegend = { "#ff0000" = "lavva" }\n\n'
            '[[scene]]\nshape = "image"\nfile = "p.png"\nlegend = { "red" = "lava" }\n'
        )
    lines = [str(p) for p in caught.value.problems]
    assert lines == ["w.toml:23:12: scene.3.legend.red: invalid name: must be a colour like '#c2b280' (got 'red')"]  # schema first
    with pytest.raises(ProblemsError) as caught:
        world(
            '[[scene]]\nshape = "image"\nfile = "junk.png"\nlegend = { "#ff0000" = "lava" }\n\n'
            '[[scene]]\nshape = "image"\nfile = "gone.png"\nlegend = { "#ff0000" = "lava" }\n\n'
            '[[scene]]\nshape = "image"\nfile = "p.png"\nlegend = { "#ff0000" = "lavva" }\n'
        )
    assert [str(p) for p in caught.value.problems] == [
        "w.toml:7:1: scene.0.file: not an image pillow can read: junk.png",
        "w.toml:12:1: scene.1.file: no such image: gone.png",
        "w.toml:18:12: scene.2.legend.#ff0000: unknown element 'lavva' (did you mean 'lava'?)",
    ]


def test_fit_takes_the_pixel_under_each_cell_centre():
    indices = np.arange(12).reshape(3, 4)
    assert (fit(indices, 8, 6) == indices.repeat(2, 0).repeat(2, 1)).all()
    assert (fit(indices, 2, 3) == indices[:, [1, 3]]).all()


def test_the_example_level_is_painted_from_its_picture():
    loaded = load_world(EXAMPLES / "picture_level.toml")
    counts = loaded.world.counts()
    with Image.open(EXAMPLES / "level.png") as im:
        pixels = dict((colour, n) for n, colour in im.convert("RGB").getcolors())
    assert counts["lava:lava"] == 4 * pixels[(255, 64, 0)]
    assert counts["water:ice"] == 4 * pixels[(192, 240, 255)]
    assert counts["sand:sand"] == 4 * pixels[(232, 192, 112)]
