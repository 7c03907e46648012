"""Colours never run out: an element looks the same however many others are loaded, and every
format shows the frames' colours (exactly, up to what the format holds)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageSequence

from conftest import walls_mod, write_mods
from sandmod.formats.recording import VideoSettings, fit_palette
from sandmod.jobs.render import render
from sandmod.rules import compiler
from sandmod.world.loading import load_registry, load_ruleset
from sandmod.world.world import World

REGISTRY = load_registry()
IRON = '[elements.iron]\narchetype = "static"\ncolor = ["#8a8d91", "#7d8085"]\nshade = 0.1\ntags = ["metal"]\n'


def pack(folder: Path, others: int):
    """The base mod and a mod of iron and ``others`` more static elements, each its own colour."""
    mods = write_mods(folder, {"pack.toml": walls_mod("pack", others, IRON)})
    return load_ruleset(["base", "pack"], [mods], registry=REGISTRY)


@pytest.fixture(scope="module")
def few(tmp_path_factory):
    return pack(tmp_path_factory.mktemp("few"), 0)


@pytest.fixture(scope="module")
def many(tmp_path_factory):
    return pack(tmp_path_factory.mktemp("many"), 300)


def looks_of(ruleset, name: str) -> list[np.ndarray]:
    """An element's colours: shades, scorched shades, glow levels (RGB)."""
    e, looks = ruleset.index(name), ruleset.looks
    return [ruleset.colours[group[e]] for group in (looks.normal, looks.scorched, looks.glow)]


def test_an_element_looks_the_same_with_3_elements_and_with_300(few, many):
    assert len(few.elements) == 5 and len(many.elements) == 305
    for name in ("iron", "stone", "empty"):
        for mine, theirs in zip(looks_of(few, name), looks_of(many, name)):
            assert (mine == theirs).all(), name
    shades, scorched, glow = looks_of(many, "iron")
    assert len(np.unique(shades, axis=0)) == 8 and len(np.unique(scorched, axis=0)) == 4 and len(np.unique(glow, axis=0)) == 3
    assert len(many.colours) == 8 + 304 * 15 and many.looks.normal.max() >= 256


def test_a_bar_of_iron_at_1200_degrees_glows_with_300_elements_loaded(many):
    world = World(many, 12, 3)
    bar = np.zeros((3, 12), bool)
    bar[1, 1:11] = True
    world.paint(bar, many.index("iron"))
    world.set_temperature(bar, 1200.0)
    iron, looks = many.index("iron"), many.looks
    assert (world.image()[bar] == looks.glow[iron, 2]).all()  # (1200 - 525) // 300: the third level, yellow-white
    r, g, b = world.rgb()[1, 5].astype(int)
    assert r > g > b and g > 180
    world.set_temperature(bar, 20.0)
    assert np.isin(world.image()[bar], looks.normal[iron]).all()


def statics(ruleset) -> list[int]:
    return [e.index for e in ruleset.elements if e.spec.archetype == "static"]


def stripes(ruleset, height: int = 16) -> World:
    """Every static element in a column of its own: with many, thousands of colours in one frame."""
    walls = statics(ruleset)
    world = World(ruleset, len(walls), height, seed=5)
    for x, element in enumerate(walls):
        column = np.zeros((height, world.width), bool)
        column[:, x] = True
        world.paint(column, element)
    return world


def gif_frames(path: Path) -> list[np.ndarray]:
    with Image.open(path) as im:
        return [np.asarray(frame.convert("RGB")) for frame in ImageSequence.Iterator(im)]


def test_a_gif_of_more_than_256_colours_is_exact_in_its_most_common_256(many, tmp_path):
    world = stripes(many)
    frame = world.image()
    assert len(np.unique(frame)) > 1000
    render(world, REGISTRY.recorders["gif"].value, tmp_path / "m.gif", frames=0)
    (shown,) = gif_frames(tmp_path / "m.gif")
    palette = fit_palette([frame], many.colours)
    exact = palette.kept[frame]
    assert not palette.exact and len(palette.rgb) == 256 and exact.sum() > 0.15 * frame.size
    assert (shown[exact] == world.rgb()[exact]).all()
    assert (shown == palette.rgb[palette.indices(frame)]).all()  # the rest: the nearest of those kept


def test_a_gif_of_at_most_256_colours_a_picture_is_exact_new_colours_and_all(many, tmp_path):
    from sandmod.plugins.gif import GifRecorder

    world = World(many, 40, 30, seed=1)
    path = tmp_path / "a.gif"
    recorder = GifRecorder(path, VideoSettings(world.width, world.height, many.colours, 25))
    expected = []
    for k in range(6):  # each image a new element, far apart in the colours: outside the global table
        block = np.zeros((30, 40), bool)
        block[5 * k : 5 * k + 5, 2 + 6 * k : 8 + 6 * k] = True
        world.paint(block, statics(many)[50 * k])
        recorder.add_frame(world.image())
        expected.append(world.rgb())
    recorder.close()
    assert recorder.pictures == 6 and recorder.local_tables >= 4
    got = gif_frames(path)
    assert len(got) == 6 and all((mine == theirs).all() for mine, theirs in zip(expected, got))


@pytest.mark.parametrize("name, suffix", [("apng", ".apng"), ("png-frames", ""), ("webp", ".webp")])
def test_lossless_formats_read_back_as_the_world_in_few_colours_and_in_many(name, suffix, few, many, tmp_path):
    for ruleset, mode in ((few, "P"), (many, "RGB")):
        world = stripes(ruleset)
        out = tmp_path / f"{len(ruleset.elements)}{suffix}"
        render(world, REGISTRY.recorders[name].value, out, frames=0)
        path = next(out.iterdir()) if out.is_dir() else out
        with Image.open(path) as im:
            assert im.mode == mode or name == "webp"
            assert (np.asarray(im.convert("RGB")) == world.rgb()).all()


def test_a_still_png_of_many_colours_is_rgb_and_exact(many, tmp_path):
    from sandmod.formats.recording import write_png

    world = stripes(many)
    write_png(tmp_path / "s.png", world.image(), many.colours)
    with Image.open(tmp_path / "s.png") as im:
        assert im.mode == "RGB" and (np.asarray(im) == world.rgb()).all()


def test_a_palette_is_exact_up_to_256_colours_and_the_nearest_of_the_most_common_beyond():
    colours = np.array([[0, 0, 0], [255, 255, 255], [250, 250, 250], [10, 0, 0]], np.uint8)
    frame = np.array([[0, 1, 1, 3]], np.uint16)
    palette = fit_palette([frame], colours)
    assert palette.exact and (palette.rgb[palette.indices(frame)] == colours[frame]).all() and len(palette.rgb) == 3
    many = np.stack([np.arange(600) % 256, np.arange(600) // 256, np.full(600, 7)], axis=1).astype(np.uint8)
    busy = np.concatenate([np.repeat(np.arange(256), 3), np.arange(256, 600)]).astype(np.uint16)[None]
    palette = fit_palette([busy], many)
    assert not palette.exact and len(palette.rgb) == 256
    assert palette.kept[:256].all() and not palette.kept[256:].any()  # the most common
    assert (palette.rgb[palette.indices(busy[:, :768])] == many[busy[:, :768]]).all()


def test_the_colours_of_the_most_elements_a_ruleset_holds_fit_uint16_indices():
    per_element = compiler.SHADES + compiler.SCORCHED_SHADES + len(compiler.GLOW_COLOURS)
    assert compiler.SHADES + (compiler.MAX_ELEMENTS - 1) * per_element <= 2**16
