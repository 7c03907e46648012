"""A play session: what the player does is recorded as a world file that replays it bit for bit;
undo goes back a stroke; mods saved while playing are reloaded, or their problems shown."""

from __future__ import annotations

from pathlib import Path

import pytest

from sandmod.errors import ProblemsError
from sandmod.jobs.benchmark import state_digest
from sandmod.jobs import session as session_module
from sandmod.jobs.session import Session
from sandmod.jobs.undo import History
from sandmod.world.loading import load_world

WORLD = """
[world]
width = 64
height = 48
seed = 3
mods = ["sand", "water", "explosives"]

[[scene]]
shape = "rect"
element = "stone"
x = 0
y = 44
width = 64
height = 4

[[emitters]]
shape = "rect"
element = "water"
x = 50
y = 0
width = 4
height = 2
chance = 0.3
"""


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def played(session: Session) -> None:
    """Strokes, an erase, heat, a spray and a blast, some while paused (two events on one frame)."""
    session.checkpoint("paint")
    session.add("paint", {"shape": "stroke", "points": [[10, 10], [30, 12]], "thickness": 3, "element": "sand"})
    for _ in range(5):
        session.step()
    session.add("paint", {"shape": "stroke", "points": [[30, 12], [40, 20]], "thickness": 3, "element": "sand"})
    session.add("paint", {"shape": "rect", "x": 5, "y": 30, "width": 20, "height": 6, "element": "water", "over": "empty"})
    for _ in range(10):
        session.step()
    session.checkpoint("paint")
    session.add("erase", {"shape": "stroke", "points": [[20, 40], [25, 43]], "thickness": 4})
    session.add("heat", {"shape": "rect", "x": 0, "y": 40, "width": 10, "height": 4, "temperature": 800.0})
    session.add("spawn", {"element": "sand", "at": [32, 5], "radius": 2, "count": 10, "direction": 90, "spread": 90, "speed": [1, 2]})
    session.add("explode", {"at": [40, 40], "radius": 5, "strength": 10.0})
    session.add("launch", {"shape": "circle", "x": 20, "y": 42, "radius": 4, "speed": [2, 4], "spread": 90})
    for _ in range(20):
        session.step()


def test_the_saved_world_file_replays_the_session_bit_for_bit(tmp_path):
    Path("w.toml").write_text(WORLD)
    session = Session.open(Path("w.toml"))
    played(session)
    session.save(Path("w-session.toml"))
    replay = load_world("w-session.toml")
    for _ in range(replay.spec.render.frames):
        replay.world.step()
    assert replay.world.frame == session.world.frame == 35
    assert state_digest(replay.world) == state_digest(session.world)


def test_a_session_without_a_world_file_replays_too(tmp_path):
    session = Session.open(None, size=(48, 40))
    session.checkpoint("paint")
    session.add("paint", {"shape": "stroke", "points": [[5, 5], [40, 5]], "thickness": 5, "element": "sand"})
    for _ in range(30):
        session.step()
    session.save(Path("play-session.toml"))
    replay = load_world("play-session.toml")
    for _ in range(replay.spec.render.frames):
        replay.world.step()
    assert state_digest(replay.world) == state_digest(session.world)
    assert replay.world.counts()["sand:sand"] > 100


def test_undo_goes_back_to_before_the_last_stroke_and_forgets_it(tmp_path):
    Path("w.toml").write_text(WORLD)
    session = Session.open(Path("w.toml"))
    for _ in range(5):
        session.step()
    before = state_digest(session.world)
    session.checkpoint("paint")
    session.add("paint", {"shape": "circle", "x": 20, "y": 20, "radius": 6, "element": "sand"})
    for _ in range(8):
        session.step()
    assert session.undo() == "paint" and session.world.frame == 5 and state_digest(session.world) == before
    assert session.events == [] and session.undo() is None
    for _ in range(8):  # and the world goes on as if the stroke never was
        session.step()
    fresh = load_world("w.toml").world
    for _ in range(13):
        fresh.step()
    assert state_digest(fresh) == state_digest(session.world)


def test_a_mistake_in_an_event_is_a_problem_and_records_nothing(tmp_path):
    session = Session.open(None, size=(32, 32))
    with pytest.raises(ProblemsError) as caught:
        session.add("paint", {"shape": "circle", "x": 5, "y": 5, "radius": 2, "element": "nosuch"})
    assert "nosuch" in str(caught.value.problems[0]) and session.events == []


def test_a_mod_saved_while_playing_is_reloaded_keeping_every_cell(tmp_path):
    Path("mods").mkdir()
    mod = Path("mods/goo.toml")
    mod.write_text('[mod]\nname = "goo"\n\n[elements.goo]\narchetype = "liquid"\ncolor = "#00ff00"\ndensity = 900\ndispersion = 2\n')
    session = Session.open(None, size=(40, 30))
    session.add("paint", {"shape": "rect", "x": 5, "y": 20, "width": 30, "height": 5, "element": "goo"})
    session.step()
    goo = session.world.counts()["goo:goo"]
    assert not session.mods_changed()
    mod.write_text(mod.read_text().replace("#00ff00", "#ff00ff"))
    assert session.mods_changed()
    assert session.reload_mods() == []
    ruleset = session.world.ruleset
    assert ruleset.elements[ruleset.index("goo")].spec.color == ["#ff00ff"]
    assert session.world.counts()["goo:goo"] == goo and session.world.frame == 1
    mod.write_text(mod.read_text().replace("density = 900", "density = -1"))
    problems = session.reload_mods()
    assert problems and "goo.toml" in problems[0] and "density" in problems[0]
    assert session.world.ruleset is ruleset  # the old rules go on


def test_undo_keeps_the_blocks_each_action_changed_within_its_budget(tmp_path):
    session = Session.open(None, size=(1024, 512))
    state_bytes = sum(a.nbytes for a in session.world.state)
    digests = []
    for number in range(25):  # stone: it stays where it is painted, so each step changes a few blocks
        digests.append(state_digest(session.world))
        session.checkpoint("paint")
        session.add("paint", {"shape": "circle", "x": 40 * number + 10, "y": 100, "radius": 4, "element": "stone"})
        session.step()
    history = session.history
    assert len(history.points) == 25 and history.nbytes < state_bytes + 25 * 8 * 64 * 64 * 4
    for number in reversed(range(25)):
        assert session.undo() == "paint" and state_digest(session.world) == digests[number]
    assert session.undo() is None
    small = History(memory=state_bytes - 1)
    assert not small.push("paint", 0, 0, list(session.world.state), [])  # one copy would pass it: no undo
    assert small.points == []


def test_a_full_session_goes_on_unrecorded_and_what_it_saved_replays(tmp_path, monkeypatch):
    monkeypatch.setattr(session_module, "MAX_EVENTS", 3)
    session = Session.open(None, size=(48, 40))
    for number in range(3):
        assert session.add("paint", {"shape": "circle", "x": 10 + 5 * number, "y": 5, "radius": 2, "element": "sand"})
        session.step()
    recorded = state_digest(session.world)
    assert not session.add("paint", {"shape": "circle", "x": 40, "y": 5, "radius": 2, "element": "sand"})
    assert session.full_at == 3 and len(session.events) == 3
    session.step()
    assert state_digest(session.world) != recorded  # the stroke past the limit is in the world
    session.save(Path("s.toml"))
    assert "the session was full at frame 3: it replays up to there" in session.caveats
    replay = load_world("s.toml")
    assert replay.spec.render.frames == 3
    replay.world.run(replay.spec.render.frames)
    assert state_digest(replay.world) == recorded


def test_undo_back_before_the_session_was_full_records_again(tmp_path, monkeypatch):
    monkeypatch.setattr(session_module, "MAX_EVENTS", 1)
    session = Session.open(None, size=(48, 40))
    session.checkpoint("paint")
    assert session.add("paint", {"shape": "circle", "x": 10, "y": 5, "radius": 2, "element": "sand"})
    session.step()
    session.checkpoint("paint")
    assert not session.add("paint", {"shape": "circle", "x": 20, "y": 5, "radius": 2, "element": "sand"})
    session.step()
    assert session.undo() == "paint" and session.full_at is None and session.caveats == []
    assert session.world.counts()["sand:sand"] == load_world_after(session, 1)


def load_world_after(session: Session, frames: int) -> int:
    """The sand a replay of the session's saved file holds after ``frames`` frames."""
    session.save(Path("u.toml"))
    replay = load_world("u.toml")
    replay.world.run(frames)
    return replay.world.counts()["sand:sand"]


GOO = '[mod]\nname = "goo"\n\n[elements.goo]\narchetype = "liquid"\ncolor = "#00ff00"\ndensity = 900\ndispersion = 2\n'
PICTURED = WORLD.replace('mods = ["sand", "water", "explosives"]', 'mods = ["sand", "water", "explosives", "goo"]') + """
[[scene]]
shape = "image"
file = "pictures/level.png"
x = 10
y = 10
legend = { "#ff0000" = "goo" }
"""


def test_a_session_saved_anywhere_brings_its_mods_and_pictures(tmp_path):
    from PIL import Image

    shared = tmp_path / "shared"
    (shared / "mods").mkdir(parents=True)
    (shared / "pictures").mkdir()
    (shared / "mods" / "slime.toml").write_text(GOO)  # a file not named after its mod
    Image.new("RGB", (8, 4), "#ff0000").save(shared / "pictures" / "level.png")
    (shared / "w.toml").write_text(PICTURED)
    session = Session.open(shared / "w.toml")
    played(session)
    for saved, mods, picture in [
        (tmp_path / "away" / "w-session.toml", "w-session-mods", "w-session-pictures/pictures/level.png"),  # copies beside it
        (tmp_path / "w-session.toml", "shared/mods", "shared/pictures/level.png"),  # under its folder: named
    ]:
        saved.parent.mkdir(exist_ok=True)
        session.save(saved)
        text = saved.read_text()
        assert f'mod_folders = [\n    "{mods}",\n]' in text and f'file = "{picture}"' in text
        replay = load_world(saved)  # the current folder has no mods/: only what the file names is found
        replay.world.run(replay.spec.render.frames)
        assert state_digest(replay.world) == state_digest(session.world) and replay.world.counts()["goo:goo"] > 0
    assert (tmp_path / "away" / "w-session-mods" / "slime.toml").read_text() == GOO
    assert not (tmp_path / "w-session-mods").exists() and not (tmp_path / "w-session-pictures").exists()
