"""An example sandmod plugin: behaviours for what data cannot say, and the mod whose elements use them.

- ``garden:sprout``: a seed resting on soil turns into a growing tip.
- ``garden:grow``: a tip climbs upward a cell at a time, leaving stem behind it, now and
  then leaning left or right, forking into two tips, or ending in a flower.
"""

from __future__ import annotations

from pathlib import Path

from sandmod.api import hookimpl

from .behaviours import grow, sprout


@hookimpl
def register_behaviours(register):
    register("grow", grow)
    register("sprout", sprout)


@hookimpl
def register_mod_dirs(register):
    register(Path(__file__).parent / "mods")
