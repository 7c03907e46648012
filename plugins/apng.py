"""Built-in plugin: animated PNG (APNG), lossless: indexed with one shared palette when the whole
animation holds at most 256 colours, else RGB."""

from __future__ import annotations

from typing import Callable, Iterator

from sandmod.api import RecorderSpec, SavedAtClose, fit_palette, hookimpl


class ApngRecorder(SavedAtClose):
    """Frames (their colour indices, kept until the end) as one animated PNG."""

    def save(self, first, rest: list) -> None:
        from PIL import Image

        palette = fit_palette([first, *rest], self.settings.colours)
        image = palette.image if palette.exact else lambda frame: Image.fromarray(self.settings.rgb(frame), mode="RGB")
        image(first).save(
            self.path,
            format="PNG",
            save_all=True,
            append_images=Images(rest, image),
            duration=self.settings.frame_ms,
            loop=self.settings.loop,  # APNG counts plays; 0 = forever
            default_image=False,
            compress_level=3,  # as small as 6 on these images, and faster
        )


class Images:
    """Frames as pillow images, each made as it is reached: pillow goes through them twice and keeps
    its own copy of each, so that holding ours too would take the memory twice."""

    def __init__(self, frames: list, image: Callable):
        self._frames, self._image = frames, image

    def __iter__(self) -> Iterator:
        return (self._image(frame) for frame in self._frames)


@hookimpl
def register_recorders(register):
    # Until it closes: each frame's colour indices (2 bytes a pixel), then pillow's copy of its image (1 indexed,
    # 4 RGB): 3.8 bytes a pixel measured in 256 colours or fewer, 6.9 in more.
    register(
        RecorderSpec(
            "apng", (".apng", ".png"), ApngRecorder, "Animated PNG: lossless, indexed up to 256 colours, else RGB; any delay.",
            kept_bytes_per_pixel=7,
        )
    )
