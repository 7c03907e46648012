"""The element menu of ``sandmod play``: its sections (the favourites, a search's matches while one
is typed, then each category of elements), which one is shown and at which page. The view lays it
out and draws it; nothing here needs pygame."""

from __future__ import annotations

from dataclasses import dataclass
from itertools import groupby, zip_longest

from ...formats.modspec import ARCHETYPE_CATEGORIES
from ...rules.compiler import Ruleset

FAVOURITES = "Favourites"  # capitalised, unlike every category: the names of these two sections are theirs alone
FOUND = "Found"  # the section of a search's matches
KEYED = 9  # the favourites the number keys give
#: The sections of elements without a category of their own, in the menu's order; the mods' own follow, by name.
FIRST = tuple(ARCHETYPE_CATEGORIES[a] for a in ("powder", "liquid", "gas", "static", "particle"))
#: What a player starts with at hand, where loaded (see :func:`default_favourites`).
STARTERS = ("sand:sand", "water:water", "base:stone", "fire:fire", "wood:wood", "oil:oil", "lava:lava", "acid:acid", "explosives:gunpowder")


@dataclass
class Section:
    name: str
    elements: list[int]


def _rank(category: str) -> tuple[int, str]:
    return (FIRST.index(category), "") if category in FIRST else (len(FIRST), category)


def offered(ruleset: Ruleset) -> list[int]:
    """Every element a brush paints (all but empty and the particle), hidden ones too, in the menu's
    order: by section, then by name."""
    chosen = [e for e in ruleset.elements[1:] if e.index != ruleset.particle]
    return [e.index for e in sorted(chosen, key=lambda e: (_rank(e.spec.menu_category), e.name, e.id))]


def listed(ruleset: Ruleset) -> list[int]:
    """The elements the menu shows: those offered that are not ``hidden``."""
    return [e for e in offered(ruleset) if not ruleset.elements[e].spec.hidden]


def sections(ruleset: Ruleset) -> list[Section]:
    """The elements listed, one section per category."""
    category = lambda e: ruleset.elements[e].spec.menu_category  # noqa: E731
    return [Section(name, list(elements)) for name, elements in groupby(listed(ruleset), key=category)]


def default_favourites(ruleset: Ruleset, first: int) -> list[int]:
    """The favourites a player starts with: ``first`` (what the brush starts with), the :data:`STARTERS`
    loaded, then the first element of each section, the second of each, and so on: nine in all."""
    ids = {e.id: e.index for e in ruleset.elements}
    chosen = [first, *(ids[i] for i in STARTERS if i in ids and not ruleset.elements[ids[i]].spec.hidden)]
    for row in zip_longest(*(s.elements for s in sections(ruleset))):
        chosen += [e for e in row if e is not None]
    return list(dict.fromkeys(chosen))[:KEYED]


class Menu:
    """The sections, the one shown (by name) and its page; ``per_page``: how many elements a page holds."""

    def __init__(self, ruleset: Ruleset, per_page: int, favourites: list[int]):
        self.ruleset, self.per_page, self.favourites = ruleset, per_page, favourites
        self.sections = sections(ruleset)
        self.found: list[int] | None = None  # a search's matches, while one is typed
        self.shown, self.page, self.before = FAVOURITES, 0, FAVOURITES  # before: what a search's section replaced

    def reloaded(self, ruleset: Ruleset) -> Menu:
        """This menu over new rules: its favourites (those still defined) and its section kept."""
        ids = {e.id: e.index for e in ruleset.elements}
        kept = [ids[i] for i in (self.ruleset.elements[e].id for e in self.favourites) if i in ids]
        menu = Menu(ruleset, self.per_page, kept)
        menu.show(self.shown)
        return menu

    def tabs(self) -> list[Section]:
        found = [Section(FOUND, self.found)] if self.found is not None else []
        return [*found, Section(FAVOURITES, self.favourites), *self.sections]

    def current(self) -> Section:
        """The section shown (the favourites, if the one named is gone)."""
        return next((s for s in self.tabs() if s.name == self.shown), self.tabs()[int(self.found is not None)])

    def pages(self) -> int:
        return max(1, -(-len(self.current().elements) // self.per_page))

    def on_page(self) -> list[int]:
        """The elements of the section shown on the page shown."""
        page = min(self.page, self.pages() - 1)
        return self.current().elements[page * self.per_page : (page + 1) * self.per_page]

    def show(self, name: str) -> None:
        self.shown, self.page = name, 0

    def next_section(self, by: int) -> None:
        tabs = [s.name for s in self.tabs()]
        self.show(tabs[(tabs.index(self.current().name) + by) % len(tabs)])

    def turn(self, by: int) -> None:
        """Another page of the section shown (not past the first or last)."""
        self.page = max(0, min(self.page + by, self.pages() - 1))

    def next_element(self, element: int, by: int) -> int:
        """The element ``by`` places after ``element`` in the section shown (round its end; its first
        if ``element`` is not in it), its page shown."""
        elements = self.current().elements or [element]
        at = elements.index(element) + by if element in elements else 0
        chosen = elements[at % len(elements)]
        self.reveal(chosen)
        return chosen

    def reveal(self, element: int) -> None:
        """Show ``element``: in the section shown if it is there, else in its own section."""
        if element not in self.current().elements:
            self.show(next((s.name for s in self.sections if element in s.elements), self.shown))
        elements = self.current().elements
        self.page = elements.index(element) // self.per_page if element in elements else self.page

    def find(self, matches: list[int] | None) -> None:
        """Show a search's matches in a section of their own; None: the search is over, the section
        shown before it comes back."""
        if matches is not None and self.found is None:
            self.before, self.shown = self.current().name, FOUND
        elif matches is None and self.found is not None:
            self.shown = self.before
        self.found, self.page = matches, 0

    def pin(self, element: int) -> bool:
        """Make ``element`` a favourite, or no longer one if it was; whether it is now."""
        if element in self.favourites:
            self.favourites.remove(element)
            return False
        self.favourites.append(element)
        return True

    def favourite(self, number: int) -> int | None:
        """The favourite that key ``number`` (1-9) gives, if there is one."""
        return self.favourites[number - 1] if number <= len(self.favourites) else None
