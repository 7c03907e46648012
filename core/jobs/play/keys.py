"""What each key and button does in ``sandmod play``: one table, read by the window's input, its help
overlay and ``sandmod play --help``. Nothing here needs pygame."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Binding:
    """Keys (as ``pygame.key.name`` gives them, ``ctrl+`` before; none for the mouse), the window's
    command they run (``Play.do_<command>``, given the key's name), and what the help says."""

    keys: tuple[str, ...]
    command: str
    help: str
    shown: str = ""  # the keys as the help writes them, when not simply listed

    @property
    def label(self) -> str:
        return self.shown or ", ".join(self.keys)


BINDINGS = (
    Binding((), "", "paint; shift: a line from the last point", "left button"),
    Binding((), "", "erase", "right button"),
    Binding((), "", "pick the element under the cursor", "middle button"),
    Binding((), "", "brush size; ctrl: zoom; menu: pages", "wheel"),
    Binding(("[", "]"), "size", "brush size"),
    Binding(("b",), "square", "round or square brush"),
    Binding(("r",), "replace", "replace mode: over one element only"),
    Binding(("h",), "heat", "heat brush (again: paint)"),
    Binding(("c",), "cold", "cold brush (again: paint)"),
    Binding(("q",), "spray", "spray the element, while held"),
    Binding(("f",), "fling", "fling cells as particles, while held"),
    Binding(("x",), "explode", "explode at the cursor"),
    Binding(tuple("123456789"), "choose", "a favourite (or click the menu)", "1-9"),
    Binding(("m",), "pin", "pin or unpin as a favourite"),
    Binding(("tab", "shift+tab"), "section", "menu: next section (shift: back)", "tab"),
    Binding((",", "."), "element", "menu: element before, after", ", ."),
    Binding(("page up", "page down"), "page", "menu: page before, after", "page up, down"),
    Binding(("/",), "search", "find by name, then enter"),
    Binding(("space",), "pause", "pause or go on"),
    Binding(("n",), "step", "one step"),
    Binding(("=", "+", "[+]", "-", "[-]"), "speed", "faster, slower", "+ -"),
    Binding(("v",), "heat_view", "heat view"),
    Binding(("ctrl+z",), "undo", "undo a stroke, spray, blast or clear"),
    Binding(("delete",), "clear", "clear the world"),
    Binding(("left", "right", "up", "down"), "pan", "pan a world larger than the window", "arrows"),
    Binding(("s",), "save", "save the session (render replays it)"),
    Binding(("f5",), "save_snapshot", "save a snapshot"),
    Binding(("f9",), "load_snapshot", "load it: later strokes are dropped"),
    Binding(("p",), "screenshot", "screenshot of the window (PNG)"),
    Binding(("g",), "capture", "GIF of the last 10 seconds"),
    Binding(("f1", "?"), "help", "this help"),
    Binding(("escape",), "quit", "quit (asks if not saved)"),
)

#: Commands repeated every step while their key is held.
HELD = ("spray", "fling")

_BY_KEY = {key: binding.command for binding in BINDINGS for key in binding.keys}


def command(name: str, typed: str = "") -> str | None:
    """The command of a key, by its name (``ctrl+z``) or the character it typed (``?``)."""
    return _BY_KEY.get(typed) or _BY_KEY.get(name)


def help_lines() -> list[tuple[str, str]]:
    """(keys, what they do) for every binding, in the table's order."""
    return [(binding.label, binding.help) for binding in BINDINGS]


def help_text() -> str:
    """The bindings as plain text, for ``sandmod play --help``."""
    width = max(len(keys) for keys, _ in help_lines())
    return "\n".join(f"{keys.ljust(width)}  {what}" for keys, what in help_lines())
