"""Output formats and looks: every recorder round-trips through pillow; crop, scale, loop, still."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageSequence

from conftest import invoke
from sandmod.world.loading import load_registry
from sandmod.formats.recording import VideoSettings
from sandmod.jobs.render import Crop, Framing, render
from sandmod.world.world import enlarge
from sandmod.engine.layout import SCORCHED
from sandmod.world.world import World

REGISTRY = load_registry()


def pouring_world(ruleset) -> World:
    """Sand pours onto a stone floor: every frame differs from the one before."""
    world = World(ruleset, 24, 16, seed=3)
    floor = np.zeros((16, 24), bool)
    floor[14:, :] = True
    world.paint(floor, ruleset.index("stone"))
    from sandmod.world.world import Emitter

    world.emitters.append(Emitter(np.array([0, 0]), np.array([11, 12]), ruleset.index("sand"), 0, None, 1.0))
    return world


class Keep:
    """A recorder that keeps the frames (colour indices) it is given."""

    frames: list[np.ndarray] = []

    def __init__(self, path: Path, settings: VideoSettings):
        self.settings = settings
        Keep.frames = []
        path.write_text("kept")

    def add_frame(self, frame):
        Keep.frames.append(frame.copy())

    def close(self):
        pass


def expected_frames(ruleset, framing: Framing, frames: int, every: int, tmp_path: Path) -> list[np.ndarray]:
    from sandmod.formats.recording import RecorderSpec

    render(pouring_world(ruleset), RecorderSpec("keep", (".keep",), Keep), tmp_path / "x.keep", frames=frames, every=every, framing=framing)
    return Keep.frames


def rgb_frames(path: Path) -> list[np.ndarray]:
    if path.is_dir():
        return [np.asarray(Image.open(p).convert("RGB")) for p in sorted(path.iterdir())]
    with Image.open(path) as im:
        return [np.asarray(frame.convert("RGB")) for frame in ImageSequence.Iterator(im)]


def durations(path: Path) -> list[int]:
    with Image.open(path) as im:
        out = []
        for frame in ImageSequence.Iterator(im):
            frame.load()
            out.append(int(frame.info["duration"]))
        return out


@pytest.mark.parametrize("name, suffix", [("gif", ".gif"), ("apng", ".apng"), ("webp", ".webp"), ("png-frames", "")])
def test_each_format_round_trips_through_pillow(name, suffix, ruleset, tmp_path):
    framing = Framing(scale=2, crop=Crop(4, 2, 16, 13))
    expected = expected_frames(ruleset, framing, 12, 3, tmp_path)
    spec = REGISTRY.recorders[name].value
    out = tmp_path / f"movie{suffix}"
    result = render(pouring_world(ruleset), spec, out, frames=12, every=3, framing=framing, fps=20)
    assert (result.images, result.width, result.height) == (5, 32, 26)
    got = rgb_frames(out)
    assert len(got) == 5 and all(frame.shape == (26, 32, 3) for frame in got)
    for mine, theirs in zip(expected, got):
        assert (ruleset.colours[mine] == theirs).all()
    if suffix:
        assert durations(out) == [50] * 5
    assert sorted(p.name for p in tmp_path.iterdir()) == ["movie" + suffix, "x.keep"]  # nothing left behind


def test_scale_is_nearest_neighbour_and_crop_picks_the_region(ruleset):
    world = pouring_world(ruleset)
    full = world.image()
    cropped = Framing(scale=3, crop=Crop(5, 10, 8, 6)).image(world)
    assert cropped.shape == (18, 24)
    assert (cropped[::3, ::3] == full[10:16, 5:13]).all()
    blocks = cropped.reshape(6, 3, 8, 3)
    assert (blocks == blocks[:, :1, :, :1]).all()  # each cell one uniform 3 x 3 block
    assert (enlarge(full, 1) is full) and enlarge(full, 2).shape == (32, 48)
    assert not Crop(20, 0, 8, 4).fits(24, 16) and Crop(16, 0, 8, 4).fits(24, 16)


@pytest.mark.parametrize("fps, gif_ms, other_ms", [(25, 40, 40), (30, 30, 33), (50, 20, 20), (7, 140, 143)])
def test_durations_follow_fps_and_gif_keeps_at_least_20_ms(fps, gif_ms, other_ms, ruleset, tmp_path):
    for name, expected in (("gif", gif_ms), ("apng", other_ms), ("webp", other_ms)):
        out = tmp_path / f"d.{name}"
        render(pouring_world(ruleset), REGISTRY.recorders[name].value, out, frames=2, fps=fps)
        assert set(durations(out)) == {expected}, name


@pytest.mark.parametrize("plays", [0, 1, 3])
def test_loop_counts_plays_in_every_format(plays, ruleset, tmp_path):
    for name in ("gif", "apng", "webp"):
        out = tmp_path / f"l.{name}"
        render(pouring_world(ruleset), REGISTRY.recorders[name].value, out, frames=2, loop=plays)
        with Image.open(out) as im:
            if name == "gif":  # GIF stores repeats after the first play, and nothing for one play
                assert im.info.get("loop") == (None if plays == 1 else max(plays - 1, 0))
            else:
                assert im.info["loop"] == plays


def test_the_still_is_the_last_image(ruleset, tmp_path):
    framing = Framing(scale=2)
    expected = expected_frames(ruleset, framing, 7, 3, tmp_path)
    world = pouring_world(ruleset)
    for _ in range(7):
        world.step()
    last = framing.image(world)
    assert not (last == expected[-1]).all()  # frame 7 is not recorded with every 3 ...
    render(pouring_world(ruleset), REGISTRY.recorders["gif"].value, tmp_path / "m.gif", frames=7, every=3, framing=framing, still=tmp_path / "s.png")
    with Image.open(tmp_path / "s.png") as still:
        assert still.format == "PNG" and still.mode == "P"  # its few colours: indexed
        assert (np.asarray(still.convert("RGB")) == ruleset.colours[last]).all()  # ... but the still shows it


def test_a_frames_folder_replaces_an_old_render_but_not_other_files(ruleset, tmp_path):
    spec = REGISTRY.recorders["png-frames"].value
    out = tmp_path / "frames"
    render(pouring_world(ruleset), spec, out, frames=4)
    assert sorted(p.name for p in out.iterdir()) == [f"frame_0000{i}.png" for i in range(5)]
    render(pouring_world(ruleset), spec, out, frames=2)
    assert len(list(out.iterdir())) == 3  # the old frames went with the old render
    (out / "notes.txt").write_text("mine")
    with pytest.raises(FileExistsError):
        render(pouring_world(ruleset), spec, out, frames=2)
    assert (out / "notes.txt").read_text() == "mine" and len(list(out.iterdir())) == 4
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames"]


def test_a_grain_keeps_its_shade_as_it_falls(ruleset):
    world = World(ruleset, 8, 40, seed=1)
    sand = ruleset.index("sand")
    world.paint_cells(np.array([0]), np.array([4]), sand)
    shade = int(world.state.shade[0, 4])
    colour = ruleset.looks.normal[sand, (shade * ruleset.shades) >> 8]
    seen = set()
    for _ in range(30):
        world.step()
        (y,), (x,) = np.nonzero(world.cells == sand)
        seen.add(y)
        assert world.state.shade[y, x] == shade and world.image()[y, x] == colour
    assert len(seen) > 5  # it fell
    other = World(ruleset, 8, 40, seed=2)
    other.paint(np.ones((40, 8), bool), sand)
    assert len(np.unique(other.image())) >= 3  # and grains differ from each other


def test_scorched_cells_are_darker(ruleset):
    world = World(ruleset, 8, 8)
    world.paint(np.ones((8, 8), bool), ruleset.index("stone"))
    before = world.image()
    world.state.flags[:4] |= SCORCHED
    after = world.image()
    colours = ruleset.colours.astype(int)
    assert (colours[after[:4]].sum(axis=1) < colours[before[:4]].sum(axis=1)).all()
    assert (after[4:] == before[4:]).all()


WORLD = """
[world]
width = 30
height = 20

[[scene]]
shape = "rect"
element = "sand"
x = 5
y = 0
width = 20
height = 6
"""


def test_cli_picks_the_format_by_extension_or_by_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("w.toml").write_text(WORLD + "[render]\nframes = 6\nscale = 1\n")
    for output, kind in (("a.webp", "WEBP"), ("a.apng", "PNG"), ("a.png", "PNG"), ("a.gif", "GIF")):
        assert invoke("render", "w.toml", "-o", output, "-q").exit_code == 0
        with Image.open(output) as im:
            assert im.format == kind and im.n_frames == 4
    assert invoke("render", "w.toml", "--format", "webp", "-q").exit_code == 0
    assert Image.open("w.webp").format == "WEBP"  # the default name takes the format's extension
    assert invoke("render", "w.toml", "--format", "apng", "-o", "odd.gif", "-q").exit_code == 0
    assert Image.open("odd.gif").format == "PNG"  # --format wins over the extension
    assert invoke("render", "w.toml", "-o", "shots", "-q").exit_code == 0
    assert len(list(Path("shots").glob("frame_*.png"))) == 4


def test_cli_crop_loop_still_and_summary(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("w.toml").write_text(WORLD + "[render]\nframes = 4\nevery = 1\nscale = 2\ncrop = [0, 0, 10, 5]\nloop = 2\n")
    result = invoke("render", "w.toml", "-o", "c.gif", "--still", "last.png")
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("wrote c.gif: 5 images of 20x10 from 4 frames in ")
    assert result.stdout.rstrip().endswith(", still last.png")
    with Image.open("c.gif") as im, Image.open("last.png") as still:
        assert im.size == still.size == (20, 10) and im.info["loop"] == 1
    result = invoke("render", "w.toml", "-o", "c.gif", "--crop", "25", "0", "10", "5", "--loop", "0")
    assert result.exit_code == 2
    assert "Invalid value for '--crop': [x, y, width, height] = [25, 0, 10, 5] must lie inside the 30x20 world" in result.stderr
    Path("w.toml").write_text(WORLD + "[render]\ncrop = [0, 0, 40, 5]\n")
    result = invoke("render", "w.toml", "-o", "d.gif")
    assert result.exit_code == 2 and not Path("d.gif").exists()
    assert result.stderr.startswith("w.toml:14:1: render.crop: [x, y, width, height] = [0, 0, 40, 5] must lie inside")


def test_the_palette_card_shows_every_element_in_its_colours(tmp_path, monkeypatch, ruleset):
    from sandmod.jobs.swatches import ROW, SWATCH, card_layout

    monkeypatch.chdir(tmp_path)
    result = invoke("palette", "-o", "card.png")
    assert result.exit_code == 0 and result.stdout == f"wrote card.png: {len(ruleset.elements)} elements\n"
    looks = ruleset.looks
    with Image.open("card.png") as card:
        assert card.height == ROW * (len(ruleset.elements) + 1) + 8
        for row, element in enumerate(ruleset.by_id, start=1):
            centre = row * ROW + 2 + SWATCH // 2
            for x, group in zip(card_layout(ruleset), (looks.normal, looks.scorched, looks.glow)):
                for j, index in enumerate(group[element.index]):
                    assert card.getpixel((x + j * SWATCH + SWATCH // 2, centre)) == tuple(ruleset.colours[index])
    Path("w.toml").write_text(WORLD.replace("height = 20", 'height = 20\nmods = ["sand"]'))
    assert invoke("palette", "w.toml", "-o", "few.png").stdout == "wrote few.png: 7 elements\n"  # base: empty, particle, stone, rubble; sand needs glass (and its shards)
