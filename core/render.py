"""Run a world and record it: Python owns the frame loop, the kernel does the frames."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .recording import RecorderSpec, VideoSettings, atomic_path
from .world import World


@dataclass(frozen=True)
class RenderResult:
    """What a render wrote."""

    path: Path
    frames: int  # frames simulated
    images: int  # images written
    width: int  # image size in pixels
    height: int


def render(
    world: World,
    recorder: RecorderSpec,
    output: Path,
    *,
    frames: int,
    every: int = 1,
    scale: int = 1,
    fps: float = 25,
    progress: Callable[[int], None] | None = None,
) -> RenderResult:
    """Simulate ``frames`` frames, write an image every ``every`` frames (and the first), atomically."""
    width, height = world.width * scale, world.height * scale
    settings = VideoSettings(width, height, world.ruleset.palette, fps)
    images = 0
    with atomic_path(output) as tmp:
        out = recorder.open(tmp, settings)
        out.add_frame(world.image(scale))
        images += 1
        for done in range(1, frames + 1):
            world.step()
            if done % every == 0:
                out.add_frame(world.image(scale))
                images += 1
            if progress is not None:
                progress(1)
        out.close()
    return RenderResult(Path(output), frames, images, width, height)
