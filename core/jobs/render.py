"""Run a world and record it: Python owns the frame loop, the kernel does the frames."""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple, Sequence

import numpy as np

from ..formats.limits import MemoryBudget
from ..formats.recording import RecorderSpec, VideoSettings, atomic_folder, atomic_path, write_png, writing
from ..world.world import World, enlarge


class Crop(NamedTuple):
    """A region of the world in cells: left column, top row, width, height."""

    x: int
    y: int
    width: int
    height: int

    def fits(self, width: int, height: int) -> bool:
        """Does the region lie inside a ``width`` x ``height`` world?"""
        return self.x >= 0 and self.y >= 0 and self.width >= 1 and self.height >= 1 and (
            self.x + self.width <= width and self.y + self.height <= height
        )


@dataclass(frozen=True)
class Framing:
    """Which cells an image shows and how large: a crop (all cells if None), then ``scale`` pixels a cell."""

    scale: int = 1
    crop: Crop | None = None

    def size(self, world: World) -> tuple[int, int]:
        """The image's width and height in pixels."""
        width, height = (world.width, world.height) if self.crop is None else (self.crop.width, self.crop.height)
        return width * self.scale, height * self.scale

    def image(self, world: World) -> np.ndarray:
        """The world's current frame as colour indices, cropped and scaled."""
        frame = world.image()
        if self.crop is not None:
            x, y, w, h = self.crop
            frame = frame[y : y + h, x : x + w]
        return enlarge(frame, self.scale)


def side_problem(recorder: RecorderSpec, world: World, framing: Framing) -> str | None:
    """Why the format cannot hold images of this framing, or None."""
    width, height = framing.size(world)
    if recorder.max_side is not None and max(width, height) > recorder.max_side:
        return f"{recorder.name} images are at most {recorder.max_side} pixels a side; these would be {width}x{height}"
    return None


#: Bytes a pixel of the image being drawn: its colour indices, and the RGB copies a format makes of an
#: image of more than 256 colours (a GIF quantizes it). Measured with every bundled mod loaded (119
#: elements, 1,785 colours): ``sandmod bench --memory 8192`` peaked at 2.43 GB against 2.30 estimated
#: with 4 bytes a pixel, the 16384² render at 8.95 GB against 7.5.
DRAWN_BYTES_PER_PIXEL = 12


def kept_bytes(recorder: RecorderSpec, world: World, framing: Framing, frames: int, every: int) -> tuple[int, int]:
    """(images, bytes): what a recording keeps in memory until it closes, and the image being drawn."""
    width, height = framing.size(world)
    images = frames // every + 1
    return images, int(images * width * height * recorder.kept_bytes_per_pixel) + DRAWN_BYTES_PER_PIXEL * width * height


def render_problems(recorder: RecorderSpec, world: World, framing: Framing, frames: int, every: int, memory: MemoryBudget) -> list[str]:
    """Why a render cannot be done, found before it starts: images too large for the format, or
    more memory than ``memory`` has left for the images the format keeps until it closes."""
    too_wide = side_problem(recorder, world, framing)
    if too_wide:
        return [too_wide + " (a smaller --scale or --crop, or another format)"]
    width, height = framing.size(world)
    images, kept = kept_bytes(recorder, world, framing, frames, every)
    over = memory.take(kept, f"{recorder.name} keeping {images} images of {width}x{height}")
    return [] if over is None else [over + "; or fewer --frames, a larger --every, a smaller --scale, a streamed format (gif, png-frames)"]


@dataclass(frozen=True)
class RenderResult:
    """What a render wrote."""

    path: Path
    frames: int  # frames simulated
    images: int  # images written
    distinct: int  # of them, those unlike the image before (a GIF stores only these)
    width: int  # image size in pixels
    height: int
    still: Path | None = None


def render(
    world: World,
    recorder: RecorderSpec,
    output: Path,
    *,
    frames: int,
    every: int = 1,
    framing: Framing = Framing(),
    fps: float = 25,
    loop: int = 0,
    still: Path | None = None,
    also: Sequence[tuple[Path, Callable[[World, Path], None]]] = (),
    progress: Callable[[int], None] | None = None,
) -> RenderResult:
    """Simulate ``frames`` frames and record an image every ``every`` frames (and the first).

    ``still`` is a PNG of the last frame; ``also`` pairs more outputs with what
    writes them from the final world (a snapshot). Everything is written
    atomically and together: on any failure or interruption none of the
    outputs is touched. A failure to write one raises WriteError naming it.
    """
    width, height = framing.size(world)
    settings = VideoSettings(width, height, world.ruleset.colours, fps, loop)
    with contextlib.ExitStack() as stack:
        place = atomic_folder(output, recorder.folder) if recorder.folder else atomic_path(output)
        tmp = stack.enter_context(place)
        still_tmp = stack.enter_context(atomic_path(still)) if still is not None else None
        extra_tmps = [stack.enter_context(atomic_path(path)) for path, _ in also]
        with writing(output):
            out = recorder.open(tmp, settings)
            image = framing.image(world)
            out.add_frame(image)
            images = distinct = 1
            for done in range(1, frames + 1):
                world.step()
                if done % every == 0 or (done == frames and still_tmp is not None):
                    previous, image = image, framing.image(world)
                if done % every == 0:
                    out.add_frame(image)
                    images += 1
                    distinct += not np.array_equal(image, previous)
                if progress is not None:
                    progress(1)
            out.close()
        if still_tmp is not None:
            with writing(still):
                write_png(still_tmp, image, settings.colours)
        for (path, write), path_tmp in zip(also, extra_tmps):
            with writing(path):
                write(world, path_tmp)
    return RenderResult(Path(output), frames, images, distinct, width, height, still)
