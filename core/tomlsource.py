"""Read a TOML file and remember where each field was written.

``tomllib`` gives values but no positions. :class:`TomlSource` keeps the text
and maps every key path (``("elements", "lava", "density")``,
``("reactions", 2, "chance")``) to the line it is on, so that a problem found
later, by pydantic or by the compiler, can name its line.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

from .errors import Problem, ProblemsError, display_path

Loc = tuple[str | int, ...]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_DECODE_POSITION = re.compile(r"\s*\(at line (\d+), column (\d+)\)$")
_DECODE_END = re.compile(r"\s*\(at end of document\)$")


def _parse_key(text: str, pos: int) -> tuple[list[str], int] | None:
    """Parse a dotted TOML key starting at ``pos``; return its parts and the end position."""
    parts: list[str] = []
    while True:
        while pos < len(text) and text[pos] in " \t":
            pos += 1
        if pos >= len(text):
            return None
        quote = text[pos]
        if quote in "\"'":
            end = text.find(quote, pos + 1)
            if end < 0:
                return None
            parts.append(text[pos + 1 : end])
            pos = end + 1
        else:
            m = _BARE_KEY.match(text, pos)
            if not m:
                return None
            parts.append(m.group())
            pos = m.end()
        while pos < len(text) and text[pos] in " \t":
            pos += 1
        if pos < len(text) and text[pos] == ".":
            pos += 1
            continue
        return parts, pos


def index_lines(text: str) -> dict[Loc, int]:
    """Map each table header and key path in ``text`` to its 1-based line."""
    lines: dict[Loc, int] = {}
    array_counts: dict[tuple[str, ...], int] = {}
    table: Loc = ()
    in_multiline = False
    for number, raw in enumerate(text.splitlines(), start=1):
        toggles = raw.count('"""') % 2 or raw.count("'''") % 2
        if in_multiline:
            in_multiline = not toggles
            continue
        in_multiline = bool(toggles)
        stripped = raw.strip()
        if stripped.startswith("["):
            is_array = stripped.startswith("[[")
            parsed = _parse_key(stripped, 2 if is_array else 1)
            if parsed is None:
                continue
            keys = parsed[0]
            resolved: list[str | int] = []
            for i, key in enumerate(keys):
                resolved.append(key)
                prefix = tuple(keys[: i + 1])
                is_last = i == len(keys) - 1
                if is_array and is_last:
                    array_counts[prefix] = array_counts.get(prefix, -1) + 1
                    # Tables nested under an earlier entry of this array are forgotten.
                    for other in [k for k in array_counts if k[: len(prefix)] == prefix and k != prefix]:
                        del array_counts[other]
                if prefix in array_counts:
                    resolved.append(array_counts[prefix])
            table = tuple(resolved)
            for end in range(1, len(table) + 1):  # [a.b] also opens a
                lines.setdefault(table[:end], number)
            continue
        parsed = _parse_key(raw, 0)
        if parsed is None:
            continue
        keys, end = parsed
        if end < len(raw) and raw[end] == "=":
            lines.setdefault(table + tuple(keys), number)
    return lines


@dataclass
class TomlSource:
    """A parsed TOML file: its data, its path as shown to users, and key positions."""

    name: str
    text: str
    data: dict[str, Any]
    lines: dict[Loc, int] = field(default_factory=dict)
    path: Path | None = None  # the file it was read from, if any

    @classmethod
    def read(cls, path: str | Path) -> "TomlSource":
        """Read and parse ``path``; raise :class:`ProblemsError` for unreadable or invalid TOML."""
        name = display_path(path)
        try:
            text = Path(path).read_text(encoding="utf-8")
        except OSError as exc:
            raise ProblemsError([Problem(name, None, "", f"cannot read file: {exc.strerror or exc}")])
        except UnicodeDecodeError:
            raise ProblemsError([Problem(name, None, "", "file is not UTF-8 text")])
        source = cls.parse(text, name)
        source.path = Path(path).resolve()
        return source

    @classmethod
    def parse(cls, text: str, name: str) -> "TomlSource":
        """Parse TOML ``text`` that came from ``name``."""
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ProblemsError([_decode_problem(name, text, exc)])
        return cls(name, text, data, index_lines(text))

    def line_of(self, loc: Sequence[str | int]) -> int | None:
        """The line of the longest prefix of ``loc`` that is written in the file."""
        loc = tuple(loc)
        for end in range(len(loc), 0, -1):
            line = self.lines.get(loc[:end])
            if line is not None:
                return line
        return None

    def problem(self, loc: Sequence[str | int], message: str) -> Problem:
        """A problem at field path ``loc`` of this file."""
        return Problem(self.name, self.line_of(loc), format_loc(loc), message)


def format_loc(loc: Sequence[str | int]) -> str:
    """``("reactions", 2, "chance")`` -> ``reactions.2.chance``."""
    return ".".join(str(part) for part in loc)


def _decode_problem(name: str, text: str, exc: tomllib.TOMLDecodeError) -> Problem:
    message = str(exc)
    line = None
    m = _DECODE_POSITION.search(message)
    if m:
        line = int(m.group(1))
        message = message[: m.start()]
    elif _DECODE_END.search(message):
        line = max(1, text.count("\n") + (0 if text.endswith("\n") else 1))
        message = _DECODE_END.sub("", message)
    return Problem(name, line, "", f"invalid TOML: {message}")
