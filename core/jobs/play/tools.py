"""The player's brush and tools, as the timeline events they add to a session: what a stroke,
a spray, a fling or a blast at a cell is, written as a world file writes it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...rules.compiler import Ruleset

MAX_BRUSH = 64
HOT, COLD = 800.0, -100.0  # what the heat and cold brushes set, in degrees


@dataclass
class Brush:
    element: int
    size: int = 5
    square: bool = False
    tool: str = "paint"  # paint, heat, cold
    replace: bool = False
    over: int | None = None  # replace mode: the element this stroke paints over


Event = tuple[str, dict[str, Any]]  # (action, table)


def stroke(brush: Brush, ruleset: Ruleset, start: tuple[int, int], end: tuple[int, int], erase: bool) -> Event:
    """The brush dragged from cell ``start`` to ``end``: paint, erase, heat or cold."""
    shape: dict[str, Any] = {"shape": "stroke", "points": [list(start), list(end)], "thickness": brush.size}
    if brush.square:
        shape["brush"] = "square"
    if erase:
        return "erase", shape
    if brush.tool in ("heat", "cold"):
        return "heat", {**shape, "temperature": HOT if brush.tool == "heat" else COLD}
    table = {**shape, "element": ruleset.elements[brush.element].id}
    if brush.over is not None:
        table["over"] = ruleset.elements[brush.over].id
    return "paint", table


def spray(brush: Brush, ruleset: Ruleset, at: tuple[int, int]) -> Event:
    """A burst of the brush's element flying up from around ``at``."""
    return "spawn", {"element": ruleset.elements[brush.element].id, "at": list(at), "radius": brush.size / 2,
                     "count": 24, "direction": 90, "spread": 120, "speed": [1.5, 3.0]}


def fling(brush: Brush, at: tuple[int, int]) -> Event:
    """The cells under the brush at ``at`` sent flying up as particles."""
    return "launch", {"shape": "circle", "x": at[0], "y": at[1], "radius": max(brush.size // 2, 1),
                      "direction": 90, "spread": 140, "speed": [1.0, 4.0]}


def blast(brush: Brush, at: tuple[int, int]) -> Event:
    return "explode", {"at": list(at), "radius": max(brush.size, 4), "strength": 20.0}


def default_element(ruleset: Ruleset, offered: list[int], named: list[str] | None = None) -> int:
    """What a first stroke paints: sand; else the first of the mods the world names (``named``, in its
    order; None: every mod loaded) whose namesake element (``lava:lava``) is a powder or liquid; else
    the first powder, else the first liquid, of those mods, in the menu's order; else the first powder
    or liquid offered; else the first element offered."""
    try:
        return ruleset.index("sand:sand")
    except KeyError:
        pass
    for mod in named or []:
        namesake = [e for e in offered if ruleset.elements[e].id == f"{mod}:{mod}"]
        if namesake and ruleset.elements[namesake[0]].spec.archetype in ("powder", "liquid"):
            return namesake[0]
    order = {name: number for number, name in enumerate(named or [])}
    mods = [e for e in offered if named is None or ruleset.elements[e].mod in order]
    mods.sort(key=lambda e: order.get(ruleset.elements[e].mod, 0))  # stable: the menu's order within a mod
    for candidates in (mods, offered):
        for archetype in ("powder", "liquid"):
            found = [e for e in candidates if ruleset.elements[e].spec.archetype == archetype]
            if found:
                return found[0]
    return (offered or [0])[0]


def search(ruleset: Ruleset, offered: list[int], text: str) -> list[int]:
    """Elements whose id holds ``text``: the exact name first, then names that start with it, then
    ids that do, then the rest, each in the menu's order."""
    text = text.strip().lower()
    if not text:
        return []

    def rank(index: int) -> int:
        element = ruleset.elements[index]
        if text in (element.name, element.id):
            return 0
        if element.name.startswith(text):
            return 1
        return 2 if element.id.startswith(text) else 3

    found = [e for e in offered if text in ruleset.elements[e].id]
    return sorted(found, key=rank)
