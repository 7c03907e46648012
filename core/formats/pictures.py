"""Levels drawn as pictures: each pixel's colour picks an element through a legend."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ..errors import display_path
from .userfiles import NO_SUCH_FILE, Refused, open_regular

#: Pixels less opaque than this are transparent: they leave their cells alone.
OPAQUE = 128
#: Unknown colours named in one error, at most.
SHOWN_UNKNOWN = 5


class PictureError(ValueError):
    """The picture cannot be read, or holds colours the legend does not map."""


def hex_rgb(colour: str) -> tuple[int, int, int]:
    """'#rrggbb' as (r, g, b)."""
    return int(colour[1:3], 16), int(colour[3:5], 16), int(colour[5:7], 16)


def read_rgba(path: Path, max_pixels: int | None = None) -> np.ndarray:
    """The picture at ``path`` as a (height, width, 4) uint8 array; PictureError if it cannot be read
    or has more than ``max_pixels`` pixels (checked from its header, before it is decoded)."""
    from PIL import Image, UnidentifiedImageError

    shown = display_path(path)
    too_large = f"{shown} has more pixels than the memory limit allows (raise it with --max-memory)"
    try:
        with warnings.catch_warnings(), open_regular(path) as file:
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # the memory limit decides
            with Image.open(file) as image:
                if max_pixels is not None and image.width * image.height > max_pixels:
                    raise PictureError(too_large)
                return np.asarray(image.convert("RGBA"))
    except Refused as exc:
        raise PictureError(f"no such image: {shown}" if str(exc) == NO_SUCH_FILE else f"cannot read image {shown}: {exc}") from None
    except Image.DecompressionBombError:
        raise PictureError(too_large) from None
    except UnidentifiedImageError:
        raise PictureError(f"not an image pillow can read: {shown}") from None
    except (OSError, ValueError, SyntaxError) as exc:  # pillow's plugins raise any of these on bad data
        raise PictureError(f"cannot read image {shown}: {exc}") from None


def legend_indices(rgba: np.ndarray, colours: list[tuple[int, int, int]], *, nearest: bool) -> np.ndarray:
    """For each pixel, the number of its legend colour (-1 where transparent).

    Exact matching raises PictureError naming the colours that are not in the
    legend (how many pixels, and the first one's place); nearest matching picks
    the closest legend colour by distance in RGB.
    """
    height, width = rgba.shape[:2]
    packed = (rgba[..., 0].astype(np.int64) << 16) | (rgba[..., 1].astype(np.int64) << 8) | rgba[..., 2]
    opaque = rgba[..., 3] >= OPAQUE
    found, first, inverse = np.unique(np.where(opaque, packed, -1), return_index=True, return_inverse=True)
    inverse = inverse.reshape(height, width)
    legend = np.array([(r << 16) | (g << 8) | b for r, g, b in colours], np.int64)
    if nearest:
        rgb = np.stack([(found >> 16) & 255, (found >> 8) & 255, found & 255], axis=1)
        wanted = np.array(colours, np.int64)
        distance = ((rgb[:, None, :] - wanted[None, :, :]) ** 2).sum(axis=2)
        pick = distance.argmin(axis=1)
    else:
        match = found[:, None] == legend[None, :]
        pick = np.where(match.any(axis=1), match.argmax(axis=1), -2)
        missing = [i for i in range(len(found)) if pick[i] == -2 and found[i] >= 0]
        if missing:
            raise PictureError(_unknown_colours(found, first, inverse, missing, width))
    pick = np.where(found < 0, -1, pick)
    return pick[inverse]


def _unknown_colours(found: np.ndarray, first: np.ndarray, inverse: np.ndarray, missing: list[int], width: int) -> str:
    """The commonest unknown colours (then in reading order), each with its count and first pixel."""
    counts = np.bincount(inverse.ravel(), minlength=len(found))
    missing.sort(key=lambda i: (-counts[i], first[i]))
    described = []
    for i in missing[:SHOWN_UNKNOWN]:
        y, x = divmod(int(first[i]), width)
        described.append(f"#{int(found[i]):06x} ({counts[i]} pixels, first at x={x}, y={y})")
    more = f" and {len(missing) - SHOWN_UNKNOWN} more" if len(missing) > SHOWN_UNKNOWN else ""
    return f"colours not in the legend: {', '.join(described)}{more} (or use match = \"nearest\")"


def fit(indices: np.ndarray, width: int, height: int) -> np.ndarray:
    """``indices`` scaled to ``width`` x ``height`` by nearest neighbour (each cell takes the pixel under its centre)."""
    rows = (np.arange(height) * 2 + 1) * indices.shape[0] // (2 * height)
    columns = (np.arange(width) * 2 + 1) * indices.shape[1] // (2 * width)
    return indices[rows[:, None], columns[None, :]]
