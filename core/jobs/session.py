"""A play session: a world stepped live, what the player does to it, undo, mods reloaded as they
are saved, and the world file that replays it all.

Everything the player does to the world is a timeline event of the world-file format, set up by
the same code that sets up a world file's timeline (:func:`sandmod.world.scene.add_event`) and
applied by the world on its frame. So the world file :meth:`Session.save` writes, the starting
world with the session's events in its ``[[timeline]]``, renders to the same frames bit for bit.
This module knows nothing of windows: :mod:`sandmod.jobs.play` drives it.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import tomli_w

from ..errors import ProblemsError
from ..formats.tomlsource import TomlSource
from ..formats.validation import validate
from ..formats.worldspec import Event, WorldFile
from ..world.loading import LoadedWorld, load_world_spec, mod_folders, read_world_spec, world_rules
from ..world.scene import add_event, build_world
from ..world.world import World

#: The size of a world played without a world file.
DEFAULT_SIZE = (320, 200)

#: How many strokes undo goes back.
UNDO_DEPTH = 20


@dataclass
class _Undo:
    """The world as it was when a stroke began: its arrays, its frame, and how many events there were."""

    arrays: list[np.ndarray]
    frame: int
    events: int


@dataclass
class Session:
    """A world being played. Open one with :meth:`open`."""

    loaded: LoadedWorld
    mod_dirs: list[Path]
    data: dict[str, Any]  # the starting world file's tables, without the session's events
    events: list[dict[str, Any]] = field(default_factory=list)  # what the player did, as [[timeline]] tables
    undos: list[_Undo] = field(default_factory=list)
    mod_files: dict[Path, tuple[int, int]] = field(default_factory=dict)  # what the mods' folders held: (mtime, size)

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

    # --- what the player does ---------------------------------------------------------------

    def add(self, action: str, table: dict[str, Any]) -> None:
        """Do ``action`` ("paint", "erase", "heat", "spawn" or "explode": a timeline action, ``table``
        as a world file writes it) before the next step. ProblemsError if it is not one."""
        event = {"frame": self.world.frame, action: table}
        spec = self.loaded.spec
        spec.timeline.append(validate(Event, TomlSource("play", "", event, folder=self.loaded.source.folder)))
        try:
            add_event(self.world, spec, self.loaded.source, len(spec.timeline) - 1)
        except ProblemsError:
            spec.timeline.pop()
            raise
        self.events.append(event)

    def begin_stroke(self) -> None:
        """Remember the world as it is, for :meth:`undo`: a stroke begins (the button went down)."""
        state = [a.copy() for a in (*self.world.state, self.world.awake, self.world._even)]
        self.undos.append(_Undo(state, self.world.frame, len(self.events)))
        del self.undos[:-UNDO_DEPTH]

    def undo(self) -> bool:
        """Put the world back as it was before the last stroke, forgetting that stroke's events and
        all since (time goes back too). False if there is nothing to undo."""
        if not self.undos:
            return False
        last = self.undos.pop()
        del self.events[last.events :]
        self._rebuild(self.loaded.ruleset)
        for array, saved in zip((*self.world.state, self.world.awake, self.world._even), last.arrays):
            array[...] = saved
        self.world.frame = last.frame
        return True

    def step(self) -> None:
        self.world.step()

    # --- mods -------------------------------------------------------------------------------

    def _mod_files(self) -> dict[Path, tuple[int, int]]:
        files = {}
        for folder in mod_folders(self.mod_dirs, self.loaded.path):
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
        try:
            rules = world_rules(self._starting_spec(), base.source, base.path, mod_dirs=self.mod_dirs)
        except ProblemsError as error:
            return [str(problem) for problem in error.problems]
        with tempfile.TemporaryDirectory(prefix="sandmod-play-") as scratch:
            snapshot = Path(scratch) / "world.npz"
            self.world.save_snapshot(snapshot)
            self.loaded = replace(base, registry=rules.registry, ruleset=rules.ruleset)
            self._rebuild(rules.ruleset)
            try:
                self.world.load_snapshot(snapshot)
            except ProblemsError as error:  # an element the world holds is gone: keep the old rules
                self.loaded = base
                self._rebuild(base.ruleset)
                self.world.load_snapshot(snapshot)
                return [str(problem) for problem in error.problems]
        return []

    def _starting_spec(self) -> WorldFile:
        return validate(WorldFile, self.loaded.source)

    def _rebuild(self, ruleset) -> None:
        """The world built afresh from the starting file and the session's events, under ``ruleset``."""
        spec = self._starting_spec()
        spec.timeline.extend(validate(Event, TomlSource("play", "", e)) for e in self.events)
        world = build_world(spec, ruleset, self.loaded.source)
        world.threads = self.world.threads
        self.loaded = replace(self.loaded, spec=spec, world=world)

    # --- the record ---------------------------------------------------------------------------

    def world_file(self) -> str:
        """The session as a world file: the starting world, with every event of the session in its
        timeline. ``sandmod render`` of it makes the session's frames, bit for bit."""
        data = dict(self.data)
        data["timeline"] = [*self.data.get("timeline", []), *self.events]
        render = dict(data.get("render", {}))
        render["frames"] = max(self.world.frame, 1)
        data["render"] = render
        return tomli_w.dumps(data)

    def save(self, path: Path) -> None:
        """Write :meth:`world_file` to ``path``, whole or not at all."""
        from ..formats.recording import atomic_path

        with atomic_path(Path(path)) as temporary:
            temporary.write_text(self.world_file(), encoding="utf-8")
