"""``sandmod play``: a window onto a session (:mod:`sandmod.jobs.session`), with pygame-ce.

:mod:`.window` runs the loop, :mod:`.view` draws (and knows what is stale), :mod:`.keys` says what
each key does, :mod:`.tools` turns the brush into timeline events, :mod:`.files` writes what play saves.
Importing the package costs nothing until :class:`Play` is used (the CLI reads :mod:`.keys` for its help).
"""

__all__ = ["Play", "benchmark"]


def __getattr__(name: str):
    if name in __all__:
        from . import window

        return getattr(window, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
