"""The contact sheet: every run's last frame, a row per world and combination of parameters and a
column per seed, failed runs shown as such. Bounded: a tile is at most ``TILE`` pixels a side, a
frame larger than ``MAX_FRAME_PIXELS`` is never decoded, and the sheet is at most ``MAX_SIDE``
pixels a side (smaller tiles, then the first rows and a line saying how many more)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

from ...formats.recording import atomic_path
from .run import Run

TILE = 240
MIN_TILE = 48
MAX_SIDE = 16384
MAX_FRAME_PIXELS = 64 * 2**20
GAP = 8  # pixels between tiles
LINE = 14  # pixels a line of text takes
_BACKGROUND, _TEXT, _FAILED = (24, 24, 28), (220, 220, 220), (120, 32, 32)


def contact_sheet(rows: list[dict[str, Any]], runs: list[Run], out: Path) -> Path | None:
    """Write OUT/contact_sheet.png; None when no run has a row."""
    from PIL import Image, ImageDraw

    by_id = {row["id"]: row for row in rows if row}
    groups: dict[str, list[Run]] = {}
    for run in runs:
        if run.id in by_id:
            groups.setdefault(_label(run), []).append(run)
    if not groups:
        return None
    sizes = [size for run in runs if run.id in by_id and (size := _size(run)) is not None]
    columns = max(len(members) for members in groups.values())
    draw = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    label_width = int(max(draw.textlength(label) for label in groups)) + 2 * GAP
    width, height = _tile_size(sizes, (MAX_SIDE - label_width) // columns - GAP)
    cell = height + GAP + LINE
    shown = min(len(groups), max(1, (MAX_SIDE - 2 * LINE) // cell))
    more = 2 * LINE if shown < len(groups) else 0
    sheet = Image.new("RGB", (label_width + columns * (width + GAP), shown * cell + GAP + more), _BACKGROUND)
    draw = ImageDraw.Draw(sheet)
    for number, (label, members) in enumerate(list(groups.items())[:shown]):
        top = number * cell + GAP
        draw.text((GAP, top + height // 2 - LINE // 2), label, fill=_TEXT)
        for column, run in enumerate(members):
            left = label_width + column * (width + GAP)
            _tile(sheet, draw, run, by_id[run.id], (left, top, width, height))
            draw.text((left, top + height + 1), f"seed {run.seed}", fill=_TEXT)
    if more:
        draw.text((GAP, shown * cell + GAP), f"... and {len(groups) - shown} more combinations (see results.csv)", fill=_TEXT)
    path = out / "contact_sheet.png"
    with atomic_path(path) as temporary:
        sheet.save(temporary, "PNG")
    return path


def _label(run: Run) -> str:
    values = ", ".join(f"{k.split('.', 1)[1] if k.startswith('elements.') else k} = {v}" for k, v in run.parameters.items())
    return (f"{run.world}: {values}" if values else run.world)[:80]


def _tile_size(sizes: list[tuple[int, int]], room: int) -> tuple[int, int]:
    """A tile's width and height: the largest frame fitted into TILE (and ``room``) pixels, a whole
    number of pixels a cell when it fits, so that no cell is drawn wider than another."""
    side = max(MIN_TILE, min(TILE, room))
    if not sizes:
        return side, side
    width, height = max(w for w, _ in sizes), max(h for _, h in sizes)
    longest = max(width, height)
    if longest <= side:
        scale = side // longest
        return width * scale, height * scale
    return max(1, width * side // longest), max(1, height * side // longest)


def _size(run: Run) -> tuple[int, int] | None:
    """The size of a run's last frame, read from its header, if it is one to show."""
    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # never decoded if too large
            with Image.open(run.folder / "last.png") as image:
                return image.size if image.width * image.height <= MAX_FRAME_PIXELS else None
    except Exception:  # a frame that does not read is shown as such
        return None


def _tile(sheet, draw, run: Run, row: dict[str, Any], box: tuple[int, int, int, int]) -> None:
    """The run's last frame, scaled to fit the box; a red tile saying why when there is none."""
    left, top, width, height = box
    image, why = _frame(run, width, height) if row.get("status") == "done" else (None, "failed")
    if image is None:
        draw.rectangle((left, top, left + width - 1, top + height - 1), fill=_FAILED)
        draw.line((left, top, left + width - 1, top + height - 1), fill=_TEXT)
        draw.line((left, top + height - 1, left + width - 1, top), fill=_TEXT)
        draw.text((left + 4, top + 4), why, fill=_TEXT)
        return
    sheet.paste(image, (left + (width - image.width) // 2, top + (height - image.height) // 2))


def _frame(run: Run, width: int, height: int):
    """(the last frame fitted into width x height pixels, None) or (None, why not)."""
    from PIL import Image

    if _size(run) is None:
        return None, "unreadable or too large"
    try:
        with Image.open(run.folder / "last.png") as image:
            image = image.convert("RGB")
    except Exception:  # a frame that does not read is shown as such; the table has the run
        return None, "unreadable"
    if image.width <= width and image.height <= height:  # a whole number of pixels a cell
        scale = min(width // image.width, height // image.height)
        return image.resize((image.width * scale, image.height * scale), Image.NEAREST), None
    scale = min(width / image.width, height / image.height)
    return image.resize((max(1, int(image.width * scale)), max(1, int(image.height * scale))), Image.BOX), None
