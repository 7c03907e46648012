"""The plugin API: built-ins are plugins, third parties register through the same hooks."""

from __future__ import annotations

import inspect
from pathlib import Path

import numpy as np
import pytest

from sandmod import hooks
from sandmod.rules.compiler import compile_mods
from sandmod.errors import ProblemsError
from sandmod.rules.modset import find_mods
from sandmod.formats.recording import RecorderSpec, VideoSettings
from sandmod.registry import BUILTIN_PLUGINS, collect, make_plugin_manager
from sandmod.jobs.render import render
from sandmod.world.world import World


class FramesInMemory:
    """A recorder that keeps frames (and writes their count)."""

    def __init__(self, path: Path, settings: VideoSettings):
        self.path, self.settings, self.frames = path, settings, []

    def add_frame(self, frame: np.ndarray) -> None:
        self.frames.append(frame.copy())

    def close(self) -> None:
        self.path.write_text(str(len(self.frames)))


class ThirdParty:
    """A plugin as a package would ship it."""

    @hooks.hookimpl
    def register_mods(self, register):
        register(
            {
                "mod": {"name": "neon", "version": "2.0.0"},
                "elements": {"neon": {"archetype": "gas", "color": "#ff2299", "density": 0.9, "dispersion": 2}},
            },
            "neon (python)",
        )

    @hooks.hookimpl
    def register_recorders(self, register):
        register(RecorderSpec("count", (".count",), FramesInMemory, "Counts frames."))


def test_every_hook_is_typed_and_documented():
    specs = [f for name, f in inspect.getmembers(hooks, inspect.isfunction) if name.startswith("register_")]
    assert len(specs) == 6
    for spec in specs:
        assert spec.__doc__ and len(spec.__doc__.strip()) > 40, spec.__name__
        assert set(spec.__annotations__) == {"register", "return"}, spec.__name__


def test_built_in_behaviour_comes_from_plugins():
    pm = make_plugin_manager(entry_points=False)
    assert {pm.get_name(p) for p in pm.get_plugins()} == set(BUILTIN_PLUGINS)
    registry = collect(pm)
    assert registry.mod_loaders[".toml"].plugin == "sandmod.plugins.toml_mods"
    assert registry.recorders["gif"].plugin == "sandmod.plugins.gif"
    assert [d.plugin for d in registry.mod_dirs] == ["sandmod.plugins.toml_mods"]


def test_each_manager_is_independent():
    first = make_plugin_manager(entry_points=False)
    first.register(ThirdParty(), name="third")
    assert "count" not in collect(make_plugin_manager(entry_points=False)).recorders


def test_a_third_party_plugin_adds_a_mod_and_a_recorder(tmp_path):
    pm = make_plugin_manager(entry_points=False)
    pm.register(ThirdParty(), name="neon-plugin")
    registry = collect(pm)
    assert registry.recorders["count"].plugin == "neon-plugin"
    ruleset = compile_mods(find_mods(registry).select(["neon"]))
    assert [m.name for m in ruleset.mods] == ["base", "neon"]
    assert [m.plugin for m in ruleset.mods] == ["sandmod.plugins.toml_mods", "neon-plugin"]
    world = World(ruleset, 8, 8)
    world.paint(np.eye(8, dtype=bool), ruleset.index("neon"))
    result = render(world, registry.recorder_for(Path("x.count")), tmp_path / "x.count", frames=4, every=2)
    assert (tmp_path / "x.count").read_text() == "3" and result.images == 3


def test_python_mods_are_validated_like_files():
    class Broken:
        @hooks.hookimpl
        def register_mods(self, register):
            register({"mod": {"name": "bad"}, "elements": {"x": {"archetype": "powder", "color": "#000000"}}}, "bad (python)")

    pm = make_plugin_manager(entry_points=False)
    pm.register(Broken(), name="broken")
    with pytest.raises(ProblemsError) as caught:
        find_mods(collect(pm))
    assert [str(p) for p in caught.value.problems] == ["bad (python): elements.x.density: required field is missing"]


def test_plugins_can_be_disabled_by_name(monkeypatch):
    monkeypatch.setenv("SANDMOD_DISABLE_PLUGINS", "sandmod.plugins.gif")
    registry = collect(make_plugin_manager(entry_points=False))
    assert "gif" not in registry.recorders and ".toml" in registry.mod_loaders


def test_a_registered_folder_must_exist(tmp_path):
    class Lost:
        @hooks.hookimpl
        def register_mod_dirs(self, register):
            register(tmp_path / "missing")

    pm = make_plugin_manager(entry_points=False)
    pm.register(Lost(), name="lost")
    with pytest.raises(ProblemsError) as caught:
        collect(pm)
    assert str(caught.value.problems[0]).startswith("lost: register_mod_dirs: ")


class Exploding(FramesInMemory):
    def add_frame(self, frame):
        if len(self.frames) == 2:
            self.path.write_text("half a file")
            raise RuntimeError("disk on fire")
        super().add_frame(frame)


def test_a_failed_render_leaves_no_file_and_keeps_the_old_one(tmp_path, ruleset):
    out = tmp_path / "movie.count"
    out.write_text("the previous render")
    spec = RecorderSpec("boom", (".count",), Exploding)
    with pytest.raises(RuntimeError):
        render(World(ruleset, 8, 8), spec, out, frames=10)
    assert out.read_text() == "the previous render"
    assert [p.name for p in tmp_path.iterdir()] == ["movie.count"]


def test_gif_stores_what_changed_and_shows_a_repeated_picture_longer(tmp_path):
    from PIL import Image, ImageSequence

    from sandmod.formats.recording import VideoSettings
    from sandmod.plugins.gif import MAX_DELAY_MS, GifRecorder, changes

    colours = np.arange(3 * 300).reshape(300, 3).astype(np.uint8)
    first = np.zeros((6, 8), np.uint16)
    second = first.copy()
    second[2:4, 5] = 299  # a 1 x 2 box at (5, 2), of a colour beyond the global table's 256
    frames = [first, first.copy(), second, second.copy(), second.copy()]
    stored = [(box.shape, x, y, ms) for box, x, y, ms in changes(frames, 40)]
    assert stored == [((6, 8), 0, 0, 80), ((2, 1), 5, 2, 120)]
    assert [ms for *_, ms in changes([first] * 3, MAX_DELAY_MS // 2 + 10)] == [MAX_DELAY_MS // 2 + 10] * 3  # none over the most
    out = tmp_path / "m.gif"
    recorder = GifRecorder(out, VideoSettings(8, 6, colours, 25, loop=3))
    for frame in frames:
        recorder.add_frame(frame)
    recorder.close()
    assert (recorder.pictures, recorder.local_tables) == (2, 1)
    with Image.open(out) as im:
        assert (im.size, im.info["loop"]) == ((8, 6), 2)
        pictures = [(np.asarray(f.convert("RGB")).copy(), f.info["duration"]) for f in ImageSequence.Iterator(im)]
    assert [ms for _, ms in pictures] == [80, 120]
    assert (pictures[0][0] == colours[first]).all() and (pictures[1][0] == colours[second]).all()


def test_a_finished_render_gets_ordinary_file_permissions(tmp_path, ruleset):
    import os

    out = tmp_path / "movie.count"
    render(World(ruleset, 8, 8), RecorderSpec("count", (".count",), FramesInMemory), out, frames=2)
    plain = tmp_path / "plain"
    plain.write_text("")
    assert out.stat().st_mode & 0o777 == plain.stat().st_mode & 0o777
    assert os.access(out, os.R_OK)


def test_a_misspelled_hook_and_bad_registrations_are_problems_naming_the_plugin():
    from sandmod.errors import ProblemsError
    from sandmod.hooks import hookimpl

    class Misspelled:
        @hookimpl
        def register_recorder(self, register):  # no such hook: register_recorders
            pass

    pm = make_plugin_manager(entry_points=False)
    pm.register(Misspelled(), name="typo-plugin")
    with pytest.raises(ProblemsError) as caught:
        collect(pm)
    assert str(caught.value).startswith("typo-plugin: ") and "register_recorder" in str(caught.value)

    class Careless:
        @hookimpl
        def register_mod_loaders(self, register):
            register("toml", None)

        @hookimpl
        def register_recorders(self, register):
            register("gif")

        @hookimpl
        def register_mods(self, register):
            raise RuntimeError("oops")

    pm = make_plugin_manager(entry_points=False)
    pm.register(Careless(), name="careless")
    with pytest.raises(ProblemsError) as caught:
        collect(pm)
    lines = sorted(str(p) for p in caught.value.problems)
    assert [line.split(":")[:2] for line in lines] == [
        ["careless", " register_mod_loaders"], ["careless", " register_mods"], ["careless", " register_recorders"]
    ]
