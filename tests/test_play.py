"""``sandmod play`` headless (SDL's dummy video driver), driven by events posted to pygame's queue."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

pygame = pytest.importorskip("pygame")

from sandmod.jobs import session as session_module  # noqa: E402
from sandmod.jobs.benchmark import state_digest  # noqa: E402
from sandmod.jobs.play import Play  # noqa: E402
from sandmod.jobs.play.menu import FAVOURITES, FOUND, KEYED, listed, offered  # noqa: E402
from sandmod.jobs.play.view import CHOSEN, MARGIN, MENU, PANEL, STATUS, TEXT, contrast, ink  # noqa: E402
from sandmod.jobs.session import Session  # noqa: E402
from sandmod.tools.cli import cli  # noqa: E402
from sandmod.world.loading import load_world  # noqa: E402

SCALE = 2
GOO = '[mod]\nname = "goo"\n\n[elements.goo]\narchetype = "liquid"\ncolor = "#00ff00"\ndensity = 900\ndispersion = 2\n'


@pytest.fixture(autouse=True)
def _headless(tmp_path, monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.setenv("XDG_CACHE_HOME", os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache"))  # the kernel's
    monkeypatch.setenv("HOME", str(tmp_path / "home"))  # where play writes when no other folder will do
    monkeypatch.chdir(tmp_path)
    opened = Play.__init__

    def remembered(self, *args, **kwargs):
        opened(self, *args, **kwargs)
        Play.last = self

    monkeypatch.setattr(Play, "__init__", remembered)


def post(kind, **fields) -> None:
    pygame.event.post(pygame.event.Event(kind, **fields))


def at(x: int, y: int, play: Play | None = None) -> tuple[int, int]:
    """The window position of cell (x, y) (in the last window opened, unless ``play`` is given)."""
    view = (play or Play.last).view
    left, top = view.origin()
    return left + (x - view.corner[0]) * view.scale + 1, top + (y - view.corner[1]) * view.scale + 1


def frames(play: Play, count: int) -> None:
    for _ in range(count):
        play._one_frame()


def key(play: Play, name: int, mod: int = 0) -> None:
    post(pygame.KEYDOWN, key=name, mod=mod, unicode="")
    frames(play, 1)


def capture_outcome(play: Play) -> str:
    """What came of the last capture, waiting for it (the status line takes it once it is done)."""
    return play.capture_job.result(wait=True) if play.capture_job is not None else play.message


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
    assert play.message == "undid a paint" and play.session.world.frame == 12  # back to 11, then that frame's step
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
    assert capture_outcome(play).startswith("saved")
    assert Path("play-screenshot.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and Path("play-capture.gif").read_bytes()[:6] == b"GIF89a"


def test_saving_a_mod_reloads_it_and_a_broken_one_is_shown_while_the_old_rules_go_on():
    Path("mods").mkdir()
    mod = Path("mods/goo.toml")
    mod.write_text(GOO)
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
    view = play.view
    assert view.area == (1280, 800) and view.shown() == (640, 400)
    key(play, pygame.K_RIGHT)
    key(play, pygame.K_DOWN)
    assert view.corner == [160, 100] and view.cell_at((1, 1)) == (160, 100)
    key(play, pygame.K_RIGHT)
    assert view.corner == [160, 100]  # at the world's edge
    view.zoom(2, (0, 0))
    assert view.scale == 4 and view.shown() == (320, 200) and view.cell_at((0, 0)) == (160, 100)
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


# --- the screen is the world -------------------------------------------------------------------

def wrong_cells(play: Play) -> int:
    """Cells whose colour on the screen is not the world's (``world.rgb()``)."""
    view, world = play.view, play.session.world
    screen = pygame.surfarray.array3d(view.screen).transpose(1, 0, 2)
    left, top = view.origin()
    columns, rows = view.shown()
    shown = screen[top : top + rows * view.scale : view.scale, left : left + columns * view.scale : view.scale]
    x0, y0 = view.corner
    if view.heat_view:
        truth = world.heat_image()[y0 : y0 + rows, x0 : x0 + columns]
    else:
        truth = world.rgb()[y0 : y0 + rows, x0 : x0 + columns]
    return int((shown != truth).any(axis=2).sum())


def away(play: Play) -> None:
    """The mouse over the status line: no brush outline over the world, no tooltip."""
    pygame.mouse.set_pos((play.view.size[0] - 5, play.view.size[1] - 5))


def drag(play: Play, cells, button: int = 1) -> None:
    post(pygame.MOUSEBUTTONDOWN, pos=at(*cells[0]), button=button)
    for cell in cells[1:]:
        post(pygame.MOUSEMOTION, pos=at(*cell), rel=(0, 0), buttons=(1, 0, 0))
    post(pygame.MOUSEBUTTONUP, pos=at(*cells[-1]), button=button)
    frames(play, 1)


def test_after_every_kind_of_action_the_screen_shows_the_world_cell_for_cell():
    Path("mods").mkdir()
    mod = Path("mods/goo.toml")
    mod.write_text(GOO)
    play = Play(Session.open(None, size=(96, 64)), scale=SCALE, fixed_steps=2)
    play.next_mod_check = float("inf")
    ruleset = play.session.world.ruleset
    away(play)
    drag(play, [(5, 30), (60, 30)])  # sand, falling
    frames(play, 120)  # everything asleep
    assert play.session.world.awake_fraction == 0 and wrong_cells(play) == 0
    play.brush.element = ruleset.index("stone")  # into the quiet world: it stays where it is painted
    drag(play, [(70, 10), (90, 12)])
    away(play)
    frames(play, 3)
    assert wrong_cells(play) == 0 and (play.session.world.cells == play.brush.element).sum() > 20
    checks = {
        "erase": lambda: drag(play, [(20, 60), (30, 60)], button=3),
        "undo": lambda: key(play, pygame.K_z, pygame.KMOD_CTRL),
        "explode": lambda: (pygame.mouse.set_pos(at(40, 55)), key(play, pygame.K_x)),
        "spray": lambda: (pygame.mouse.set_pos(at(40, 20)), key(play, pygame.K_q), frames(play, 5), post(pygame.KEYUP, key=pygame.K_q, mod=0)),
        "undo again": lambda: key(play, pygame.K_z, pygame.KMOD_CTRL),
        "snapshot": lambda: key(play, pygame.K_F5),
        "paint": lambda: drag(play, [(10, 5), (50, 5)]),
        "load": lambda: key(play, pygame.K_F9),
        "clear": lambda: key(play, pygame.K_DELETE),
        "undo the clear": lambda: key(play, pygame.K_z, pygame.KMOD_CTRL),
        "heat view": lambda: key(play, pygame.K_v),
        "heat": lambda: (key(play, pygame.K_h), drag(play, [(10, 50), (30, 50)])),
        "cell view": lambda: key(play, pygame.K_v),
    }
    for action, do in checks.items():
        do()
        away(play)
        frames(play, 4)
        assert wrong_cells(play) == 0, action
    key(play, pygame.K_DELETE)  # water, goo floating on it, settled; then goo is made heavier than water
    play.brush.tool, play.brush.size = "paint", 9
    play.brush.element = ruleset.index("water")
    drag(play, [(2, 50), (93, 50)])
    frames(play, 60)
    play.brush.element, play.brush.size = ruleset.index("goo"), 3
    drag(play, [(2, 30), (93, 30)])
    away(play)
    frames(play, 200)
    mod.write_text(mod.read_text().replace("#00ff00", "#ff00ff").replace("density = 900", "density = 2500"))
    play.reload()
    assert play.message == "mods reloaded"
    frames(play, 1)
    assert wrong_cells(play) == 0, "reload"
    goo = play.session.world.ruleset.index("goo")
    low = lambda: float(np.nonzero(play.session.world.cells == goo)[0].mean())
    before = low()
    frames(play, 40)
    assert low() > before + 3, "settled goo feels its new density"
    assert wrong_cells(play) == 0


def test_the_screen_shows_a_world_of_more_than_256_colours_cell_for_cell():
    from conftest import walls_mod
    Path("mods").mkdir()
    Path("mods/walls.toml").write_text(walls_mod("walls", 280))
    play = Play(Session.open(None, size=(140, 40)), scale=SCALE, fixed_steps=1)
    world = play.session.world
    walls = [e.index for e in world.ruleset.elements if e.id.startswith("walls:")]
    for x in range(world.width):
        column = np.zeros((world.height, world.width), bool)
        column[10:, x] = True
        world.paint(column, walls[2 * x])
    away(play)
    frames(play, 2)
    assert len(np.unique(world.image())) > 256 and wrong_cells(play) == 0


def test_writing_where_it_cannot_is_a_message_and_play_goes_on(tmp_path):
    unwritable = Path("/proc")  # even for root, as tests in containers often are
    if not unwritable.is_dir():
        pytest.skip("needs /proc")
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1, session_path=unwritable / "w-session.toml")
    drag(play, [(5, 5), (20, 5)])
    for name in (pygame.K_s, pygame.K_p, pygame.K_F5, pygame.K_g):
        key(play, name)
    capture_outcome(play)
    assert play.saved_to == tmp_path / "w-session.toml"  # the current folder, the first being read-only
    assert {"w-session.toml", "play-screenshot.png", "play-snapshot.npz", "play-capture.gif"} <= {p.name for p in tmp_path.iterdir()}
    Path(tmp_path).chmod(0o555)
    try:
        key(play, pygame.K_s)  # the home folder, the current one being read-only too (unless we are root)
        assert play.running
    finally:
        Path(tmp_path).chmod(0o755)


def test_escape_with_unsaved_strokes_asks_and_the_close_button_saves():
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1)
    drag(play, [(5, 5), (20, 5)])
    key(play, pygame.K_ESCAPE)
    assert play.running and "not saved" in play.prompt
    key(play, pygame.K_a)  # any other key: stay
    assert play.running and not play.prompt
    key(play, pygame.K_ESCAPE)
    key(play, pygame.K_s)  # s: save, and quit
    assert not play.running and Path("play-session.toml").is_file()
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1)
    drag(play, [(5, 5), (20, 5)])
    post(pygame.QUIT)
    frames(play, 1)
    assert not play.running and "paint" in Path("play-session.toml").read_text()


def test_a_reload_that_cannot_apply_is_shown_and_the_old_rules_go_on():
    Path("mods").mkdir()
    mod = Path("mods/goo.toml")
    mod.write_text(GOO)
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1)
    play.next_mod_check = float("inf")
    play.brush.element = play.session.world.ruleset.index("goo")
    drag(play, [(5, 5), (20, 5)])
    frames(play, 2)
    mod.write_text(mod.read_text().replace("[elements.goo]", "[elements.slime]"))  # renamed, while the world holds goo
    play.reload()
    assert play.problems and play.session.world.ruleset.index("goo:goo") and play.running
    frames(play, 3)
    assert play.session.world.frame == 6 and (play.session.world.cells == play.brush.element).any()


def test_loading_a_snapshot_drops_the_strokes_after_it():
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1)
    key(play, pygame.K_F5)
    drag(play, [(5, 5), (20, 5)])
    frames(play, 5)
    key(play, pygame.K_F9)
    assert play.session.events == [] and not play.session.world.cells.any()
    frames(play, 10)
    assert not play.session.world.cells.any()
    play.do_save()
    assert "does not replay bit for bit (a snapshot was loaded at frame 0)" in play.message


def test_each_tool_is_an_undo_step_of_its_own():
    play = Play(Session.open(None, size=(64, 48)), scale=SCALE, fixed_steps=1)
    drag(play, [(5, 40), (50, 40)])
    pygame.mouse.set_pos(at(30, 20))
    key(play, pygame.K_q)
    frames(play, 4)
    post(pygame.KEYUP, key=pygame.K_q, mod=0)
    frames(play, 1)
    sprays = [e for e in play.session.events if "spawn" in e]
    assert len(sprays) == 5  # one a step while held
    key(play, pygame.K_x)
    key(play, pygame.K_DELETE)
    labels = []
    for _ in range(4):
        key(play, pygame.K_z, pygame.KMOD_CTRL)
        labels.append(play.message)
    assert labels == ["undid a clear", "undid a blast", "undid a spray", "undid a paint"]
    assert play.session.events == [] and play.session.world.frame == 1


def find(play: Play, text: str) -> None:
    """Type ``/``, then ``text``, then enter."""
    post(pygame.KEYDOWN, key=pygame.K_SLASH, mod=0, unicode="/")
    for letter in text:
        post(pygame.KEYDOWN, key=ord(letter), mod=0, unicode=letter)
    key(play, pygame.K_RETURN)


def test_search_prefers_the_exact_name_and_shows_its_matches_in_the_menu():
    play = Play(Session.open(None, size=(64, 48)), scale=SCALE, fixed_steps=1)
    ruleset = play.session.world.ruleset
    assert ruleset.elements[play.brush.element].id == "sand:sand"
    for typed, wanted in (("water", "water:water"), ("fire", "fire:fire"), ("sto", "base:stone")):
        find(play, typed)
        assert ruleset.elements[play.brush.element].id == wanted, typed
    key(play, pygame.K_SLASH)
    for letter in "as":
        post(pygame.KEYDOWN, key=ord(letter), mod=0, unicode=letter)
    frames(play, 1)
    shown = [what for _, (kind, what) in play.view.menu_items(play.menu) if kind == "element"]
    assert play.menu.current().name == FOUND and shown == play._matches() and {ruleset.elements[e].id for e in shown} >= {"fire:ash", "glass:glass", "lava:basalt"}
    key(play, pygame.K_ESCAPE)
    assert play.search is None and play.menu.found is None and ruleset.elements[play.brush.element].id == "base:stone"
    assert play.menu.current().name == FAVOURITES  # as before the search: stone is there
    find(play, "coal")
    assert play.menu.current().name == "powders" and ruleset.index("coal") in play.menu.on_page()  # where coal is


# --- the element menu --------------------------------------------------------------------------

def click(play: Play, rect) -> None:
    post(pygame.MOUSEBUTTONDOWN, pos=(rect[0] + rect[2] // 2, rect[1] + rect[3] // 2), button=1)
    post(pygame.MOUSEBUTTONUP, pos=(rect[0] + rect[2] // 2, rect[1] + rect[3] // 2), button=1)
    frames(play, 1)


def rect_of(play: Play, kind: str, what) -> tuple[int, int, int, int]:
    """Where the menu shows the tab, button or swatch that does (kind, what)."""
    return next(rect for rect, action in play.view.menu_items(play.menu) if action == (kind, what))


def test_a_tab_shows_its_section_as_labelled_swatches_and_a_click_takes_one():
    play = Play(Session.open(None, size=(64, 48)), scale=SCALE, fixed_steps=1)
    ruleset, view = play.session.world.ruleset, play.view
    click(play, rect_of(play, "section", "liquids"))
    liquids = [e for e in offered(ruleset) if ruleset.elements[e].spec.menu_category == "liquids"]  # nitroglycerin is with the explosives
    shown = [(rect, what) for rect, (kind, what) in view.menu_items(play.menu) if kind == "element"]
    assert play.menu.current().name == "liquids" and [what for _, what in shown] == liquids
    screen = pygame.surfarray.array3d(view.screen).transpose(1, 0, 2)
    for (left, top, width, height), element in shown:
        inside = screen[top + 2 : top + height - 2, left + 2 : left + width - 2].reshape(-1, 3)
        colours = {tuple(int(c) for c in rgb) for rgb in inside}
        swatch = ruleset.swatch(element)
        assert colours >= {swatch, ink(swatch)}, ruleset.elements[element].id  # the swatch, its name on it
        assert view.font.size(ruleset.elements[element].name)[0] <= width - 10  # the whole name
    water = ruleset.index("water")
    click(play, rect_of(play, "element", water))
    assert play.brush.element == water
    left, top, width, height = rect_of(play, "element", water)
    pygame.mouse.set_pos((left + 4, top + 4))
    frames(play, 1)
    screen = pygame.surfarray.array3d(view.screen)
    assert (screen[left, top : top + height] == CHOSEN).all() and (screen[left + width - 1, top : top + height] == CHOSEN).all()  # framed
    status = screen[:, view.size[1] - STATUS :]
    text = view.font.render("water:water   liquid, mod water, in liquids", True, TEXT)
    drawn = pygame.Surface(text.get_size())
    drawn.fill(PANEL)
    drawn.blit(text, (0, 0))
    drawn = pygame.surfarray.array3d(drawn)
    assert (status[MARGIN : MARGIN + drawn.shape[0], 3 : 3 + drawn.shape[1]] == drawn).all()  # hovered: its id, archetype, mod, section
    assert view.size[1] == view.area[1] + MENU + STATUS  # the menu below the world, not over it


def test_the_keys_move_through_sections_elements_and_pages():
    play = Play(Session.open(None, size=(64, 48)), scale=SCALE, fixed_steps=1)
    ruleset, menu = play.session.world.ruleset, play.menu
    names = [s.name for s in menu.tabs()]
    assert names[:5] == [FAVOURITES, "powders", "liquids", "gases", "solids"] and {"energy", "explosives"} <= set(names)
    key(play, pygame.K_TAB)
    assert menu.current().name == "powders"
    key(play, pygame.K_TAB, pygame.KMOD_SHIFT)
    key(play, pygame.K_TAB, pygame.KMOD_SHIFT)
    assert menu.current().name == names[-1]
    key(play, pygame.K_TAB)
    key(play, pygame.K_TAB)
    powders = [ruleset.elements[e].id for e in menu.current().elements]
    assert powders == sorted(powders, key=lambda id: id.split(":")[1])  # by name
    assert {"fire:ash", "lava:basalt", "coal:coal", "dirt:dirt", "base:rubble", "sand:sand", "glass:shards"} <= set(powders)
    after_sand = powders[powders.index("sand:sand") + 1]
    key(play, pygame.K_PERIOD)  # after sand, the next
    assert play.brush.element == ruleset.index(after_sand)
    play.brush.element = ruleset.index(powders[-1])
    key(play, pygame.K_PERIOD)  # after the last: round to the first
    assert play.brush.element == ruleset.index(powders[0])
    key(play, pygame.K_COMMA)
    assert play.brush.element == ruleset.index(powders[-1])
    menu.per_page = 2  # pages, as a window too narrow for a section would have
    key(play, pygame.K_PAGEDOWN)
    assert menu.page == 1 and menu.on_page() == menu.current().elements[2:4]
    key(play, pygame.K_PAGEUP)
    key(play, pygame.K_PAGEUP)
    assert menu.page == 0
    pygame.mouse.set_pos((10, play.view.area[1] + 30))
    post(pygame.MOUSEWHEEL, x=0, y=-1)  # the wheel over the menu turns its pages, not the brush's size
    frames(play, 1)
    assert menu.page == 1 and play.brush.size == 5


def test_the_number_keys_give_the_favourites_and_m_pins_and_unpins():
    play = Play(Session.open(None, size=(64, 48)), scale=SCALE, fixed_steps=1)
    menu = play.menu
    ids = lambda elements: [play.session.world.ruleset.elements[e].id for e in elements]  # noqa: E731
    assert ids(menu.favourites)[:4] == ["sand:sand", "water:water", "base:stone", "fire:fire"] and len(menu.favourites) == KEYED
    for number, wanted in ((pygame.K_2, "water:water"), (pygame.K_1, "sand:sand"), (pygame.K_4, "fire:fire")):
        key(play, number)
        assert ids([play.brush.element]) == [wanted] and menu.current().name == FAVOURITES
    find(play, "coal")
    key(play, pygame.K_m)
    assert ids(menu.favourites)[-1] == "coal:coal" and play.message == "coal is favourite 10: keys 1-9 give the first 9"
    key(play, pygame.K_1)
    key(play, pygame.K_m)
    assert play.message == "sand is no longer a favourite" and ids(menu.favourites)[:2] == ["water:water", "base:stone"]
    key(play, pygame.K_9)
    assert ids([play.brush.element]) == ["coal:coal"]  # tenth, now ninth
    find(play, "coal")
    key(play, pygame.K_m)
    key(play, pygame.K_1)
    assert "coal:coal" not in ids(menu.favourites) and ids([play.brush.element]) == ["water:water"]
    Path("mods").mkdir()  # a reload keeps them, and the section shown
    Path("mods/goo.toml").write_text(GOO)
    assert menu.current().name == "liquids"  # water is not among the powders shown after coal was found
    key(play, pygame.K_TAB)
    pinned = ids(menu.favourites)
    play.reload()
    assert play.message == "mods reloaded" and ids(play.menu.favourites) == pinned and play.menu.current().name == "gases"
    liquids = next(s.elements for s in play.menu.sections if s.name == "liquids")
    assert play.session.world.ruleset.index("goo") in liquids


SECTIONS = ("metals", "plants", "machines", "food", "minerals", "weather", "space", "favourites", "tools", "found")  # the last two: tabs apart from the menu's own
FIELDS = {"powder": "density = 1500", "liquid": "density = 1000\ndispersion = 2", "gas": "density = 0.5\ndispersion = 2", "static": ""}
#: 20 packs of 25 elements: 500 in all.
PACKS, PER_PACK = 20, 25


def mod_packs(folder: Path, packs: int, per_pack: int) -> None:
    """Mod packs, as a user installs them: ``packs`` mod files of ``per_pack`` elements each, of every
    archetype, some in sections of their own, some hidden, some with long names."""
    folder.mkdir()
    for pack in range(packs):
        text = f'[mod]\nname = "pack{pack:02d}"\n'
        for n in range(per_pack):
            archetype = tuple(FIELDS)[n % 4]
            name = f"p{pack:02d}_{archetype}_{n}{'_with_a_long_name' if n % 7 == 3 else ''}"
            colour = f"#{pack * 53 % 256:02x}{n * 97 % 256:02x}{pack * n * 31 % 256:02x}"
            text += f'\n[elements.{name}]\narchetype = "{archetype}"\ncolor = "{colour}"\n{FIELDS[archetype]}\n'
            text += f'category = "{SECTIONS[(pack + n) % len(SECTIONS)]}"\n' if n % 5 == 1 else ""
            text += "hidden = true\n" if n % 11 == 10 else ""
        (folder / f"pack{pack:02d}.toml").write_text(text)


def test_with_hundreds_of_elements_each_is_reached_by_tab_page_and_swatch_and_by_search():
    mod_packs(Path("mods"), PACKS, PER_PACK)
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1)
    ruleset, menu = play.session.world.ruleset, play.menu
    generated = [e for e in offered(ruleset) if ruleset.elements[e].mod.startswith("pack")]
    bundled = {e.spec.menu_category for e in ruleset.elements if not e.mod.startswith("pack") and not e.spec.hidden} - {"powders", "liquids", "gases", "solids", "empty", "particles"}
    assert len(generated) == PACKS * PER_PACK and len(menu.tabs()) == 1 + 4 + len(bundled - set(SECTIONS)) + len(SECTIONS)  # more than a row holds
    reached = set()
    for _ in menu.tabs():
        actions = [action for _, action in play.view.menu_items(menu)]
        assert ("section", menu.current().name) in actions  # its tab, scrolled into the row
        for page in range(menu.pages()):
            assert menu.page == page
            for rect, (kind, element) in play.view.menu_items(menu):
                if kind == "element":
                    click(play, rect)
                    assert play.brush.element == element and menu.page == page
                    reached.add(element)
            click(play, rect_of(play, "page", 1))
        click(play, rect_of(play, "sections", 1))
    assert menu.current().name == FAVOURITES and reached == set(listed(ruleset))
    hidden = set(offered(ruleset)) - reached
    in_packs = [e for e in hidden if ruleset.elements[e].mod.startswith("pack")]  # the bundled mods hide some forms too (a spark, a lit lamp)
    assert len(in_packs) == PACKS * (PER_PACK // 11) and all(ruleset.elements[e].spec.hidden for e in hidden)
    for element in offered(ruleset):  # the hidden ones too
        find(play, ruleset.elements[element].id)
        assert play.brush.element == element, ruleset.elements[element].id


def test_without_the_bundled_elements_the_favourites_are_the_first_of_each_section():
    mod_packs(Path("mods"), 2, 10)
    Path("w.toml").write_text('[world]\nwidth = 40\nheight = 30\nmods = ["pack00", "pack01"]\n')
    play = Play(Session.open(Path("w.toml")), scale=SCALE, fixed_steps=1)
    ruleset, menu = play.session.world.ruleset, play.menu
    favourites = [ruleset.elements[e] for e in menu.favourites]
    assert menu.favourites[0] == play.brush.element and favourites[0].id == "pack00:p00_powder_0"
    assert "base:stone" in [e.id for e in favourites] and len(favourites) == KEYED
    assert {s.elements[0] for s in menu.sections} <= set(menu.favourites) and not any(e.spec.hidden for e in favourites)


def test_contrast_picks_the_ink_that_reads_on_any_swatch():
    for rgb in np.ndindex(9, 9, 9):
        back = tuple(min(255, c * 32) for c in rgb)
        assert contrast(ink(back), back) >= 4.5, back


def test_consecutive_moves_of_one_stroke_on_a_frame_are_one_event():
    play = Play(Session.open(None, size=(64, 48)), scale=SCALE, fixed_steps=1)
    key(play, pygame.K_SPACE)  # paused: every move is on one frame
    drag(play, [(5, 5), (10, 6), (15, 8), (20, 8), (30, 9)])
    assert len(play.session.events) == 1 and len(play.session.events[0]["paint"]["points"]) == 5
    key(play, pygame.K_SPACE)
    frames(play, 3)
    play.do_save()
    replay = load_world("play-session.toml")
    for _ in range(replay.spec.render.frames):
        replay.world.step()
    assert state_digest(replay.world) == state_digest(play.session.world)


# --- play never loses work ---------------------------------------------------------------------

def read_only(folder: Path, name: str) -> None:
    """Make writing ``name`` into ``folder`` fail, as in a read-only folder: its mode, and (since root
    ignores modes) a folder where the file would go."""
    (folder / name).mkdir()
    folder.chmod(0o555)


def replayed(path: Path):
    """The world file at ``path``, rendered to its last frame (its mods found only as render finds them)."""
    replay = load_world(path)
    replay.world.run(replay.spec.render.frames)
    return replay.world


def test_a_session_saved_away_from_a_read_only_world_renders_where_it_is_saved(tmp_path, monkeypatch):
    shared, here = tmp_path / "shared", tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    (shared / "mods").mkdir(parents=True)
    (shared / "mods" / "goo.toml").write_text(GOO)
    (shared / "w.toml").write_text('[world]\nwidth = 40\nheight = 30\nmods = ["goo"]\n')
    read_only(shared, "w-session.toml")
    try:
        play = Play(Session.open(shared / "w.toml"), scale=SCALE, fixed_steps=1, session_path=shared / "w-session.toml")
        drag(play, [(5, 5), (30, 5)])
        frames(play, 5)
        key(play, pygame.K_SPACE)  # paused, so that the world is at the frame saved
        key(play, pygame.K_s)
    finally:
        shared.chmod(0o755)
    assert play.saved_to == here / "w-session.toml"  # the current folder: shared/ would not take it
    assert play.message == f"saved {play.saved_to}: sandmod render w-session.toml replays it"
    assert (here / "w-session-mods" / "goo.toml").read_text() == GOO and not Path("mods").exists()
    result = CliRunner().invoke(cli, ["render", "w-session.toml", "-q"])
    assert result.exit_code == 0, result.output
    assert state_digest(replayed(here / "w-session.toml")) == state_digest(play.session.world)
    assert play.session.world.counts()["goo:goo"] > 20


def scripted_close(monkeypatch) -> None:
    """Each window the command line opens gets a stroke, then the close button."""
    run = Play.run

    def closed(self, frames=None):
        post(pygame.MOUSEBUTTONDOWN, pos=at(5, 5, self), button=1)
        post(pygame.MOUSEBUTTONUP, pos=at(20, 5, self), button=1)
        post(pygame.QUIT)
        run(self, frames)

    monkeypatch.setattr(Play, "run", closed)


@pytest.mark.parametrize("temporary", ["tmp", "gone"])
def test_the_close_button_with_nowhere_to_write_says_where_the_session_went_and_exits_1(tmp_path, monkeypatch, temporary):
    home = tmp_path / "home"
    home.mkdir()
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / temporary))
    scripted_close(monkeypatch)
    read_only(home, "play-session.toml")
    read_only(tmp_path, "play-session.toml")
    try:
        result = CliRunner().invoke(cli, ["play", "--size", "40x30"])
    finally:
        tmp_path.chmod(0o755)
        home.chmod(0o755)
    assert result.exit_code == 1 and result.stdout == ""
    said = result.stderr.splitlines()[-1]  # after what compiling the kernels said, if it had to
    written = list((tmp_path / "tmp").glob("sandmod-play-*/play-session.toml"))
    if temporary == "gone":
        assert written == [] and said == f"the session was not saved: not in {tmp_path}, {home}, nor in a temporary folder (No such file or directory)"
        return
    assert said == f"the session was not saved in {tmp_path}, {home}; it was written to {written[0]} instead"
    assert replayed(written[0]).counts()["sand:sand"] > 20


def test_the_close_button_saves_and_the_terminal_says_where(tmp_path, monkeypatch):
    scripted_close(monkeypatch)
    result = CliRunner().invoke(cli, ["play", "--size", "40x30"])
    assert result.exit_code == 0 and "not saved" not in result.stderr
    assert result.stdout.splitlines()[-1] == "saved play-session.toml: sandmod render play-session.toml replays it"
    assert "paint" in (tmp_path / "play-session.toml").read_text()


def test_past_the_sessions_limit_painting_goes_on_and_what_was_saved_replays(monkeypatch):
    play = Play(Session.open(None, size=(64, 48)), scale=SCALE, fixed_steps=1)
    drag(play, [(5, 5), (20, 5)])
    frames(play, 3)
    monkeypatch.setattr(session_module, "MAX_RECORD_BYTES", play.session.record_bytes)  # full: as a real session fills up
    full, at_full = play.session.world.frame, state_digest(play.session.world)
    play.brush.element = play.session.world.ruleset.index("stone")
    drag(play, [(5, 30), (40, 30)])
    assert play.message == f"session full: painting goes on, but strokes from frame {full} on are not saved (s saves the rest)"
    away(play)
    frames(play, 2)
    stone = (play.session.world.cells == play.brush.element).sum()
    assert stone > 50 and wrong_cells(play) == 0  # in the world, and on the screen
    play.do_save()
    assert play.message.endswith(f"does not replay bit for bit (the session was full at frame {full}: it replays up to there)")
    assert state_digest(replayed(Path("play-session.toml"))) == at_full


def test_the_quit_prompt_counts_what_is_not_saved():
    play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1)
    drag(play, [(5, 5), (20, 5)])
    drag(play, [(5, 15), (20, 15)])
    key(play, pygame.K_s)
    drag(play, [(5, 25), (20, 25)])
    key(play, pygame.K_ESCAPE)
    assert play.prompt.startswith("1 action not saved:") and play.view.said[0][0].startswith("1 action not saved:")
    key(play, pygame.K_a)
    key(play, pygame.K_z, pygame.KMOD_CTRL)
    key(play, pygame.K_z, pygame.KMOD_CTRL)
    key(play, pygame.K_ESCAPE)
    assert play.prompt.startswith("1 undone action not saved:")


def test_a_long_message_is_drawn_whole_in_lines_that_fit_the_window(tmp_path):
    (tmp_path / "home").mkdir()
    read_only(tmp_path / "home", "w-session.toml")
    read_only(tmp_path, "w-session.toml")
    try:
        play = Play(Session.open(None, size=(40, 30)), scale=SCALE, fixed_steps=1, session_path=Path("/proc/w-session.toml"))
        drag(play, [(5, 5), (20, 5)])
        key(play, pygame.K_s)
    finally:
        tmp_path.chmod(0o755)
        (tmp_path / "home").chmod(0o755)
    view, message = play.view, play.message
    assert message.startswith(f"could not save w-session.toml in /proc, {tmp_path}, {tmp_path / 'home'}: ")
    assert view.size[0] == 640 and view.font.size(message)[0] > 640 and len(view.said) > 1
    assert "".join(line for line, _ in view.said) == message
    screen = pygame.surfarray.array3d(view.screen)
    for line, rect in view.said:
        assert 0 <= rect.left and rect.right <= view.size[0] - 6, line
        drawn = pygame.Surface(rect.size)
        drawn.fill(PANEL)
        drawn.blit(view.font.render(line, True, TEXT), (0, 0))
        assert (pygame.surfarray.array3d(drawn) == screen[rect.left : rect.right, rect.top : rect.bottom]).all(), line


DEFAULTS = {"acid_wall": "acid:acid", "boiling_pool": "lava:lava", "forest_fire": "dirt:dirt", "garden": "plants:algae", "lava_lake": "lava:lava"}


@pytest.mark.parametrize("world", sorted(p for p in Path(__file__).parent.parent.glob("examples/*.toml") if "[sweep]" not in p.read_text()), ids=lambda p: p.stem)
def test_each_example_starts_with_a_brush_of_its_own_story(world):
    play = Play(Session.open(world), scale=1, fixed_steps=1)
    ruleset = play.session.world.ruleset
    chosen = ruleset.elements[play.brush.element]
    assert chosen.id == DEFAULTS.get(world.stem, "sand:sand")
    assert chosen.mod in play.session.loaded.spec.world.mods and chosen.spec.archetype in ("powder", "liquid")
    away(play)
    frames(play, 1)
    assert f"   {chosen.name} 5" in play._status()
