"""``sandmod play``: a window onto a session (:mod:`sandmod.jobs.session`), with pygame-ce.

The simulation runs at its own tick rate (60 a second, times the speed), apart from the display's
60 frames a second; each displayed frame shows the cells the steps since the last one changed.
What the mouse and keys do is in ``sandmod play --help``. Everything done to the world goes
through the session, so the world file ``s`` writes replays the session bit for bit.
"""

from __future__ import annotations

import os
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ProblemsError
from ..formats.recording import VideoSettings, atomic_path
from ..world.world import enlarge
from .session import Session

TICKS = 60  # simulation steps a second at speed 1
DISPLAY_FPS = 60
BAR = 28  # the element bar's height, in pixels
STATUS = 20  # the status line's
SWATCH = 24  # an element's swatch in the bar
CAPTURE_SECONDS = 10
MIN_WIDTH = 640  # room for the element bar and the status line
MAX_AREA = (1280, 800)  # the most of the screen the world takes; a larger one is seen through a view
SPEEDS = (0.25, 0.5, 1, 2, 4, 8)

@dataclass
class Brush:
    element: int
    size: int = 5
    square: bool = False
    tool: str = "paint"  # paint, heat, cold
    replace: bool = False
    over: int | None = None  # replace mode: the element this stroke paints over


@dataclass
class Phases:
    """Seconds spent in each part of the loop, summed over the frames shown."""

    step: float = 0.0
    pixels: float = 0.0
    blit: float = 0.0
    input: float = 0.0
    frames: int = 0


@dataclass
class Play:
    """The window, its input and its drawing, around a :class:`Session`."""

    session: Session
    scale: int = 2
    session_path: Path = Path("play-session.toml")
    fixed_steps: int | None = None  # steps per displayed frame regardless of time (tests and --benchmark)
    save_on_exit: bool = False  # write the session's world file when the window closes
    paused: bool = False
    speed: float = 1.0
    heat_view: bool = False
    message: str = ""
    problems: list[str] = field(default_factory=list)
    phases: Phases = field(default_factory=Phases)

    def __post_init__(self):
        import pygame

        self.pg = pygame
        pygame.display.init()  # and no sound
        pygame.font.init()
        world = self.session.world
        self.area = (min(world.width * self.scale, MAX_AREA[0]), min(world.height * self.scale, MAX_AREA[1]))
        self.size = (max(self.area[0], MIN_WIDTH), self.area[1] + BAR + STATUS)
        self.view = [0, 0]  # the world's cell at the area's top-left corner
        self.screen = pygame.display.set_mode(self.size)
        pygame.display.set_caption("sandmod")
        self.font = pygame.font.Font(None, 17)
        self.brush = Brush(self._first_element())
        self.last_cell: tuple[int, int] | None = None
        self.stroke: str | None = None  # "paint" or "erase" while a button is down
        self.search: str | None = None
        self.captured: deque = deque(maxlen=CAPTURE_SECONDS * DISPLAY_FPS // 2)
        self.due = 0.0
        self.next_mod_check = 0.0
        self.running = True
        self._new_world()

    # --- set-up ---------------------------------------------------------------------------------

    def _first_element(self) -> int:
        ruleset = self.session.world.ruleset
        for name in ("sand:sand",):
            if name in ruleset._ids:
                return ruleset.index(name)
        return 1

    def _new_world(self) -> None:
        """Surfaces for the world as it is now (after a reload the palette may differ)."""
        world = self.session.world
        pygame = self.pg
        self.pixels = np.zeros((world.height, world.width), np.uint8)
        self.cells_surface = pygame.Surface((world.width, world.height), depth=8)
        palette = np.frombuffer(world.ruleset.palette, np.uint8).reshape(256, 3)
        self.cells_surface.set_palette([tuple(int(c) for c in rgb) for rgb in palette])
        self.heat_surface = pygame.Surface((world.width, world.height), depth=24)
        self.elements = [e for e in range(1, len(world.ruleset.elements)) if e != world.ruleset.particle]
        self.fresh = True

    # --- the loop -------------------------------------------------------------------------------

    def run(self, frames: int | None = None) -> None:
        """Show frames until the window closes (or ``frames`` were shown)."""
        clock = self.pg.time.Clock()
        shown = 0
        self.running = True
        while self.running and (frames is None or shown < frames):
            self._one_frame(clock.tick(DISPLAY_FPS if self.fixed_steps is None else 0) / 1000)
            shown += 1
        if self.save_on_exit:
            self.save_session()
        self.pg.quit()

    def _one_frame(self, elapsed: float = 0.0) -> None:
        """Input, the steps due, and the picture: one displayed frame."""
        began = time.perf_counter()
        self._input()
        self._reload_if_saved()
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
            self.session.step()
            self.fresh = True
        self.phases.step += time.perf_counter() - began

    def _reload_if_saved(self) -> None:
        now = time.monotonic()
        if now < self.next_mod_check:
            return
        self.next_mod_check = now + 0.5
        if self.session.mods_changed():
            self.reload()

    def reload(self) -> None:
        """Load the mods again (a mod file was saved): new rules, or the problems and the old rules."""
        self.problems = self.session.reload_mods()
        if not self.problems:
            self.message = "mods reloaded"
            self._new_world()
            self.brush.element = min(self.brush.element, len(self.session.world.ruleset.elements) - 1)

    # --- input ----------------------------------------------------------------------------------

    def _cell(self, pos) -> tuple[int, int] | None:
        """The cell under a window position (None: not over the world)."""
        if not (0 <= pos[0] < self.area[0] and 0 <= pos[1] < self.area[1]):
            return None
        x, y = self.view[0] + pos[0] // self.scale, self.view[1] + pos[1] // self.scale
        world = self.session.world
        return (x, y) if 0 <= x < world.width and 0 <= y < world.height else None

    def _shown(self) -> tuple[int, int]:
        """How many columns and rows of cells the area shows."""
        world = self.session.world
        return min(world.width, -(-self.area[0] // self.scale)), min(world.height, -(-self.area[1] // self.scale))

    def _pan(self, dx: int, dy: int) -> None:
        world, (columns, rows) = self.session.world, self._shown()
        self.view = [int(np.clip(self.view[0] + dx, 0, world.width - columns)), int(np.clip(self.view[1] + dy, 0, world.height - rows))]
        self.fresh = True

    def _zoom(self, by: int, pos) -> None:
        """Cells bigger or smaller on the screen, the cell under ``pos`` staying under it."""
        cell = self._cell(pos) or (self.view[0], self.view[1])
        self.scale = int(np.clip(self.scale + by, 1, 16))
        self.view = [cell[0] - pos[0] // self.scale, cell[1] - pos[1] // self.scale]
        self._pan(0, 0)

    def _input(self) -> None:
        pygame = self.pg
        for event in pygame.event.get():
            if event.type == pygame.QUIT:
                self.running = False
            elif event.type == pygame.KEYDOWN:
                self._key(event)
            elif event.type == pygame.MOUSEBUTTONDOWN:
                self._button_down(event)
            elif event.type == pygame.MOUSEBUTTONUP and event.button in (1, 3):
                self.stroke, self.last_cell = None, self._cell(event.pos) or self.last_cell
            elif event.type == pygame.MOUSEWHEEL and pygame.key.get_mods() & pygame.KMOD_CTRL:
                self._zoom(event.y, pygame.mouse.get_pos())
            elif event.type == pygame.MOUSEWHEEL:
                self.brush.size = int(np.clip(self.brush.size + event.y, 1, 64))
            elif event.type == pygame.MOUSEMOTION and self.stroke is not None:
                self._drag(event.pos)

    def _button_down(self, event) -> None:
        if event.pos[1] >= self.area[1]:
            self._bar_click(event.pos)
            return
        cell = self._cell(event.pos)
        if cell is None:
            return
        if event.button == 2:
            self.brush.element = int(self.session.world.cells[cell[1], cell[0]]) or self.brush.element
            return
        if event.button not in (1, 3):
            return
        self.session.begin_stroke()
        self.stroke = "paint" if event.button == 1 else "erase"
        self.brush.over = int(self.session.world.cells[cell[1], cell[0]]) if self.brush.replace else None
        start = self.last_cell if (self.pg.key.get_mods() & self.pg.KMOD_SHIFT) and self.last_cell else cell
        self._apply(start, cell)
        self.last_cell = cell

    def _drag(self, pos) -> None:
        cell = self._cell(pos)
        if cell is not None and cell != self.last_cell:
            self._apply(self.last_cell or cell, cell)
            self.last_cell = cell

    def _apply(self, start: tuple[int, int], end: tuple[int, int]) -> None:
        """The brush from ``start`` to ``end`` (cells), as a session event."""
        brush, world = self.brush, self.session.world
        shape = {"shape": "stroke", "points": [list(start), list(end)], "thickness": brush.size}
        if brush.square:
            shape["brush"] = "square"
        try:
            if self.stroke == "erase":
                self.session.add("erase", shape)
            elif brush.tool in ("heat", "cold"):
                self.session.add("heat", {**shape, "temperature": 800.0 if brush.tool == "heat" else -100.0})
            else:
                table = {**shape, "element": world.ruleset.elements[brush.element].id}
                if brush.over is not None:
                    table["over"] = world.ruleset.elements[brush.over].id
                self.session.add("paint", table)
        except ProblemsError as error:
            self.message = str(error.problems[0])

    def _at_cursor(self, action: str, table: dict) -> None:
        cell = self._cell(self.pg.mouse.get_pos())
        if cell is not None:
            try:
                self.session.add(action, {**table, "at": list(cell)})
            except ProblemsError as error:
                self.message = str(error.problems[0])

    def _key(self, event) -> None:
        pygame, key, brush = self.pg, event.key, self.brush
        if self.search is not None:
            self._search_key(event)
            return
        ctrl = event.mod & pygame.KMOD_CTRL
        if key == pygame.K_ESCAPE:
            self.running = False
        elif key == pygame.K_z and ctrl:
            self.message = "undone" if self.session.undo() else "nothing to undo"
            self.fresh = True
        elif key == pygame.K_SPACE:
            self.paused = not self.paused
        elif key == pygame.K_n:
            self.session.step()
            self.fresh = True
        elif key in (pygame.K_PLUS, pygame.K_EQUALS, pygame.K_KP_PLUS, pygame.K_MINUS, pygame.K_KP_MINUS):
            index = SPEEDS.index(self.speed) + (1 if key in (pygame.K_PLUS, pygame.K_EQUALS, pygame.K_KP_PLUS) else -1)
            self.speed = SPEEDS[int(np.clip(index, 0, len(SPEEDS) - 1))]
        elif key in (pygame.K_LEFTBRACKET, pygame.K_RIGHTBRACKET):
            brush.size = int(np.clip(brush.size + (1 if key == pygame.K_RIGHTBRACKET else -1), 1, 64))
        elif key == pygame.K_b:
            brush.square = not brush.square
        elif key == pygame.K_r:
            brush.replace = not brush.replace
        elif key in (pygame.K_h, pygame.K_c):
            tool = "heat" if key == pygame.K_h else "cold"
            brush.tool = "paint" if brush.tool == tool else tool
        elif key == pygame.K_q:
            self._at_cursor("spawn", {"element": self.session.world.ruleset.elements[brush.element].id, "radius": brush.size / 2,
                                      "count": 24, "direction": 90, "spread": 120, "speed": [1.5, 3.0]})
        elif key == pygame.K_x:
            self._at_cursor("explode", {"radius": max(brush.size, 4), "strength": 20.0})
        elif key == pygame.K_v:
            self.heat_view = not self.heat_view
            self.fresh = True
        elif key == pygame.K_DELETE:
            world = self.session.world
            self.session.begin_stroke()
            self.session.add("erase", {"shape": "rect", "x": 0, "y": 0, "width": world.width, "height": world.height})
        elif key == pygame.K_s:
            self.save_session()
        elif key in (pygame.K_F5, pygame.K_F9):
            self._snapshot(key == pygame.K_F5)
        elif key == pygame.K_p:
            self.screenshot(Path("play-screenshot.png"))
        elif key == pygame.K_g:
            self.capture(Path("play-capture.gif"))
        elif key in (pygame.K_LEFT, pygame.K_RIGHT, pygame.K_UP, pygame.K_DOWN):
            columns, rows = self._shown()
            self._pan({pygame.K_LEFT: -columns // 4, pygame.K_RIGHT: columns // 4}.get(key, 0), {pygame.K_UP: -rows // 4, pygame.K_DOWN: rows // 4}.get(key, 0))
        elif key == pygame.K_SLASH:
            self.search = ""
        elif pygame.K_1 <= key <= pygame.K_9 and key - pygame.K_1 < len(self.elements):
            brush.element = self.elements[key - pygame.K_1]

    def _search_key(self, event) -> None:
        pygame = self.pg
        if event.key == pygame.K_ESCAPE:
            self.search = None
        elif event.key == pygame.K_RETURN:
            found = self._matches()
            if found:
                self.brush.element = found[0]
            self.search = None
        elif event.key == pygame.K_BACKSPACE:
            self.search = self.search[:-1]
        elif event.unicode and event.unicode.isprintable():
            self.search += event.unicode.lower()

    def _matches(self) -> list[int]:
        elements = self.session.world.ruleset.elements
        return [e for e in self.elements if self.search and self.search in elements[e].id]

    def _bar_click(self, pos) -> None:
        index = pos[0] // SWATCH
        if pos[1] < self.area[1] + BAR and index < len(self.elements):
            self.brush.element = self.elements[index]

    # --- files ----------------------------------------------------------------------------------

    def save_session(self) -> None:
        self.session.save(self.session_path)
        self.message = f"saved {self.session_path}: sandmod render {self.session_path} replays it"

    def _snapshot(self, save: bool) -> None:
        path = Path("play-snapshot.npz")
        try:
            if save:
                self.session.world.save_snapshot(path)
                self.message = f"saved {path}"
            else:
                self.session.world.load_snapshot(path)
                self.fresh = True
                self.message = f"loaded {path} (the session's world file no longer replays it)"
        except (ProblemsError, OSError) as error:
            self.message = str(error)

    def screenshot(self, path: Path) -> None:
        """The window as it is, as a PNG."""
        with atomic_path(path) as temporary:
            self.pg.image.save(self.screen, str(temporary), "png")
        self.message = f"saved {path}"

    def capture(self, path: Path) -> None:
        """The last seconds shown, as a GIF (through the gif recorder plugin)."""
        from ..world.loading import load_registry

        world = self.session.world
        scale = max(1, min(self.scale, MAX_AREA[0] // world.width, MAX_AREA[1] // world.height))  # the whole world
        spec = load_registry().recorders["gif"].value
        settings = VideoSettings(world.width * scale, world.height * scale, world.ruleset.palette, DISPLAY_FPS / 2)
        with atomic_path(path) as temporary:
            recorder = spec.open(temporary, settings)
            for frame in self.captured:
                recorder.add_frame(enlarge(frame, scale))
            recorder.close()
        self.message = f"saved {path}: {len(self.captured)} images"

    # --- drawing --------------------------------------------------------------------------------

    def _draw(self) -> None:
        pygame, world = self.pg, self.session.world
        began = time.perf_counter()
        if self.fresh:
            if self.heat_view:
                pygame.surfarray.blit_array(self.heat_surface, world.heat_image().transpose(1, 0, 2))
            else:
                world.image(self.pixels, changed_only=True)
                self._preview_pending()
                pygame.surfarray.blit_array(self.cells_surface, self.pixels.T)
                if self.phases.frames % 2 == 0:
                    self.captured.append(self.pixels.copy())
        self.phases.pixels += time.perf_counter() - began
        began = time.perf_counter()
        if self.fresh:
            columns, rows = self._shown()
            source = (self.heat_surface if self.heat_view else self.cells_surface).subsurface((*self.view, columns, rows))
            self.screen.fill((0, 0, 0), (0, 0, *self.area))
            self.screen.blit(pygame.transform.scale(source, (columns * self.scale, rows * self.scale)), (0, 0))
        self._draw_bar()
        self._draw_status()
        pygame.display.flip()
        self.fresh = False
        self.phases.blit += time.perf_counter() - began

    def _preview_pending(self) -> None:
        """Paintings due before the next step, shown now (while paused they would wait for it)."""
        world = self.session.world
        for painting in world.paintings:
            if painting.frame == world.frame:
                layer = painting.layer(world.cells)
                shown = layer >= 0
                self.pixels[shown] = world.ruleset.looks.normal[layer[shown], 0]

    def _draw_bar(self) -> None:
        pygame, world = self.pg, self.session.world
        top = self.area[1]
        pygame.draw.rect(self.screen, (24, 24, 28), (0, top, self.size[0], BAR + STATUS))
        palette = np.frombuffer(world.ruleset.palette, np.uint8).reshape(256, 3)
        matches = set(self._matches()) if self.search else set()
        for index, element in enumerate(self.elements):
            left = index * SWATCH
            if left + SWATCH > self.size[0]:
                break
            colour = tuple(int(c) for c in palette[world.ruleset.looks.normal[element, 0]])
            pygame.draw.rect(self.screen, colour, (left + 2, top + 2, SWATCH - 4, BAR - 4))
            if element == self.brush.element or element in matches:
                pygame.draw.rect(self.screen, (255, 255, 255), (left + 1, top + 1, SWATCH - 2, BAR - 2), 2)

    def _draw_status(self) -> None:
        text = self.problems[0] if self.problems else self._status()
        colour = (255, 120, 100) if self.problems else (220, 220, 220)
        image = self.font.render(text[: self.size[0] // 5], True, colour)
        self.screen.blit(image, (4, self.area[1] + BAR + 3))

    def _status(self) -> str:
        world, brush = self.session.world, self.brush
        element = world.ruleset.elements[brush.element].id
        state = "paused" if self.paused else f"x{self.speed:g}"
        parts = [f"frame {world.frame} {state}", f"{brush.tool} {element} {brush.size}{' square' if brush.square else ''}{' replace' if brush.replace else ''}"]
        cell = self._cell(self.pg.mouse.get_pos())
        if cell is not None:
            x, y = cell
            under = world.ruleset.elements[int(world.cells[y, x])]
            celsius = float(world._temperature_units(slice(y, y + 1), slice(x, x + 1))[0, 0]) / 16
            parts.append(f"{under.id} ({under.mod}) {celsius:.0f} °C at {x},{y}")
        if self.search is not None:
            parts.append(f"/{self.search}")
        if self.message:
            parts.append(self.message)
        return "   ".join(parts)


def benchmark(session: Session, scale: int, frames: int, busy: bool) -> dict:
    """Show ``frames`` frames as fast as they go, one step each, with a brush painting near the top;
    with ``busy``, over ``sandmod bench``'s everything scene first (fire, heat, reactions, blasts).
    Returns frames a second and each phase's milliseconds a frame (step, pixels, blit, input)."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    from .benchmark import everything

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
