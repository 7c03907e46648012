"""The memory limit: what loading a world and rendering it will take, estimated before it is taken.

A shared world file may ask for a huge world, a huge picture or a render
that keeps a million frames. Each is estimated from the file before anything
is allocated and refused with one line when the total passes the limit
(``DEFAULT_MAX_MEMORY``; the CLI's ``--max-memory`` raises it). The per-cell
figures are measured peaks (``sandmod bench --memory``), rounded up.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

#: The limit unless the user gives another.
DEFAULT_MAX_MEMORY = 4 * 2**30
#: Bytes a world takes per cell at its peak: 15 of state, the rest while painting and stepping; a render
#: adds 4 a pixel for the frame it draws. Measured: 23.3 a cell in all, rendering 16384x16384 at scale 1.
WORLD_BYTES_PER_CELL = 24
#: Bytes a picture takes per pixel while its colours are matched to the legend (measured: 62).
PICTURE_BYTES_PER_PIXEL = 72
#: What the interpreter, numpy, numba and the kernel take before any world (compiling it, on a first run,
#: takes 370 MB at its peak).
BASELINE_BYTES = 512 * 2**20

_SIZE = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*([kmgt]?)i?b?\s*$", re.IGNORECASE)
_UNITS = {"": 1, "k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}


def parse_size(text: str) -> int:
    """'4G', '512M', '1.5GB', '100000000' as bytes; ValueError if it is none of these."""
    found = _SIZE.match(text)
    if not found:
        raise ValueError(f"{text!r} is not a size like 4G or 512M")
    return int(float(found.group(1)) * _UNITS[found.group(2).lower()])


def size_text(nbytes: int) -> str:
    """A size for people: '3.2 GB', '640 MB'."""
    for unit, scale in (("TB", 2**40), ("GB", 2**30), ("MB", 2**20)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{max(nbytes, 0) / 2**10:.3g} kB"


@dataclass
class MemoryBudget:
    """Bytes allowed (None: no limit) and bytes promised so far."""

    limit: int | None = DEFAULT_MAX_MEMORY
    used: int = BASELINE_BYTES

    def take(self, nbytes: int, what: str) -> str | None:
        """Promise ``nbytes`` for ``what``; a message saying what it would take if that passes the limit."""
        if self.limit is not None and self.used + nbytes > self.limit:
            return (
                f"{what} would take about {size_text(nbytes)} of memory, {size_text(self.used + nbytes)} in all: "
                f"more than the limit of {size_text(self.limit)} (raise it with --max-memory)"
            )
        self.used += nbytes
        return None

    def left(self) -> int | None:
        """Bytes still free under the limit (None: no limit)."""
        return None if self.limit is None else max(self.limit - self.used, 0)
