"""A play session: a world stepped live, what the player does to it, undo, mods reloaded as they
are saved, and the world file that replays it all.

Everything the player does to the world is a timeline event of the world-file format, set up by
the same code that sets up a world file's timeline (:func:`sandmod.world.scene.add_event`) and
applied by the world on its frame. So the world file :meth:`Session.save` writes, the starting
world with the session's events in its ``[[timeline]]``, renders to the same frames bit for bit.
This module knows nothing of windows: :mod:`sandmod.jobs.play` drives it.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import tomli_w

from ..errors import ProblemsError
from ..formats.recording import atomic_path
from ..formats.tomlsource import TomlSource
from ..formats.userfiles import MAX_TEXT_BYTES
from ..formats.validation import validate
from ..formats.worldspec import MAX_TIMELINE, Event, WorldFile
from ..world.loading import LoadedWorld, load_world_spec, read_world_spec, world_mod_folders, world_rules
from ..world.scene import add_event, build_world
from ..world.world import World
from .undo import History

#: The size of a world played without a world file.
DEFAULT_SIZE = (320, 200)

#: Events the record holds: a world file's timeline can hold no more.
MAX_EVENTS = MAX_TIMELINE
#: The record's size in a world file, beside the starting file (what a world file may hold, less a margin).
#: It binds before MAX_EVENTS: a stroke's move takes about 185 bytes, so about 21,000 moves fill it.
MAX_RECORD_BYTES = MAX_TEXT_BYTES - 256 * 2**10


def _size(event: dict[str, Any]) -> int:
    """An event's bytes in a world file."""
    return len(tomli_w.dumps({"timeline": [event]}))


@dataclass
class Session:
    """A world being played. Open one with :meth:`open`."""

    loaded: LoadedWorld
    mod_dirs: list[Path]
    data: dict[str, Any]  # the starting world file's tables, without the session's events
    events: list[dict[str, Any]] = field(default_factory=list)  # what the player did, as [[timeline]] tables
    history: History = field(default_factory=History)
    _added: list[list] | None = None  # what the last event set up in the world, while it may be joined
    mod_files: dict[Path, tuple[int, int]] = field(default_factory=dict)  # what the mods' folders held: (mtime, size)
    not_replayed: list[str] = field(default_factory=list)  # why the saved world file would not replay the session
    changes: int = 0  # what the player did to the record: events added, undone, dropped
    saved_changes: int = 0  # ... when it was last saved
    record_bytes: int = 0  # the events' size in a world file
    saved_events: list[dict[str, Any]] = field(default_factory=list)  # the record when it was last saved
    full_at: int | None = None  # the frame from which what the player does is not recorded (the record is full)

    @classmethod
    def open(cls, path: Path | None = None, *, size: tuple[int, int] | None = None, mod_dirs: Iterable[Path] = ()) -> "Session":
        """A session on the world file ``path``, or on an empty world of ``size`` (width, height)
        loading every mod found. ProblemsError names what is wrong with either."""
        mod_dirs = [Path(d) for d in mod_dirs]
        if path is None:
            width, height = size or DEFAULT_SIZE
            data: dict[str, Any] = {"world": {"width": width, "height": height}}
            source = TomlSource("play", "", data, folder=Path.cwd())
            path = Path.cwd() / "play.toml"
            spec = validate(WorldFile, source)
        else:
            path = Path(path)
            spec, source = read_world_spec(path)
            if size is not None:
                raise ProblemsError([source.problem(("world",), "--size is for a new world; a world file has its own")])
            data = source.data
        loaded = load_world_spec(spec, source, path, mod_dirs=mod_dirs)
        session = cls(loaded, mod_dirs, data)
        session.mod_files = session._mod_files()
        return session

    @property
    def world(self) -> World:
        return self.loaded.world

    @property
    def unsaved(self) -> bool:
        """Has the player done anything since the session was last saved (or opened)?"""
        return self.changes != self.saved_changes

    def unsaved_events(self) -> tuple[int, int]:
        """(recorded since the last save, saved but undone or dropped since): what a save would change."""
        same = 0
        for now, saved in zip(self.events, self.saved_events):
            if now != saved:
                break
            same += 1
        return len(self.events) - same, len(self.saved_events) - same

    @property
    def caveats(self) -> list[str]:
        """Why the world file :meth:`save` writes would not replay the session bit for bit (none: it would)."""
        full = [f"the session was full at frame {self.full_at}: it replays up to there"] if self.full_at is not None else []
        return [*self.not_replayed, *full]

    # --- what the player does ---------------------------------------------------------------

    def add(self, action: str, table: dict[str, Any]) -> bool:
        """Do ``action`` ("paint", "erase", "heat", "spawn", "launch" or "explode": a timeline action,
        ``table`` as a world file writes it) before the next step. A stroke that goes on from the last
        event's end on the same frame joins it. ProblemsError if it is not an action. Returns whether
        it was recorded: once the record holds what a world file can, the world still changes but
        nothing more is recorded (:attr:`full_at`)."""
        event = {"frame": self.world.frame, action: table}
        if self.full_at is None:
            joined = self._joined(event)
            if self._fits(joined or event, joined is not None):
                if joined is not None:
                    self._forget_last()
                self._record(joined or event)
                return True
        self._apply(event)
        self._added = None
        self.full_at = self.world.frame if self.full_at is None else self.full_at
        return False

    def _fits(self, event: dict[str, Any], joins: bool) -> bool:
        """Would the record, with ``event`` (in place of the last event, if it ``joins`` it), fit a world file?"""
        events, size = len(self.events) + 1, self.record_bytes + _size(event)
        if joins:
            events, size = events - 1, size - _size(self.events[-1])
        return events <= MAX_EVENTS and size <= MAX_RECORD_BYTES

    def _record(self, event: dict[str, Any]) -> None:
        self._added = self._apply(event)
        self.events.append(event)
        self.record_bytes += _size(event)
        self.changes += 1

    def _apply(self, event: dict[str, Any]) -> list[list]:
        """Set ``event`` up in the world (after the recorded ones in the timeline); the world's lists it added to."""
        spec = self.loaded.spec
        spec.timeline.append(validate(Event, TomlSource("play", "", event, folder=self.loaded.source.folder)))
        lists = self._world_lists()
        before = [len(items) for items in lists]
        try:
            add_event(self.world, spec, self.loaded.source, len(spec.timeline) - 1)
        except ProblemsError:
            spec.timeline.pop()
            raise
        return [items for items, length in zip(lists, before) if len(items) > length]

    def _world_lists(self) -> list[list]:
        world = self.world
        return [world.paintings, world.heaters, world.sprays, world.launchers, world.scheduled]

    def _joined(self, event: dict[str, Any]) -> dict[str, Any] | None:
        """``event`` and the last one as one stroke, if they are strokes of one brush on this frame and
        this one starts where that one ends (None if not)."""
        if not self.events or self._added is None:
            return None
        last = self.events[-1]
        if last.keys() != event.keys() or last["frame"] != event["frame"]:
            return None
        (action,) = set(event) - {"frame"}
        old, new = last[action], event[action]
        if old.get("shape") != "stroke" or new.get("shape") != "stroke" or action not in ("paint", "erase", "heat"):
            return None
        if {k: v for k, v in old.items() if k != "points"} != {k: v for k, v in new.items() if k != "points"}:
            return None
        if old["points"][-1] != new["points"][0] or len(old["points"]) + len(new["points"]) > 4096:
            return None
        points = [p for n, p in enumerate(old["points"]) if n == 0 or p != old["points"][n - 1]]  # a click's [a, a] is [a]
        return {"frame": event["frame"], action: {**old, "points": points + new["points"][1:]}}

    def _forget_last(self) -> None:
        """Take back the last event (not yet stepped): its record and what it set up in the world."""
        for items in self._added:
            items.pop()
        self.loaded.spec.timeline.pop()
        self.record_bytes -= _size(self.events.pop())
        self._added = None

    def checkpoint(self, label: str) -> None:
        """Remember the world as it is, for :meth:`undo`: an action (a stroke, a spray, a blast, a
        clear) begins. A world too large for undo's memory budget keeps no points."""
        world = self.world
        self._added = None  # a new action: never joined to the last
        self.history.push(label, world.frame, len(self.events), list(world.state), self._marks())

    def _marks(self) -> list[np.ndarray]:
        return [self.world.awake, self.world._even]

    def undo(self) -> str | None:
        """Put the world back as it was before the last action, forgetting that action's events and
        all since (time goes back too). The action's label; None if there is nothing to undo."""
        if not self.history.points:
            return None
        keep = self._kept_state()
        point = self.history.pop(list(self.world.state), self._marks())
        del self.events[point.events :]
        self._rebuild_around(keep, point.frame)
        self.changes += 1
        return point.label

    def _kept_state(self) -> list[np.ndarray]:
        return [*self.world.state, self.world.awake, self.world._even]

    def _rebuild_around(self, arrays: list[np.ndarray], frame: int) -> None:
        """The world built again for the session's events, holding ``arrays`` at ``frame``."""
        seed = self.world.seed
        self._rebuild(self.loaded.ruleset)
        for array, kept in zip(self._kept_state(), arrays):
            array[...] = kept
        self.world.frame, self.world.seed = frame, seed
        self.world.mark_changed()
        self._added = None
        self.record_bytes = sum(_size(e) for e in self.events)
        if self.full_at is not None and frame <= self.full_at:  # back before anything went unrecorded
            self.full_at = None

    def load_snapshot(self, path: Path) -> list[str]:
        """Load a snapshot into the world: its cells and its frame. Events at its frame or later are
        dropped (they have not happened in it), undo forgets, and the session no longer replays from
        its world file. Returns warnings; ProblemsError if it cannot be loaded (nothing changed)."""
        warnings = self.world.load_snapshot(path)
        frame = self.world.frame
        self.events = [e for e in self.events if e["frame"] < frame]
        self._rebuild_around(self._kept_state(), frame)
        self.history.clear()
        self.changes += 1
        self.not_replayed.append(f"a snapshot was loaded at frame {frame}")
        return warnings

    def step(self) -> None:
        self.world.step()

    # --- mods -------------------------------------------------------------------------------

    def _mod_files(self) -> dict[Path, tuple[int, int]]:
        files: dict[Path, tuple[int, int]] = {}
        try:
            folders = world_mod_folders(self.loaded.spec, self.loaded.source, self.loaded.path, self.mod_dirs)
        except ProblemsError:  # a folder the world names is gone: a reload says so
            return files
        for folder in folders:
            for path in sorted(Path(folder).glob("*.toml")):
                try:
                    stat = path.stat()
                except OSError:
                    continue
                files[path] = (stat.st_mtime_ns, stat.st_size)
        return files

    def mods_changed(self) -> bool:
        """Has a mod file in the mods' folders been saved, added or removed since the last look?"""
        now = self._mod_files()
        changed = now != self.mod_files
        self.mod_files = now
        return changed

    def reload_mods(self) -> list[str]:
        """Load the mods again and carry on with the new rules, every cell kept by its element's id.

        Returns the problems (one line each) if the mods do not load, keeping the old rules; no
        problems: the new rules are in force. The kernel is not compiled again: the rules are its
        tables' contents, never its code."""
        base = self.loaded
        with tempfile.TemporaryDirectory(prefix="sandmod-play-") as scratch:
            snapshot = Path(scratch) / "world.npz"
            try:
                rules = world_rules(self._starting_spec(), base.source, base.path, mod_dirs=self.mod_dirs)
                self.world.save_snapshot(snapshot)
                self.loaded = replace(base, registry=rules.registry, ruleset=rules.ruleset)
                self._rebuild(rules.ruleset)  # an event naming an element that is gone: a problem
                self.world.load_snapshot(snapshot)  # a cell of an element that is gone: a problem
            except ProblemsError as error:  # the old world, untouched, goes on under the old rules
                self.loaded = base
                return [str(problem) for problem in error.problems]
        self.world.wake()  # settled cells feel the new rules
        self.history.clear()
        self._added = None
        self.not_replayed.append(f"the mods were reloaded at frame {self.world.frame}")
        return []

    def _starting_spec(self) -> WorldFile:
        return validate(WorldFile, self.loaded.source)

    def _rebuild(self, ruleset) -> None:
        """The world built afresh from the starting file and the session's events, under ``ruleset``."""
        spec = self._starting_spec()
        first = len(spec.timeline)
        spec.timeline.extend(self.loaded.spec.timeline[first : first + len(self.events)])  # validated when added
        world = build_world(spec, ruleset, self.loaded.source)
        world.threads = self.world.threads
        self.loaded = replace(self.loaded, spec=spec, world=world)

    # --- the record ---------------------------------------------------------------------------

    def world_file(self, folders: list[str] | None = None, pictures: dict[str, str] | None = None) -> str:
        """The session as a world file: the starting world, with every event of the session in its
        timeline, loading mods from ``folders`` too and its pictures from where ``pictures`` says
        (relative to where it is written; None: as the starting world does). ``sandmod render`` of it
        makes the session's frames, bit for bit, up to the frame the record was full at, if it was."""
        data = dict(self.data)
        if folders is not None:
            world = {k: v for k, v in data["world"].items() if k != "mod_folders"}
            data["world"] = {**world, "mod_folders": folders} if folders else world
        pictures = pictures or {}

        def moved(table: dict[str, Any]) -> dict[str, Any]:
            return {**table, "file": pictures[table["file"]]} if _picture(table) in pictures else table

        if "scene" in data:
            data["scene"] = [moved(shape) for shape in data["scene"]]
        timeline = [{**e, "paint": moved(e["paint"])} if "paint" in e else e for e in self.data.get("timeline", [])]
        data["timeline"] = [*timeline, *self.events]
        render = dict(data.get("render", {}))
        render["frames"] = max(self.world.frame if self.full_at is None else self.full_at, 1)
        data["render"] = render
        return tomli_w.dumps(data)

    def save(self, path: Path) -> None:
        """Write :meth:`world_file` to ``path``, whole or not at all (WriteError if it cannot be), so
        that it renders there: the player's mods and the world's pictures that render would not find
        from there are copied beside it, into ``NAME-mods`` and ``NAME-pictures``. :attr:`caveats` says
        why it would not replay the session bit for bit."""
        path = Path(path)
        folders, pictures = self._bring_mods(path), self._bring_pictures(path)
        with atomic_path(path) as temporary:
            temporary.write_text(self.world_file(folders, pictures), encoding="utf-8")
        self.saved_changes = self.changes
        self.saved_events = list(self.events)

    def _bring_mods(self, path: Path) -> list[str]:
        """The ``mod_folders`` a world file at ``path`` needs to load the player's mods (those no plugin
        brings): each mod's folder if it lies under ``path``'s folder, else a copy of its file, as it
        was loaded, in ``NAME-mods`` beside it (written here)."""
        home = path.parent.resolve()
        named: list[str] = []
        copies: dict[str, bytes] = {}
        for mod in self.world.ruleset.mods:
            file = mod.source.path
            if mod.plugin != "user" or file is None or file.parent == (home / "mods").resolve():
                continue
            if home in file.parent.parents:
                named.append(file.parent.relative_to(home).as_posix())
                continue
            name = file.name if file.name not in copies else f"{mod.name}-{file.name}"  # the same name: a copy render takes for the same mod
            copies[name] = mod.source.text.encode("utf-8") if file.suffix == ".toml" else file.read_bytes()
        if copies:
            named.append(_carry(copies, path.parent / f"{path.stem}-mods").name)
        return list(dict.fromkeys(named))

    def _bring_pictures(self, path: Path) -> dict[str, str]:
        """Where a world file at ``path`` finds each picture the starting world paints (by the name it
        gives): under ``path``'s folder, or a copy in ``NAME-pictures`` beside it (written here)."""
        folder = self.loaded.source.folder
        home = path.parent.resolve()
        if folder is None or folder.resolve() == home:
            return {}
        tables = [*self.data.get("scene", []), *(e.get("paint", {}) for e in self.data.get("timeline", []))]
        found, copies = {}, {}
        for written in dict.fromkeys(filter(None, map(_picture, tables))):
            real = (folder / written).resolve()
            if home in real.parents:
                found[written] = real.relative_to(home).as_posix()
            else:
                copies[os.path.normpath(written)] = real.read_bytes()
                found[written] = f"{path.stem}-pictures/{Path(os.path.normpath(written)).as_posix()}"
        if copies:
            _carry(copies, path.parent / f"{path.stem}-pictures")
        return found


def _picture(table: Any) -> str | None:
    """The file a world file's shape paints, if it is a picture."""
    return table.get("file") if isinstance(table, dict) and table.get("shape") == "image" else None


def _carry(files: dict[str, bytes], folder: Path) -> Path:
    """``files`` (relative name: contents) written into ``folder``, each whole or not at all."""
    for name, contents in files.items():
        with atomic_path(folder / name) as temporary:
            temporary.write_bytes(contents)
    return folder
