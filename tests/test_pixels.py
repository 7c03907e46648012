"""Frames to pixels: the compiled pixels are the numpy reference's, and the heat view's scale."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sandmod.jobs import benchmark
from sandmod.world.loading import load_world
from sandmod.world.world import World

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.mark.parametrize(("name", "frames"), [("demolition", 150), ("lava_lake", 120), ("forest_fire", 200), ("fountain", 60)])
def test_the_compiled_pixels_are_the_numpy_ones(name, frames):
    # Scorch (demolition), glow (lava, fire) and particles showing what they carry (fountain).
    world = load_world(EXAMPLES / f"{name}.toml").world
    for frame in range(frames):
        world.step()
        if frame % 30 == 29:
            assert np.array_equal(world.image(), benchmark.numpy_image(world)), frame


def test_only_the_changed_chunks_are_drawn_and_they_are_enough():
    world = load_world(EXAMPLES / "hourglass.toml").world
    frame = world.image()
    for _ in range(40):
        world.step()
        world.image(frame, changed_only=True)
        assert np.array_equal(frame, world.image())
    poisoned = np.full_like(frame, 255)
    world.image(poisoned, changed_only=True)
    assert (poisoned == 255).any()  # the chunks asleep were left alone


def test_the_heat_view_goes_from_blue_through_dark_to_white(ruleset):
    world = World(ruleset, 4, 1)
    world.paint(np.ones((1, 4), bool), ruleset.index("stone"))
    for x, celsius in enumerate((-100.0, 20.0, 800.0, 9000.0)):
        mask = np.zeros((1, 4), bool)
        mask[0, x] = True
        world.set_temperature(mask, celsius)
    cold, room, hot, hottest = world.heat_image()[0].astype(int)
    assert cold[2] > cold[0] and cold[2] > 100  # blue
    assert room.sum() < 100  # dark
    assert hot[0] == 255 and hot[2] < 50  # orange
    assert hottest.min() > 220  # white
