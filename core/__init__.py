"""sandmod: a falling-sand engine in which every element is data.

Its parts follow the data, each package importing only those before it
(docs/architecture.md has the map):

- :mod:`sandmod.formats`: the files (TOML, the pydantic models of mods and worlds, pictures);
- :mod:`sandmod.rules`: mods found, ordered and compiled into numpy tables;
- :mod:`sandmod.engine`: the numba kernel and its phases, which imports nothing above it;
- :mod:`sandmod.world`: the world's state, stepping and painting, built from a world file;
- :mod:`sandmod.jobs`: what the commands run (render, validate, tests, bench);
- :mod:`sandmod.hooks`, :mod:`sandmod.registry`: the plugin hooks, beside them.

The public API is what this package gives (plugin authors: :mod:`sandmod.api`)::

    import sandmod

    loaded = sandmod.load_world("examples/hourglass.toml")   # mods found as the CLI finds them
    world = loaded.world
    world.paint_shape(shape="circle", element="water", x=50, y=20, radius=6)
    world.run(100)
    world.counts()                 # {'base:empty': 8968, 'base:stone': 794, 'sand:sand': 1503, 'water:water': 1135}
    world.temperature()            # degrees Celsius, (height, width)
    world.image()                  # colour indices; world.rgb() for colours
    world.save_snapshot("hourglass.npz")

Importing ``sandmod`` imports none of the modules (each name loads on first
use), and nothing but the kernel imports numba. Everything else is private.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_PUBLIC = {
    "load_world": "world.loading",
    "load_ruleset": "world.loading",
    "LoadedWorld": "world.loading",
    "World": "world.world",
    "Ruleset": "rules.compiler",
    "Problem": "errors",
    "ProblemsError": "errors",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str):
    if name in _PUBLIC:
        return getattr(importlib.import_module(f"{__name__}.{_PUBLIC[name]}"), name)
    raise AttributeError(f"module 'sandmod' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
