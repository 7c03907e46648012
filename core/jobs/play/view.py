"""The window's picture: the world through a viewport, the element bar, the status line, the brush
outline and the overlays (problems, help, a tooltip).

The view owns what is stale on the screen. The world records every chunk that changed since it was
last drawn, whatever changed it (steps, strokes, blasts, undo, a snapshot); a new world (after an
undo, a reload or a snapshot load) or another view mode redraws everything.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ...world.world import World
from .keys import help_lines

BAR = 28  # the element bar's height, in pixels
STATUS = 20  # the status line's
SWATCH = 24  # the widest an element's swatch in the bar gets
GAP = 6  # between the bar's groups
MIN_WIDTH = 640  # room for the element bar and the status line
MIN_HEIGHT = 280  # room for the help
MAX_AREA = (1280, 800)  # the most of the screen the world takes; a larger one is seen through a viewport
LINE = 16  # a line of text's height, in pixels
MARGIN = 6  # between text and the window's edges
TEXT, DIM, RED = (225, 225, 225), (150, 150, 160), (255, 120, 100)
PANEL, PROBLEM_BACK = (24, 24, 28), (20, 10, 10)


def wrap(font, text: str, width: int) -> list[str]:
    """``text`` cut into lines that each fit ``width`` pixels in ``font``: at spaces where it can,
    inside a word too long for a line. ``"".join`` of the lines gives ``text`` back."""
    fits = lambda line: font.size(line.rstrip())[0] <= width  # noqa: E731
    lines, line = [], ""
    for token in re.findall(r"\S+\s*|\s+", text):
        if fits(line + token):
            line += token
            continue
        if line:
            lines.append(line)
        while not fits(token):
            cut = next((n for n in range(len(token) - 1, 0, -1) if fits(token[:n])), 1)
            lines.append(token[:cut])
            token = token[cut:]
        line = token
    return [*lines, line] if line or not lines else lines


@dataclass
class Overlay:
    """What the window shows over the world, besides the cells: filled in by the window every frame."""

    status: str = ""  # the frame, the speed, the brush, what is under the cursor
    message: str = ""  # what the window says (what was saved, why not...), after the status
    problems: list[str] = field(default_factory=list)
    prompt: str = ""  # a question the next key answers, in place of the message
    help: bool = False
    bar: list[int] = field(default_factory=list)  # the elements offered, in order
    chosen: int = 0
    matches: set[int] = field(default_factory=set)
    brush: tuple[int, bool] | None = None  # (size, square) under the cursor; None: no outline


class View:
    def __init__(self, pygame, world: World, scale: int):
        self.pg = pygame
        self.scale = scale
        self.area = (max(min(world.width * scale, MAX_AREA[0]), MIN_WIDTH), max(min(world.height * scale, MAX_AREA[1]), MIN_HEIGHT))
        self.size = (self.area[0], self.area[1] + BAR + STATUS)
        self.screen = pygame.display.set_mode(self.size)
        pygame.display.set_caption("sandmod")
        self.font = pygame.font.Font(None, 17)
        self.corner = [0, 0]  # the world's cell at the viewport's top-left
        self.heat_view = False
        self.world: World | None = None
        self.said: list[tuple[str, object]] = []  # the message's lines as last drawn, with their rectangles
        self.attach(world)

    # --- what is stale ----------------------------------------------------------------------

    def attach(self, world: World) -> None:
        """Show ``world`` (a new one, or the same under new rules): everything is stale."""
        pygame = self.pg
        self.world = world
        self.pixels = np.zeros((world.height, world.width), np.uint16)  # the cells' colour indices (what a capture keeps)
        self.rgb = np.zeros((world.height, world.width, 4), np.uint8)  # their colours, and a byte that 32-bit pixels scale faster with
        self.cells_surface = pygame.image.frombuffer(self.rgb, (world.width, world.height), "RGBX")  # rgb's memory: no copy
        self.heat = np.zeros((world.height, world.width, 3), np.uint8)
        self.heat_surface = pygame.Surface((world.width, world.height), depth=24)
        self.everything = True
        self.scaled = None

    def show_heat(self, on: bool) -> None:
        self.heat_view, self.everything = on, True

    def refresh(self, world: World) -> None:
        """Bring the picture up to date with ``world``: the chunks changed since the last refresh, or
        everything."""
        if world is not self.world:
            self.attach(world)
        if self.heat_view:
            world.heat_image(self.heat, changed_only=not self.everything)
            self.pg.surfarray.blit_array(self.heat_surface, self.heat.transpose(1, 0, 2))
        else:
            world.image(self.pixels, changed_only=not self.everything, rgb=self.rgb)
            self._preview(world)
        self.everything, self.scaled = False, None

    def _preview(self, world: World) -> None:
        """Paintings due before the next step, shown now (paused, they would wait for it)."""
        for painting in world.paintings:
            if painting.frame == world.frame:
                layer = painting.layer(world.cells)
                shown = layer >= 0
                self.pixels[shown] = world.ruleset.looks.normal[layer[shown], 0]
                self.rgb[shown, :3] = world.ruleset.colours[self.pixels[shown]]

    # --- where things are -------------------------------------------------------------------

    def shown(self) -> tuple[int, int]:
        """How many columns and rows of cells the viewport shows."""
        world = self.world
        return min(world.width, -(-self.area[0] // self.scale)), min(world.height, -(-self.area[1] // self.scale))

    def origin(self) -> tuple[int, int]:
        """The window position of the viewport's first cell: a world smaller than the area is centred."""
        columns, rows = self.shown()
        return max(0, (self.area[0] - columns * self.scale) // 2), max(0, (self.area[1] - rows * self.scale) // 2)

    def cell_at(self, pos) -> tuple[int, int] | None:
        """The cell under a window position (None: not over the world)."""
        left, top = self.origin()
        if not (0 <= pos[0] < self.area[0] and 0 <= pos[1] < self.area[1]) or pos[0] < left or pos[1] < top:
            return None
        x, y = self.corner[0] + (pos[0] - left) // self.scale, self.corner[1] + (pos[1] - top) // self.scale
        return (x, y) if 0 <= x < self.world.width and 0 <= y < self.world.height else None

    def pan(self, dx: int, dy: int) -> None:
        world, (columns, rows) = self.world, self.shown()
        self.corner = [int(np.clip(self.corner[0] + dx, 0, world.width - columns)), int(np.clip(self.corner[1] + dy, 0, world.height - rows))]
        self.scaled = None

    def zoom(self, by: int, pos) -> None:
        """Cells ``by`` pixels bigger or smaller, the cell under ``pos`` staying under it."""
        cell = self.cell_at(pos)
        self.scale = int(np.clip(self.scale + by, 1, 16))
        if cell is not None:
            left, top = self.origin()
            self.corner = [cell[0] - (pos[0] - left) // self.scale, cell[1] - (pos[1] - top) // self.scale]
        self.pan(0, 0)

    def bar_slots(self, elements: list[int]) -> list[tuple[int, int, int]]:
        """(left, width, element) of each swatch in the bar: groups of one archetype apart."""
        archetypes = [self.world.ruleset.elements[e].spec.archetype for e in elements]
        groups = len(set(archetypes))
        width = int(np.clip((self.size[0] - GAP * groups) // max(len(elements), 1), 6, SWATCH))
        slots, left = [], 2
        for number, element in enumerate(elements):
            if number and archetypes[number] != archetypes[number - 1]:
                left += GAP
            if left + width > self.size[0]:
                break
            slots.append((left, width, element))
            left += width
        return slots

    def bar_element_at(self, pos, elements: list[int]) -> int | None:
        if not (self.area[1] <= pos[1] < self.area[1] + BAR):
            return None
        return next((e for left, width, e in self.bar_slots(elements) if left <= pos[0] < left + width), None)

    # --- drawing ----------------------------------------------------------------------------

    def draw(self, overlay: Overlay, mouse) -> None:
        """The whole window, shown."""
        self._world()
        if overlay.brush is not None:
            self._outline(mouse, *overlay.brush)
        self._problems(overlay.problems)
        self._bar(overlay)
        self._status(overlay)
        self._tooltip(overlay, mouse)
        if overlay.help:
            self._help()
        self.pg.display.flip()

    def _world(self) -> None:
        pygame = self.pg
        if self.scaled is None:
            columns, rows = self.shown()
            source = (self.heat_surface if self.heat_view else self.cells_surface).subsurface((*self.corner, columns, rows))
            self.scaled = pygame.transform.scale(source, (columns * self.scale, rows * self.scale))
        self.screen.fill((0, 0, 0), (0, 0, *self.area))
        self.screen.blit(self.scaled, self.origin())

    def _outline(self, mouse, size: int, square: bool) -> None:
        cell = self.cell_at(mouse)
        if cell is None:
            return
        left, top = self.origin()
        x = left + (cell[0] - self.corner[0]) * self.scale + self.scale // 2
        y = top + (cell[1] - self.corner[1]) * self.scale + self.scale // 2
        reach = max(size * self.scale // 2, 2)
        if square:
            self.pg.draw.rect(self.screen, TEXT, (x - reach, y - reach, 2 * reach, 2 * reach), 1)
        else:
            self.pg.draw.circle(self.screen, TEXT, (x, y), reach, 1)

    def _text(self, text: str, at: tuple[int, int], colour=TEXT, back=None):
        """``text`` drawn with its top-left at ``at``; the rectangle it took."""
        image = self.font.render(text, True, colour)
        if back is not None:
            self.pg.draw.rect(self.screen, back, (at[0] - 3, at[1] - 2, image.get_width() + 6, image.get_height() + 4))
        return self.screen.blit(image, at)

    def _lines(self, text: str) -> list[str]:
        return wrap(self.font, text, self.size[0] - 2 * MARGIN)

    def _problems(self, problems: list[str]) -> None:
        shown = problems[:6] + ([f"... and {len(problems) - 6} more"] if len(problems) > 6 else [])
        if shown:
            shown.append("the old rules go on; save the mod again when it is fixed")
        lines = [line for problem in shown for line in self._lines(problem)]
        for number, line in enumerate(lines[: (self.area[1] - MARGIN) // LINE]):
            self._text(line, (MARGIN, MARGIN + number * LINE), RED, back=PROBLEM_BACK)

    def _bar(self, overlay: Overlay) -> None:
        pygame, top = self.pg, self.area[1]
        pygame.draw.rect(self.screen, PANEL, (0, top, self.size[0], BAR + STATUS))
        for left, width, element in self.bar_slots(overlay.bar):
            colour = self.world.ruleset.swatch(element)
            pygame.draw.rect(self.screen, colour, (left + 1, top + 3, width - 2, BAR - 6))
            if element == overlay.chosen or element in overlay.matches:
                pygame.draw.rect(self.screen, (255, 255, 255), (left, top + 1, width, BAR - 2), 2)

    def _status(self, overlay: Overlay) -> None:
        """The status line; the message (or prompt) after it if it fits there, else wrapped in lines
        over the bottom of the world, the whole of it readable."""
        said, colour = (overlay.prompt, RED) if overlay.prompt else (overlay.message, TEXT)
        row = self.area[1] + BAR + 3
        status = self._text(overlay.status, (MARGIN, row))
        gap = self.font.size("   ")[0] if overlay.status else 0
        if status.right + gap + self.font.size(said)[0] <= self.size[0] - MARGIN:
            self.said = [(said, self._text(said, (status.right + gap, row), colour))] if said else []
            return
        lines = self._lines(said)
        top = max(self.area[1] - len(lines) * LINE - 2, 0)
        self.said = [(line, self._text(line, (MARGIN, top + number * LINE), colour, back=PANEL)) for number, line in enumerate(lines)]

    def _tooltip(self, overlay: Overlay, mouse) -> None:
        element = self.bar_element_at(mouse, overlay.bar)
        if element is None:
            return
        info = self.world.ruleset.elements[element]
        text = f"{info.name}  ({info.spec.archetype}, mod {info.mod})"
        width = self.font.size(text)[0]
        self._text(text, (int(np.clip(mouse[0] - width // 2, 4, self.size[0] - width - 4)), self.area[1] - 18), back=(40, 40, 48))

    def _help(self) -> None:
        pygame = self.pg
        shade = pygame.Surface(self.size, pygame.SRCALPHA)
        shade.fill((0, 0, 0, 215))
        self.screen.blit(shade, (0, 0))
        lines = help_lines()
        per_column = -(-len(lines) // 2)
        column = self.size[0] // 2
        keys_width = max(self.font.size(keys)[0] for keys, _ in lines) + 12
        self._text("sandmod play: every key (F1 or ? closes this)", (12, 8))
        for number, (keys, what) in enumerate(lines):
            left = 12 + (number // per_column) * column
            top = 30 + (number % per_column) * 16
            self._text(keys, (left, top), (255, 220, 120))
            while what and self.font.size(what)[0] > column - keys_width - 16:
                what = what[:-2] + "…"[: len(what) > 1]
            self._text(what, (left + keys_width, top), TEXT)
