"""User-facing problems: one line each, ``file:line:column: field.path: message``.

Every mistake in a mod or world file becomes a :class:`Problem`. Loaders
collect as many as they can find and raise them together in a
:class:`ProblemsError`; the CLI prints one line per problem and exits 2.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

#: Characters a terminal may act on (C0 and C1 controls, DEL, bidirectional overrides): shown escaped.
_UNPRINTABLE = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u200e\u200f\u202a-\u202e\u2066-\u2069]")


@dataclass(frozen=True, order=True)
class Problem:
    """One mistake in a user's file."""

    #: The file, as the user would type its path.
    file: str
    #: Its line (1-based), or None where no line is known.
    line: int | None
    #: The field's path within the file (``elements.sand.density``), or empty.
    path: str
    #: What is wrong.
    message: str
    #: The column (1-based), where known.
    column: int | None = None

    def __str__(self) -> str:
        where = self.file if self.line is None else f"{self.file}:{self.line}"
        if self.line is not None and self.column is not None:
            where += f":{self.column}"
        line = f"{where}: {self.path}: {self.message}" if self.path else f"{where}: {self.message}"
        return printable(line)


class ProblemsError(Exception):
    """Raised with every problem found in the user's input."""

    #: Each problem once, in the order found.
    problems: list[Problem]

    def __init__(self, problems: Iterable[Problem]):
        self.problems = list(dict.fromkeys(problems))  # each once, in the order found
        super().__init__("\n".join(str(p) for p in self.problems))


def display_path(path: str | Path) -> str:
    """A path as the user would type it: relative to the working directory when inside it."""
    p = Path(path)
    try:
        return str(p.resolve().relative_to(Path.cwd().resolve()))
    except (ValueError, OSError, RuntimeError):  # RuntimeError: a symlink loop
        return str(p)


def printable(text: str) -> str:
    """``text`` with every character a terminal would act on written as an escape (``\\x1b``), so
    that a file's contents shown in a message cannot move the cursor, retitle the window or hide text."""
    return _UNPRINTABLE.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), text.replace("\n", " "))
