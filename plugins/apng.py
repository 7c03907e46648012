"""Built-in plugin: animated PNG (APNG), lossless, with the shared palette."""

from __future__ import annotations

from sandmod.api import RecorderSpec, SavedAtClose, hookimpl


class ApngRecorder(SavedAtClose):
    """Palette frames as one indexed animated PNG."""

    def save(self, first, rest: list) -> None:
        first.save(
            self.path,
            format="PNG",
            save_all=True,
            append_images=rest,
            duration=self.settings.frame_ms,
            loop=self.settings.loop,  # APNG counts plays; 0 = forever
            default_image=False,
            compress_level=3,  # as small as 6 on these images, and faster
        )


@hookimpl
def register_recorders(register):
    register(
        RecorderSpec(
            "apng", (".apng", ".png"), ApngRecorder, "Animated PNG: lossless, the shared palette, any delay.", kept_bytes_per_pixel=2
        )
    )
