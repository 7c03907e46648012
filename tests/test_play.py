"""``sandmod play`` headless (SDL's dummy video driver), driven by events posted to pygame's queue."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from click.testing import CliRunner

pygame = pytest.importorskip("pygame")

from sandmod.jobs.benchmark import state_digest  # noqa: E402
from sandmod.jobs.play import Play  # noqa: E402
from sandmod.jobs.session import Session  # noqa: E402
from sandmod.tools.cli import cli  # noqa: E402
from sandmod.world.loading import load_world  # noqa: E402

SCALE = 2


@pytest.fixture(autouse=True)
def _headless(tmp_path, monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.chdir(tmp_path)


def post(kind, **fields) -> None:
    pygame.event.post(pygame.event.Event(kind, **fields))


def at(x: int, y: int) -> tuple[int, int]:
    """The window position of cell (x, y)."""
    return x * SCALE + 1, y * SCALE + 1


def frames(play: Play, count: int) -> None:
    for _ in range(count):
        play._one_frame()


def key(play: Play, name: int, mod: int = 0) -> None:
    post(pygame.KEYDOWN, key=name, mod=mod, unicode="")
    frames(play, 1)


def test_a_scripted_session_replays_from_the_world_file_it_saves():
    play = Play(Session.open(None, size=(64, 48)), scale=SCALE, fixed_steps=1)
    sand = play.brush.element
    post(pygame.MOUSEBUTTONDOWN, pos=at(10, 10), button=1)  # paint sand along a drag
    post(pygame.MOUSEMOTION, pos=at(30, 12), rel=(0, 0), buttons=(1, 0, 0))
    post(pygame.MOUSEBUTTONUP, pos=at(30, 12), button=1)
    frames(play, 10)
    assert play.session.world.counts()["sand:sand"] > 20
    key(play, pygame.K_2)  # another element, then a stroke of it, then undo that stroke
    other = play.brush.element
    assert other != sand
    post(pygame.MOUSEBUTTONDOWN, pos=at(40, 5), button=1)
    post(pygame.MOUSEBUTTONUP, pos=at(40, 5), button=1)
    frames(play, 5)
    key(play, pygame.K_z, pygame.KMOD_CTRL)
    assert play.message == "undone" and play.session.world.frame == 12  # back to 11, then that frame's step
    ys, xs = (play.session.world.cells == sand).nonzero()
    post(pygame.MOUSEBUTTONDOWN, pos=at(int(xs[-1]), int(ys[-1])), button=2)  # pick a grain of sand
    frames(play, 1)
    assert play.brush.element == sand
    post(pygame.MOUSEBUTTONDOWN, pos=at(int(xs[0]), int(ys[0])), button=3)  # erase some of it
    post(pygame.MOUSEBUTTONUP, pos=at(int(xs[0]), int(ys[0])), button=3)
    key(play, pygame.K_SPACE)  # paused: a stroke waits for the next step, and shows meanwhile
    post(pygame.MOUSEBUTTONDOWN, pos=at(50, 20), button=1)
    post(pygame.MOUSEBUTTONUP, pos=at(50, 20), button=1)
    frames(play, 3)
    paused_at = play.session.world.frame
    key(play, pygame.K_SPACE)
    frames(play, 10)
    key(play, pygame.K_SPACE)  # paused again, to save
    key(play, pygame.K_s)
    assert play.session.world.frame == paused_at + 11
    replay = load_world("play-session.toml")
    for _ in range(replay.spec.render.frames):
        replay.world.step()
    assert state_digest(replay.world) == state_digest(play.session.world)
    key(play, pygame.K_p)
    key(play, pygame.K_g)
    assert Path("play-screenshot.png").stat().st_size > 0 and Path("play-capture.gif").stat().st_size > 0


def test_saving_a_mod_reloads_it_and_a_broken_one_is_shown_while_the_old_rules_go_on():
    Path("mods").mkdir()
    mod = Path("mods/goo.toml")
    mod.write_text('[mod]\nname = "goo"\n\n[elements.goo]\narchetype = "liquid"\ncolor = "#00ff00"\ndensity = 900\ndispersion = 2\n')
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1)
    play.next_mod_check = float("inf")  # checked by hand below, not by the clock
    frames(play, 2)
    mod.write_text(mod.read_text().replace("#00ff00", "#ff00ff"))
    assert play.session.mods_changed()
    play.reload()
    ruleset = play.session.world.ruleset
    assert play.message == "mods reloaded" and ruleset.elements[ruleset.index("goo")].spec.color == ["#ff00ff"]
    mod.write_text("[mod]\nname = 3\n")
    play.reload()
    assert play.problems and "goo.toml" in play.problems[0] and play.session.world.ruleset is ruleset
    frames(play, 2)  # and it goes on
    assert play.session.world.frame == 4


def test_the_benchmark_prints_frames_a_second_and_each_phase():
    result = CliRunner().invoke(cli, ["play", "--size", "96x64", "--benchmark", "20"], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    measured = json.loads(result.stdout.strip().splitlines()[-1])
    assert measured["frames"] == 20 and measured["fps"] > 0 and set(measured["ms_per_frame"]) == {"step", "pixels", "blit", "input"}


def test_a_bad_world_is_one_line_per_problem_and_exit_2_before_any_window():
    Path("bad.toml").write_text("[world]\nwidth = 2\nheight = 64\n")
    result = CliRunner().invoke(cli, ["play", "bad.toml"])
    assert result.exit_code == 2 and "bad.toml:2:1: world.width: must be >= 4" in result.output
    assert not pygame.display.get_init()


def test_a_world_larger_than_the_window_is_seen_through_a_view_that_pans_and_zooms():
    play = Play(Session.open(None, size=(800, 500)), scale=2, fixed_steps=1)
    assert play.area == (1280, 800) and play._shown() == (640, 400)
    key(play, pygame.K_RIGHT)
    key(play, pygame.K_DOWN)
    assert play.view == [160, 100] and play._cell(at(0, 0)) == (160, 100)
    key(play, pygame.K_RIGHT)
    assert play.view == [160, 100]  # at the world's edge
    play._zoom(2, (0, 0))
    assert play.scale == 4 and play._shown() == (320, 200) and play._cell((0, 0)) == (160, 100)
    post(pygame.MOUSEBUTTONDOWN, pos=(8, 8), button=1)  # paints where the view shows, not at the corner
    post(pygame.MOUSEBUTTONUP, pos=(8, 8), button=1)
    frames(play, 1)
    assert play.session.world.cells[100:106, 160:166].any() and not play.session.world.cells[:10, :10].any()


def test_save_session_writes_the_world_file_when_the_window_closes():
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1, save_on_exit=True)
    post(pygame.MOUSEBUTTONDOWN, pos=at(10, 5), button=1)
    post(pygame.MOUSEBUTTONUP, pos=at(10, 5), button=1)
    post(pygame.KEYDOWN, key=pygame.K_ESCAPE, mod=0, unicode="")
    play.run(frames=50)
    assert "paint" in Path("play-session.toml").read_text()


def test_a_square_brush_paints_a_square():
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1)
    play.brush.element = play.session.world.ruleset.index("stone")
    key(play, pygame.K_b)
    post(pygame.MOUSEBUTTONDOWN, pos=at(10, 10), button=1)
    post(pygame.MOUSEBUTTONUP, pos=at(10, 10), button=1)
    frames(play, 1)
    stone = play.session.world.cells == play.brush.element
    assert stone.sum() == 25 and stone[8:13, 8:13].all()
