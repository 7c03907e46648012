"""The contact sheet: every run's last frame, a row per world and combination of parameters and a
column per seed, failed runs shown as such. Bounded: a tile is at most ``TILE`` pixels a side, a
frame larger than ``MAX_FRAME_PIXELS`` is not decoded, and the sheet is at most ``MAX_SIDE`` pixels a
side (smaller tiles, then the first rows and a line saying how many more)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ...formats.recording import atomic_path
from .run import Run

TILE = 240
MIN_TILE = 48
MAX_SIDE = 16384
MAX_FRAME_PIXELS = 64 * 2**20
_LINE = 14  # pixels a line of text takes
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
    columns = max(len(members) for members in groups.values())
    label_width = min(60, max(len(label) for label in groups)) * 7 + 12
    tile = max(MIN_TILE, min(TILE, (MAX_SIDE - label_width) // columns - 8))
    cell = tile + 8 + _LINE
    shown = min(len(groups), (MAX_SIDE - 2 * _LINE) // cell)
    sheet = Image.new("RGB", (label_width + columns * (tile + 8), shown * cell + (2 * _LINE if shown < len(groups) else 0)), _BACKGROUND)
    draw = ImageDraw.Draw(sheet)
    for number, (label, members) in enumerate(list(groups.items())[:shown]):
        top = number * cell + 4
        draw.text((4, top + tile // 2), label[:60], fill=_TEXT)
        for column, run in enumerate(members):
            left = label_width + column * (tile + 8)
            _tile(sheet, draw, run, by_id[run.id], (left, top), tile)
            draw.text((left, top + tile + 2), f"seed {run.seed}", fill=_TEXT)
    if shown < len(groups):
        draw.text((4, shown * cell + 4), f"... and {len(groups) - shown} more combinations (see results.csv)", fill=_TEXT)
    path = out / "contact_sheet.png"
    with atomic_path(path) as temporary:
        sheet.save(temporary, "PNG")
    return path


def _label(run: Run) -> str:
    values = ", ".join(f"{k.split('.', 1)[1] if k.startswith('elements.') else k} = {v}" for k, v in run.parameters.items())
    return f"{run.world}" + (f": {values}" if values else "")


def _tile(sheet, draw, run: Run, row: dict[str, Any], corner: tuple[int, int], tile: int) -> None:
    """The run's last frame, scaled to fit ``tile``; a red tile saying why when there is none."""
    image, why = _frame(run, tile) if row.get("status") == "done" else (None, "failed")
    left, top = corner
    if image is None:
        draw.rectangle((left, top, left + tile - 1, top + tile - 1), fill=_FAILED)
        draw.line((left, top, left + tile - 1, top + tile - 1), fill=_TEXT)
        draw.line((left, top + tile - 1, left + tile - 1, top), fill=_TEXT)
        draw.text((left + 4, top + 4), why, fill=_TEXT)
        return
    sheet.paste(image, (left + (tile - image.width) // 2, top + (tile - image.height) // 2))


def _frame(run: Run, tile: int):
    """(the last frame fitted into ``tile`` pixels, None) or (None, why not)."""
    import warnings

    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # refused just below, never decoded
            with Image.open(run.folder / "last.png") as image:
                if image.width * image.height > MAX_FRAME_PIXELS:
                    return None, "too large"
                image = image.convert("RGB")
    except Exception:  # a frame that does not read is shown as such; the table has the run
        return None, "unreadable"
    longest = max(image.width, image.height)
    if longest <= tile:  # a whole number of pixels a cell, or the cells would be uneven
        scale = tile // longest
        return image.resize((image.width * scale, image.height * scale), Image.NEAREST), None
    size = (max(1, image.width * tile // longest), max(1, image.height * tile // longest))
    return image.resize(size, Image.BOX), None
