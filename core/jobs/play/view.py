"""The window's picture: the world through a viewport, the element menu (:mod:`.menu`) and the
status line below it, the brush outline and the overlays (problems, help).

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
from .menu import FAVOURITES, KEYED, Menu

TAB = 20  # the height of the menu's row of section tabs, in pixels
SLOT = (94, 20)  # an element's labelled swatch in the menu, with its frame
ROWS = 3  # rows of swatches on a page of the menu
ARROW = 18  # the width of a < or > button
PAGER = 2 * ARROW + 8  # right of the swatches: the page number over the page buttons
MENU = TAB + ROWS * SLOT[1] + 6  # the menu's height
STATUS = 20  # the status line's
MIN_WIDTH = 640  # room for six swatches a row and the status line
MIN_HEIGHT = 280  # room for the help
MAX_AREA = (1280, 800)  # the most of the screen the world takes; a larger one is seen through a viewport
LINE = 16  # a line of text's height, in pixels
MARGIN = 6  # between text and the window's edges
TEXT, DIM, RED, KEYS = (225, 225, 225), (150, 150, 160), (255, 120, 100), (255, 220, 120)
PANEL, PROBLEM_BACK, BUTTON = (24, 24, 28), (20, 10, 10), (52, 52, 62)
CHOSEN, TAKEN = (255, 255, 255), KEYS  # the frames of the brush's element and of what enter takes


def luminance(rgb) -> float:
    """The relative luminance of an sRGB colour (WCAG 2), 0 to 1."""
    linear = [v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4 for v in (c / 255 for c in rgb)]
    return 0.2126 * linear[0] + 0.7152 * linear[1] + 0.0722 * linear[2]


def contrast(a, b) -> float:
    """The WCAG contrast ratio of two colours, 1 to 21."""
    light, dark = sorted((luminance(a), luminance(b)), reverse=True)
    return (light + 0.05) / (dark + 0.05)


def ink(back) -> tuple[int, int, int]:
    """Black or white, whichever reads better on ``back`` (at least 4.5:1, WCAG's bar for text)."""
    return max(((0, 0, 0), (255, 255, 255)), key=lambda colour: contrast(colour, back))


def fit(font, text: str, width: int) -> str:
    """``text``, cut short with an ellipsis if it is wider than ``width`` pixels in ``font``."""
    while len(text) > 1 and font.size(text)[0] > width:
        text = text[:-2] + "…"
    return text


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
    menu: Menu | None = None
    chosen: int = 0  # the brush's element
    brush: tuple[int, bool] | None = None  # (size, square) under the cursor; None: no outline


class View:
    def __init__(self, pygame, world: World, scale: int):
        self.pg = pygame
        self.scale = scale
        self.area = (max(min(world.width * scale, MAX_AREA[0]), MIN_WIDTH), max(min(world.height * scale, MAX_AREA[1]), MIN_HEIGHT))
        self.size = (self.area[0], self.area[1] + MENU + STATUS)
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
        # Their colours, 32 bits a pixel (which pygame scales fastest), in the screen's own byte order
        # where it is the usual B, G, R, X: then the cells are scaled straight onto the screen.
        self.native = self.screen.get_masks()[:3] == (0xFF0000, 0xFF00, 0xFF)
        self.colours = np.ascontiguousarray(world.ruleset.colours[:, ::-1] if self.native else world.ruleset.colours)
        self.rgb = np.full((world.height, world.width, 4), 255, np.uint8)
        self.cells_surface = pygame.image.frombuffer(self.rgb, (world.width, world.height), "BGRA" if self.native else "RGBX")  # rgb's memory: no copy
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
            world.image(self.pixels, changed_only=not self.everything, rgb=self.rgb, colours=self.colours)
            self._preview(world)
        self.everything, self.scaled = False, None

    def _preview(self, world: World) -> None:
        """Paintings due before the next step, shown now (paused, they would wait for it)."""
        for painting in world.paintings:
            if painting.frame == world.frame:
                layer = painting.layer(world.cells)
                shown = layer >= 0
                self.pixels[shown] = world.ruleset.looks.normal[layer[shown], 0]
                self.rgb[shown, :3] = self.colours[self.pixels[shown]]

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

    def per_page(self) -> int:
        """How many swatches a page of the menu holds."""
        return self._columns() * ROWS

    def _columns(self) -> int:
        return max(1, (self.size[0] - 4 - PAGER) // SLOT[0])

    def in_menu(self, pos) -> bool:
        return self.area[1] <= pos[1] < self.area[1] + MENU

    def menu_items(self, menu: Menu) -> list[tuple[tuple[int, int, int, int], tuple[str, object]]]:
        """Each thing in the menu that a click does something on: its rectangle, and the action,
        ("section", name), ("sections", -1 or 1), ("page", -1 or 1) or ("element", element)."""
        top, right = self.area[1], self.size[0]
        items = self._tabs(menu)
        items += [((right - 2 * ARROW - 2, top + 2, ARROW - 2, TAB - 4), ("sections", -1)), ((right - ARROW - 2, top + 2, ARROW - 2, TAB - 4), ("sections", 1))]
        columns, grid = self._columns(), top + TAB + 2
        for number, element in enumerate(menu.on_page()):
            row, column = divmod(number, columns)
            items.append(((2 + column * SLOT[0], grid + row * SLOT[1], *SLOT), ("element", element)))
        pager = right - PAGER
        items += [((pager, grid + SLOT[1], ARROW, SLOT[1] - 2), ("page", -1)), ((pager + ARROW + 4, grid + SLOT[1], ARROW, SLOT[1] - 2), ("page", 1))]
        return items

    def _tabs(self, menu: Menu) -> list[tuple[tuple[int, int, int, int], tuple[str, object]]]:
        """The tabs that fit left of the < > buttons: from the first, or from one far enough on
        that the section shown is among them."""
        tabs = menu.tabs()
        widths = [self.font.size(_tab_label(s))[0] + 14 for s in tabs]
        room = self.size[0] - 2 * ARROW - 8
        shown = [s.name for s in tabs].index(menu.current().name)
        first = 0
        while first < shown and 2 + sum(widths[first : shown + 1]) > room:  # the row starts 2 pixels in
            first += 1
        items, left = [], 2
        for section, width in zip(tabs[first:], widths[first:]):
            if left + width > room:
                break
            items.append(((left, self.area[1] + 2, width - 2, TAB - 2), ("section", section.name)))
            left += width
        return items

    def menu_at(self, pos, menu: Menu) -> tuple[str, object] | None:
        """What a click at ``pos`` does in the menu (see :meth:`menu_items`); None: nothing there."""
        if not self.in_menu(pos):
            return None
        inside = lambda r: r[0] <= pos[0] < r[0] + r[2] and r[1] <= pos[1] < r[1] + r[3]  # noqa: E731
        return next((action for rect, action in self.menu_items(menu) if inside(rect)), None)

    # --- drawing ----------------------------------------------------------------------------

    def draw(self, overlay: Overlay, mouse) -> None:
        """The whole window, shown."""
        self._world()
        if overlay.brush is not None:
            self._outline(mouse, *overlay.brush)
        self._problems(overlay.problems)
        self._menu(overlay)
        self._status(overlay)
        self._tooltip(overlay, mouse)
        if overlay.help:
            self._help()
        self.pg.display.flip()

    def _world(self) -> None:
        pygame = self.pg
        columns, rows = self.shown()
        size = (columns * self.scale, rows * self.scale)
        self.screen.fill((0, 0, 0), (0, 0, *self.area))
        if self.native and not self.heat_view:  # straight onto the screen, every frame: no copy to blit
            source = self.cells_surface.subsurface((*self.corner, columns, rows))
            pygame.transform.scale(source, size, self.screen.subsurface((*self.origin(), *size)))
            return
        if self.scaled is None:
            source = (self.heat_surface if self.heat_view else self.cells_surface).subsurface((*self.corner, columns, rows))
            self.scaled = pygame.transform.scale(source, size)
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

    def _menu(self, overlay: Overlay) -> None:
        """The tabs, the page of swatches shown, and the page buttons."""
        menu, top = overlay.menu, self.area[1]
        self.pg.draw.rect(self.screen, PANEL, (0, top, self.size[0], MENU + STATUS))
        if menu is None:
            return
        names = {s.name: s for s in menu.tabs()}
        ends = {"sections": (True, True), "page": (menu.page > 0, menu.page < menu.pages() - 1)}
        for rect, (kind, what) in self.menu_items(menu):
            if kind == "section":
                shown = what == menu.current().name
                self.pg.draw.rect(self.screen, BUTTON if shown else PANEL, rect, border_radius=3)
                self._text(_tab_label(names[what]), (rect[0] + 7, rect[1] + 4), KEYS if what == FAVOURITES else TEXT if shown else DIM)
            elif kind == "element":
                self._swatch(rect, what, overlay, menu)
            else:
                self._button(rect, "<" if what < 0 else ">", ends[kind][what > 0])
        page = f"{min(menu.page, menu.pages() - 1) + 1}/{menu.pages()}"
        self._text(page, (self.size[0] - PAGER + (PAGER - self.font.size(page)[0]) // 2, top + TAB + 6), DIM)

    def _swatch(self, rect, element: int, overlay: Overlay, menu: Menu) -> None:
        """An element's swatch with its name on it (its key's number before it, among the favourites);
        framed if the brush has it, or if enter takes it."""
        left, top, width, height = rect
        colour = self.world.ruleset.swatch(element)
        name = self.world.ruleset.elements[element].name
        if menu.current().name == FAVOURITES and menu.favourites.index(element) < KEYED:
            name = f"{menu.favourites.index(element) + 1} {name}"
        taken = menu.found[0] if menu.found and menu.current().elements is menu.found else None
        frame = CHOSEN if element == overlay.chosen else TAKEN if element == taken else None
        if frame is not None:
            self.pg.draw.rect(self.screen, frame, rect, 2)
        self.pg.draw.rect(self.screen, colour, (left + 2, top + 2, width - 4, height - 4))
        label = self.font.render(fit(self.font, name, width - 10), True, ink(colour))
        self.screen.blit(label, (left + 5, top + (height - label.get_height()) // 2))

    def _button(self, rect, text: str, enabled: bool) -> None:
        self.pg.draw.rect(self.screen, BUTTON, rect, border_radius=3)
        width, height = self.font.size(text)
        self._text(text, (rect[0] + (rect[2] - width) // 2, rect[1] + (rect[3] - height) // 2), TEXT if enabled else DIM)

    def _status(self, overlay: Overlay) -> None:
        """The status line; the message (or prompt) after it if it fits there, else wrapped in lines
        over the bottom of the world, the whole of it readable."""
        said, colour = (overlay.prompt, RED) if overlay.prompt else (overlay.message, TEXT)
        row = self.area[1] + MENU + 3
        status = self._text(overlay.status, (MARGIN, row))
        gap = self.font.size("   ")[0] if overlay.status else 0
        if status.right + gap + self.font.size(said)[0] <= self.size[0] - MARGIN:
            self.said = [(said, self._text(said, (status.right + gap, row), colour))] if said else []
            return
        lines = self._lines(said)
        top = max(self.area[1] - len(lines) * LINE - 2, 0)
        self.said = [(line, self._text(line, (MARGIN, top + number * LINE), colour, back=PANEL)) for number, line in enumerate(lines)]

    def _tooltip(self, overlay: Overlay, mouse) -> None:
        """Over the status line, what the swatch under the mouse is: its id, archetype, mod and section."""
        action = self.menu_at(mouse, overlay.menu) if overlay.menu is not None else None
        if action is None or action[0] != "element":
            return
        info = self.world.ruleset.elements[action[1]]
        spec = info.spec
        row = self.area[1] + MENU
        self.pg.draw.rect(self.screen, PANEL, (0, row, self.size[0], STATUS))
        self._text(f"{info.id}   {spec.archetype}, mod {info.mod}, in {spec.menu_category}", (MARGIN, row + 3))

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
            self._text(keys, (left, top), KEYS)
            self._text(fit(self.font, what, column - keys_width - 16), (left + keys_width, top), TEXT)


def _tab_label(section) -> str:
    return f"{section.name} {len(section.elements)}"
