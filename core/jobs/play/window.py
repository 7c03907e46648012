"""The window's loop: input turned into commands (:mod:`.keys`), the tools' events (:mod:`.tools`)
added to the session, the steps due, and the picture (:mod:`.view`).

The simulation runs at its own tick rate (60 a second, times the speed), apart from the display's
60 frames a second. Everything done to the world goes through the session, so the world file ``s``
writes replays the session bit for bit.
"""

from __future__ import annotations

import os
import tempfile
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import ProblemsError, display_path
from ...formats.worldspec import MAX_FRAMES
from ..session import Session
from . import keys, tools
from .files import Capture, folders, save_png, write_somewhere
from .menu import KEYED, Menu, default_favourites, listed, offered
from .view import Overlay, View

TICKS = 60  # simulation steps a second at speed 1
DISPLAY_FPS = 60
CAPTURE_SECONDS = 10
SPEEDS = (0.25, 0.5, 1, 2, 4, 8)
MESSAGE_SECONDS = 8


@dataclass
class Phases:
    """Seconds spent in each part of the loop, summed over the frames shown."""

    step: float = 0.0
    pixels: float = 0.0
    blit: float = 0.0
    input: float = 0.0
    frames: int = 0


class Play:
    """The window, its input and its tools, around a :class:`Session`."""

    def __init__(self, session: Session, scale: int = 2, session_path: Path | None = None,
                 fixed_steps: int | None = None, save_on_exit: bool = False):
        import pygame

        self.pg = pygame
        pygame.display.init()  # and no sound
        pygame.font.init()
        self.session = session
        self.session_name = (session_path or Path("play-session.toml")).name
        self.places = folders(session_path.parent if session_path else None)
        self.fixed_steps = fixed_steps  # steps per displayed frame regardless of time (tests and --benchmark)
        self.save_on_exit = save_on_exit  # write the session's world file when the window closes
        self.view = View(pygame, session.world, scale)
        ruleset = session.world.ruleset
        self.offered = offered(ruleset)  # what a search finds
        self.brush = tools.Brush(self._default_element())
        self.menu = Menu(ruleset, self.view.per_page(), default_favourites(ruleset, self.brush.element))
        self.paused, self.speed, self.help, self.running = False, 1.0, False, True
        self.message, self.message_at, self.prompt = "", 0.0, ""
        self.problems: list[str] = []
        self.phases = Phases()
        self.last_cell: tuple[int, int] | None = None
        self.stroke: str | None = None  # "paint" or "erase" while a button is down
        self.search: str | None = None
        self.held: dict[str, int] = {}  # held tools: the frame each last acted on
        self.captured: deque = deque(maxlen=CAPTURE_SECONDS * DISPLAY_FPS // 2)
        self.capture_job: Capture | None = None
        self.saved_to: Path | None = None
        self.saved_message = ""  # what the last save said (the command line prints it when the window closes)
        self.not_saved = ""  # why the session closed without being saved where asked (and where it went instead)
        self.due = 0.0
        self.next_mod_check = 0.0
        self.clock = pygame.time.Clock()

    # --- the loop -------------------------------------------------------------------------------

    def run(self, frames: int | None = None) -> None:
        """Show frames until the window closes (or ``frames`` were shown)."""
        shown = 0
        self.running = True
        while self.running and (frames is None or shown < frames):
            self._one_frame(self.clock.tick(DISPLAY_FPS if self.fixed_steps is None else 0) / 1000)
            shown += 1
        if self.save_on_exit:
            self.save_before_closing()
        if self.capture_job is not None:
            self.capture_job.result(wait=True)
        self.pg.quit()

    def _one_frame(self, elapsed: float = 0.0) -> None:
        """Input, the steps due, and the picture: one displayed frame."""
        began = time.perf_counter()
        self._input()
        self._reload_if_saved()
        self._use_held_tools()
        self.phases.input += time.perf_counter() - began
        self._simulate(elapsed)
        self._draw()
        self.phases.frames += 1

    def _simulate(self, elapsed: float) -> None:
        began = time.perf_counter()
        if self.fixed_steps is not None:
            steps = 0 if self.paused else self.fixed_steps
        elif self.paused:
            steps, self.due = 0, 0.0
        else:
            self.due = min(self.due + elapsed * TICKS * self.speed, 8.0)  # never more than 8 steps behind
            steps = int(self.due)
            self.due -= steps
        for _ in range(steps):
            if self.session.world.frame >= MAX_FRAMES:
                self.paused = True
                self.say(f"frame {MAX_FRAMES}: the most a world file replays; s saves the session")
                break
            self.session.step()
        self.phases.step += time.perf_counter() - began

    def _draw(self) -> None:
        began = time.perf_counter()
        view = self.view
        view.refresh(self.session.world)
        if self.phases.frames % 2 == 0 and not view.heat_view:
            self.captured.append(view.pixels.copy())
        self.phases.pixels += time.perf_counter() - began
        began = time.perf_counter()
        brush = (self.brush.size, self.brush.square) if not self.help else None
        overlay = Overlay(self._status(), self._message(), self.problems, self.prompt, self.help, self.menu, self.brush.element, brush)
        view.draw(overlay, self.pg.mouse.get_pos())
        self.phases.blit += time.perf_counter() - began

    def say(self, message: str) -> None:
        self.message, self.message_at = message, time.monotonic()

    # --- mods -----------------------------------------------------------------------------------

    def _reload_if_saved(self) -> None:
        now = time.monotonic()
        if now < self.next_mod_check:
            return
        self.next_mod_check = now + 0.5
        if self.session.mods_changed():
            self.reload()

    def reload(self) -> None:
        """Load the mods again (a mod file was saved): new rules, or the problems and the old rules."""
        chosen = self.session.world.ruleset.elements[self.brush.element].id
        self.problems = self.session.reload_mods()
        if self.problems:
            return
        ruleset = self.session.world.ruleset
        self.offered, self.menu = offered(ruleset), self.menu.reloaded(ruleset)
        if self.search is not None:
            self.menu.find(self._matches())
        try:
            self.brush.element = ruleset.index(chosen)
        except KeyError:
            self.brush.element = self._default_element()
        self.say("mods reloaded")

    def _default_element(self) -> int:
        ruleset = self.session.world.ruleset
        return tools.default_element(ruleset, listed(ruleset), self.session.loaded.spec.world.mods)

    # --- input ----------------------------------------------------------------------------------

    def _input(self) -> None:
        pygame = self.pg
        for event in pygame.event.get():
            if event.type == pygame.QUIT:
                self._close()
            elif event.type == pygame.KEYDOWN:
                self._key(event)
            elif event.type == pygame.KEYUP:
                self.held.pop(keys.command(pygame.key.name(event.key)) or "", None)
            elif event.type == pygame.MOUSEBUTTONDOWN:
                self._button_down(event)
            elif event.type == pygame.MOUSEBUTTONUP and event.button in (1, 3):
                self.stroke, self.last_cell = None, self.view.cell_at(event.pos) or self.last_cell
            elif event.type == pygame.MOUSEWHEEL and self.view.in_menu(pygame.mouse.get_pos()):
                self.menu.turn(-event.y)
            elif event.type == pygame.MOUSEWHEEL and pygame.key.get_mods() & pygame.KMOD_CTRL:
                self.view.zoom(event.y, pygame.mouse.get_pos())
            elif event.type == pygame.MOUSEWHEEL:
                self.brush.size = int(np.clip(self.brush.size + event.y, 1, tools.MAX_BRUSH))
            elif event.type == pygame.MOUSEMOTION and self.stroke is not None:
                self._drag(event.pos)

    def _key(self, event) -> None:
        pygame = self.pg
        if self.search is not None:
            self._search_key(event)
            return
        name = pygame.key.name(event.key)
        if event.mod & pygame.KMOD_CTRL:
            name = f"ctrl+{name}"
        elif event.mod & pygame.KMOD_SHIFT and keys.command(f"shift+{name}"):
            name = f"shift+{name}"
        command = keys.command(name, event.unicode or "")
        if self.prompt:  # the question of quitting: s saves and quits, escape quits, anything else stays
            self.prompt = ""
            if command == "save":
                self.do_save()
                self.running = not self.saved_to
            elif command == "quit":
                self.running = False
            return
        if command is not None:
            getattr(self, f"do_{command}")(name)

    def _button_down(self, event) -> None:
        if self.view.in_menu(event.pos):
            action = self.view.menu_at(event.pos, self.menu)
            if action is not None:
                self._menu_click(*action)
            return
        cell = self.view.cell_at(event.pos)
        if cell is None:
            return
        if event.button == 2:
            self.brush.element = int(self.session.world.cells[cell[1], cell[0]]) or self.brush.element
            return
        if event.button not in (1, 3):
            return
        self.session.checkpoint("erase" if event.button == 3 else self.brush.tool)
        self.stroke = "paint" if event.button == 1 else "erase"
        self.brush.over = int(self.session.world.cells[cell[1], cell[0]]) if self.brush.replace else None
        start = self.last_cell if (self.pg.key.get_mods() & self.pg.KMOD_SHIFT) and self.last_cell else cell
        self._apply(start, cell)
        self.last_cell = cell

    def _menu_click(self, kind: str, what) -> None:
        """A click on the menu: on a swatch, a tab, or a < > button (see :meth:`.View.menu_items`)."""
        if kind == "element":
            self._take(what)
        elif kind == "section":
            self.menu.show(what)
        elif kind == "sections":
            self.menu.next_section(what)
        else:
            self.menu.turn(what)

    def _take(self, element: int) -> None:
        """The brush takes ``element`` (a search ends), and the menu shows it."""
        self.brush.element = element
        self._end_search()
        self.menu.reveal(element)

    def _drag(self, pos) -> None:
        cell = self.view.cell_at(pos)
        if cell is not None and cell != self.last_cell:
            self._apply(self.last_cell or cell, cell)
            self.last_cell = cell

    def _apply(self, start: tuple[int, int], end: tuple[int, int]) -> None:
        """The brush from ``start`` to ``end`` (cells), as a session event."""
        self._add(tools.stroke(self.brush, self.session.world.ruleset, start, end, self.stroke == "erase"))

    def _add(self, event: tools.Event) -> None:
        try:
            recorded = self.session.add(*event)
        except ProblemsError as error:
            self.say(error.problems[0].message)
            return
        if not recorded:
            self.say(f"session full: painting goes on, but strokes from frame {self.session.full_at} on are not saved (s saves the rest)")

    def _cursor(self) -> tuple[int, int] | None:
        return self.view.cell_at(self.pg.mouse.get_pos())

    def _use_held_tools(self) -> None:
        """Held tools act again once the world has stepped since they last did."""
        frame = self.session.world.frame
        for command, acted in list(self.held.items()):
            cell = self._cursor()
            if acted != frame and cell is not None:
                self._tool(command, cell)
                self.held[command] = frame

    def _tool(self, command: str, cell: tuple[int, int]) -> None:
        ruleset = self.session.world.ruleset
        self._add(tools.spray(self.brush, ruleset, cell) if command == "spray" else tools.fling(self.brush, cell))

    def _search_key(self, event) -> None:
        pygame = self.pg
        if event.key == pygame.K_ESCAPE:
            self._end_search()
        elif event.key == pygame.K_RETURN:
            found = self._matches()
            if found:
                self._take(found[0])
            else:
                self.say(f"no element's name holds '{self.search}'")
                self._end_search()
        elif event.key == pygame.K_BACKSPACE:
            self.search = self.search[:-1]
        elif event.unicode and event.unicode.isprintable():
            self.search += event.unicode.lower()
        if self.search is not None:
            self.menu.find(self._matches())

    def _end_search(self) -> None:
        self.search = None
        self.menu.find(None)

    def _matches(self) -> list[int]:
        return tools.search(self.session.world.ruleset, self.offered, self.search or "")

    # --- commands (see keys.BINDINGS) ------------------------------------------------------------

    def do_size(self, key: str) -> None:
        self.brush.size = int(np.clip(self.brush.size + (1 if key == "]" else -1), 1, tools.MAX_BRUSH))

    def do_square(self, key: str) -> None:
        self.brush.square = not self.brush.square

    def do_replace(self, key: str) -> None:
        self.brush.replace = not self.brush.replace

    def do_heat(self, key: str) -> None:
        self.brush.tool = "paint" if self.brush.tool == "heat" else "heat"

    def do_cold(self, key: str) -> None:
        self.brush.tool = "paint" if self.brush.tool == "cold" else "cold"

    def do_spray(self, key: str) -> None:
        self._start_held("spray")

    def do_fling(self, key: str) -> None:
        self._start_held("fling")

    def _start_held(self, command: str) -> None:
        cell = self._cursor()
        if command in self.held or cell is None:
            return
        self.session.checkpoint(command)
        self._tool(command, cell)
        self.held[command] = self.session.world.frame

    def do_explode(self, key: str) -> None:
        cell = self._cursor()
        if cell is not None:
            self.session.checkpoint("blast")
            self._add(tools.blast(self.brush, cell))

    def do_choose(self, key: str) -> None:
        element = self.menu.favourite(int(key))
        if element is not None:
            self._take(element)

    def do_pin(self, key: str) -> None:
        name = self.session.world.ruleset.elements[self.brush.element].name
        if not self.menu.pin(self.brush.element):
            self.say(f"{name} is no longer a favourite")
            return
        number = len(self.menu.favourites)
        self.say(f"{name} is favourite {number}: " + (f"key {number} gives it" if number <= KEYED else f"keys 1-{KEYED} give the first {KEYED}"))

    def do_section(self, key: str) -> None:
        self.menu.next_section(-1 if key.startswith("shift+") else 1)

    def do_element(self, key: str) -> None:
        self.brush.element = self.menu.next_element(self.brush.element, -1 if key == "," else 1)

    def do_page(self, key: str) -> None:
        self.menu.turn(-1 if key == "page up" else 1)

    def do_search(self, key: str) -> None:
        self.search = ""
        self.menu.find([])

    def do_pause(self, key: str) -> None:
        self.paused = not self.paused

    def do_step(self, key: str) -> None:
        self.session.step()

    def do_speed(self, key: str) -> None:
        index = SPEEDS.index(self.speed) + (-1 if "-" in key else 1)
        self.speed = SPEEDS[int(np.clip(index, 0, len(SPEEDS) - 1))]

    def do_heat_view(self, key: str) -> None:
        self.view.show_heat(not self.view.heat_view)

    def do_undo(self, key: str) -> None:
        label = self.session.undo()
        self.say(f"undid a {label}" if label else "nothing to undo")

    def do_clear(self, key: str) -> None:
        world = self.session.world
        self.session.checkpoint("clear")
        self._add(("erase", {"shape": "rect", "x": 0, "y": 0, "width": world.width, "height": world.height}))

    def do_pan(self, key: str) -> None:
        columns, rows = self.view.shown()
        self.view.pan({"left": -columns // 4, "right": columns // 4}.get(key, 0), {"up": -rows // 4, "down": rows // 4}.get(key, 0))

    def do_help(self, key: str) -> None:
        self.help = not self.help

    def do_quit(self, key: str) -> None:
        if self.help:
            self.help = False
        elif self.session.unsaved and not self.save_on_exit:
            self.prompt = f"{self._unsaved()} not saved: s saves and quits, escape quits without saving, any other key stays"
        else:
            self.running = False

    def _unsaved(self) -> str:
        """What a save would add to the session's file, in words: "3 actions", "1 undone action"..."""
        added, dropped = self.session.unsaved_events()
        words = [f"{added} action{'s' * (added != 1)}"] if added else []
        words += [f"{dropped} undone action{'s' * (dropped != 1)}"] if dropped else []
        return " and ".join(words) or "a change"

    def _close(self) -> None:
        """The window's close button: what is not saved is saved first."""
        if self.session.unsaved and not self.save_on_exit:
            self.save_before_closing()
        self.running = False

    def save_before_closing(self) -> None:
        """Save the session; if no folder takes it, into a new temporary folder, :attr:`not_saved` saying so."""
        self.do_save()
        if self.saved_to is not None:
            return
        where = self._places()
        try:
            path = Path(tempfile.mkdtemp(prefix="sandmod-play-")) / self.session_name
            self.session.save(path)
        except OSError as error:
            self.not_saved = f"the session was not saved: not in {where}, nor in a temporary folder ({error.strerror or error})"
            return
        self.not_saved = f"the session was not saved in {where}; it was written to {path} instead"

    # --- files ----------------------------------------------------------------------------------

    def do_save(self, key: str = "") -> None:
        """Write the session's world file; where it went and whether it replays bit for bit, in the status."""
        try:
            self.saved_to = write_somewhere(self.session_name, self.places, self.session.save)
        except OSError as error:
            self.saved_to = None
            self.say(f"could not save {self.session_name} in {self._places()}: {error.strerror or error}")
            return
        caveat = self.session.caveats
        replays = f"does not replay bit for bit ({'; '.join(caveat)})" if caveat else "replays it"
        self.saved_message = f"saved {self.saved_to}: sandmod render {display_path(self.saved_to)} {replays}"
        self.say(self.saved_message)

    def _places(self) -> str:
        return ", ".join(str(place.absolute()) for place in self.places)

    def do_save_snapshot(self, key: str = "") -> None:
        try:
            path = write_somewhere("play-snapshot.npz", self.places, self.session.world.save_snapshot)
            self.say(f"saved {path}")
        except (OSError, ProblemsError) as error:
            self.say(f"could not save play-snapshot.npz: {error}")

    def do_load_snapshot(self, key: str = "") -> None:
        name = "play-snapshot.npz"
        path = next((place / name for place in self.places if (place / name).is_file()), self.places[0] / name)
        try:
            warnings = self.session.load_snapshot(path)
        except ProblemsError as error:
            self.say(str(error.problems[0]))
            return
        self.say("; ".join([f"loaded {path}: the strokes after it are dropped", *warnings]))

    def do_screenshot(self, key: str = "") -> None:
        """The window as it is, as a PNG."""
        rgb = self.pg.surfarray.array3d(self.view.screen).transpose(1, 0, 2)
        try:
            path = write_somewhere("play-screenshot.png", self.places, lambda p: save_png(rgb, p))
            self.say(f"saved {path}")
        except OSError as error:
            self.say(f"could not save play-screenshot.png: {error.strerror or error}")

    def do_capture(self, key: str = "") -> None:
        """The last seconds shown, as a GIF written in the background."""
        if self.capture_job is not None and self.capture_job.result() is None:
            self.say("still writing the last capture")
            return
        if not self.captured:
            self.say("nothing to capture yet")
            return
        world, view = self.session.world, self.view
        scale = max(1, min(view.scale, 1280 // world.width, 800 // world.height))  # the whole world
        self.capture_job = Capture(list(self.captured), scale, world.ruleset.colours, DISPLAY_FPS / 2, "play-capture.gif", self.places)
        self.say(f"writing play-capture.gif: {len(self.captured)} images")

    # --- the status line ------------------------------------------------------------------------

    def _status(self) -> str:
        if self.capture_job is not None and self.capture_job.result() is not None:
            self.say(self.capture_job.result())
            self.capture_job = None
        world, brush = self.session.world, self.brush
        element = world.ruleset.elements[brush.element]
        state = "paused" if self.paused else f"x{self.speed:g}"
        tool = "erase" if self.stroke == "erase" else brush.tool if brush.tool != "paint" else element.name
        fps = self.clock.get_fps()  # 0 until the clock has ticked for a while
        parts = [f"{fps:3.0f} fps" if fps else "", f"frame {world.frame} {state}",
                 f"{tool} {brush.size}{' square' if brush.square else ''}{' replace' if brush.replace else ''}"]
        cell = self._cursor()
        if cell is not None:
            x, y = cell
            under = world.ruleset.elements[int(world.cells[y, x])]
            celsius = world.temperature_at(x, y)
            parts.append(f"{under.id} {celsius:.0f} °C at {x},{y}")
        return "   ".join(part for part in parts if part)

    def _message(self) -> str:
        """What the status line says after the status: the search, the last message (for a while), or the help key."""
        if self.search is not None:
            return f"find: {self.search}_  (enter takes it)"
        if self.message and time.monotonic() - self.message_at < MESSAGE_SECONDS:
            return self.message
        return "F1: every key"


def benchmark(session: Session, scale: int, frames: int, busy: bool) -> dict:
    """Show ``frames`` frames as fast as they go, one step each, with a brush painting near the top;
    with ``busy``, over ``sandmod bench``'s everything scene first (fire, heat, reactions, blasts).
    Returns frames a second and each phase's milliseconds a frame (step, pixels, blit, input)."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    from ..benchmark import everything

    world = session.world
    if busy:
        everything(world, world.ruleset)
    play = Play(session, scale=scale, fixed_steps=1)
    began = time.perf_counter()
    for frame in range(frames):
        if frame % 4 == 0:
            x = world.width // 4 + (frame * 7) % (world.width // 2)
            play.stroke = "paint"
            play._apply((x, 4), (x + 6, 4))
            play.stroke = None
        play._one_frame()
    seconds = time.perf_counter() - began
    phases = play.phases
    play.pg.quit()
    per_frame = {name: round(getattr(phases, name) / frames * 1000, 3) for name in ("step", "pixels", "blit", "input")}
    return {"width": world.width, "height": world.height, "scale": scale, "frames": frames, "fps": round(frames / seconds, 1), "ms_per_frame": per_frame}
