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

from ..errors import Problem, ProblemsError, display_path
from .userfiles import Refused, read_bytes

#: A key's path in a file: its keys and list indices, ``("elements", "sand", "density")``.
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


def index_positions(text: str) -> dict[Loc, tuple[int, int]]:
    """Map each table header and key path in ``text`` to its 1-based (line, column).

    Keys inside inline tables (``heated = { above = 100 }``) are indexed too.
    """
    positions: dict[Loc, tuple[int, int]] = {}
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
        column = len(raw) - len(raw.lstrip()) + 1
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
                positions.setdefault(table[:end], (number, column))
            continue
        parsed = _parse_key(raw, 0)
        if parsed is None:
            continue
        keys, end = parsed
        if end < len(raw) and raw[end] == "=":
            loc = table + tuple(keys)
            positions.setdefault(loc, (number, column))
            value = _skip_blanks(raw, end + 1)
            if value < len(raw) and raw[value] == "{":
                _index_inline_table(raw, value, loc, number, positions)
    return positions


def index_lines(text: str) -> dict[Loc, int]:
    """Map each table header and key path in ``text`` to its 1-based line."""
    return {loc: line for loc, (line, _) in index_positions(text).items()}


def _skip_blanks(text: str, pos: int) -> int:
    while pos < len(text) and text[pos] in " \t":
        pos += 1
    return pos


def _index_inline_table(raw: str, pos: int, prefix: Loc, number: int, positions: dict) -> int:
    """Index the keys of the inline table opening at ``raw[pos]``; return the position after it."""
    pos += 1
    while pos < len(raw):
        pos = _skip_blanks(raw, pos)
        if pos < len(raw) and raw[pos] == ",":
            pos += 1
            continue
        if pos >= len(raw) or raw[pos] == "}":
            return pos + 1
        parsed = _parse_key(raw, pos)
        if parsed is None:
            return len(raw)
        keys, end = parsed
        if end >= len(raw) or raw[end] != "=":
            return len(raw)
        loc = prefix + tuple(keys)
        positions.setdefault(loc, (number, pos + 1))
        pos = _skip_blanks(raw, end + 1)
        if pos < len(raw) and raw[pos] == "{":
            pos = _index_inline_table(raw, pos, loc, number, positions)
        else:
            pos = _skip_value(raw, pos)
    return pos


def _skip_value(raw: str, pos: int) -> int:
    """The position of the ',' or '}' that ends the value starting at ``pos``."""
    depth = 0
    while pos < len(raw):
        char = raw[pos]
        if char in "\"'":
            end = pos + 1
            while end < len(raw) and raw[end] != char:
                end += 2 if char == '"' and raw[end] == "\\" else 1
            pos = end + 1
            continue
        if char in "[{":
            depth += 1
        elif char in "]}":
            if depth == 0:
                return pos
            depth -= 1
        elif char == "," and depth == 0:
            return pos
        pos += 1
    return pos


@dataclass
class TomlSource:
    """A parsed TOML file: its data, its path as shown to users, and key positions."""

    #: The file's path as shown to users.
    name: str
    #: The file's text.
    text: str
    #: The parsed tables.
    data: dict[str, Any]
    #: Each key path's (line, column).
    positions: dict[Loc, tuple[int, int]] = field(default_factory=dict)
    #: The file it was read from, if any (symlinks resolved).
    path: Path | None = None
    #: The folder of the path the file was read by (a symlink's own folder).
    folder: Path | None = None

    @classmethod
    def read(cls, path: str | Path) -> "TomlSource":
        """Read and parse ``path``; raise :class:`ProblemsError` for unreadable or invalid TOML."""
        name = display_path(path)
        try:
            text = read_bytes(path).decode("utf-8")
        except Refused as exc:
            raise ProblemsError([Problem(name, None, "", f"cannot read file: {exc}")]) from None
        except UnicodeDecodeError:
            raise ProblemsError([Problem(name, None, "", "file is not UTF-8 text")]) from None
        source = cls.parse(text, name)
        source.path = Path(path).resolve()
        source.folder = Path(path).absolute().parent
        return source

    @classmethod
    def parse(cls, text: str, name: str) -> "TomlSource":
        """Parse TOML ``text`` that came from ``name``."""
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ProblemsError([_decode_problem(name, text, exc)]) from None
        except RecursionError:
            raise ProblemsError([Problem(name, None, "", "invalid TOML: arrays or tables nested too deeply")]) from None
        except ValueError:  # an integer of more digits than Python converts (4300)
            raise ProblemsError([Problem(name, None, "", "invalid TOML: a number too long to read")]) from None
        return cls(name, text, data, index_positions(text))

    def position_of(self, loc: Sequence[str | int]) -> tuple[int, int] | None:
        """(line, column) of the longest prefix of ``loc`` that is written in the file."""
        loc = tuple(loc)
        for end in range(len(loc), 0, -1):
            found = self.positions.get(loc[:end])
            if found is not None:
                return found
        return None

    def line_of(self, loc: Sequence[str | int]) -> int | None:
        """The line of the longest prefix of ``loc`` that is written in the file."""
        found = self.position_of(loc)
        return None if found is None else found[0]

    def problem(self, loc: Sequence[str | int], message: str, *, row: int | None = None) -> Problem:
        """A problem at field path ``loc`` of this file.

        ``row`` (1-based) points into a multi-line string value at ``loc``: the
        problem is then on that row's line.
        """
        found = self.position_of(loc)
        if found is None:
            return Problem(self.name, None, format_loc(loc), message)
        line, column = found
        if row is not None and self.positions.get(tuple(loc)) == found:
            line, column = self._row_position(line, loc, row)
        return Problem(self.name, line, format_loc(loc), message, column)

    def _row_position(self, line: int, loc: Sequence[str | int], row: int) -> tuple[int, int]:
        """Where row ``row`` of the (dedented, blank-trimmed) multi-line string at ``loc`` is."""
        text_lines = self.text.splitlines()
        starts_below = text_lines[line - 1].rstrip().endswith(('"""', "'''"))
        value: Any = self.data
        for part in loc:
            value = value[part]
        lines = str(value).splitlines()
        blank = next((i for i, text in enumerate(lines) if text.strip()), 0)
        number = line + (1 if starts_below else 0) + blank + row - 1
        written = text_lines[number - 1] if 0 < number <= len(text_lines) else ""
        return number, len(written) - len(written.lstrip()) + 1


def format_loc(loc: Sequence[str | int]) -> str:
    """``("reactions", 2, "chance")`` -> ``reactions.2.chance``."""
    return ".".join(str(part) for part in loc)


def _decode_problem(name: str, text: str, exc: tomllib.TOMLDecodeError) -> Problem:
    message = str(exc)
    line = column = None
    m = _DECODE_POSITION.search(message)
    if m:
        line, column = int(m.group(1)), int(m.group(2))
        message = message[: m.start()]
    elif _DECODE_END.search(message):
        line = max(1, text.count("\n") + (0 if text.endswith("\n") else 1))
        message = _DECODE_END.sub("", message)
    return Problem(name, line, "", f"invalid TOML: {message}", column)
