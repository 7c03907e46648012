"""sandmod: a falling-sand engine in which every element is data.

The engine's parts, each a small module:

- :mod:`sandmod.formats.modspec`, :mod:`sandmod.formats.worldspec`: the file formats (pydantic models);
- :mod:`sandmod.rules.modset`: find, validate and order mods;
- :mod:`sandmod.rules.compiler`: mods to numpy tables;
- :mod:`sandmod.world.world`, :mod:`sandmod.engine.kernel`: the state and the numba step;
- :mod:`sandmod.hooks`, :mod:`sandmod.registry`: the plugin API;
- :mod:`sandmod.world.loading`, :mod:`sandmod.jobs.render`: files in, animations out.

The public API is what this package gives (plugin authors: :mod:`sandmod.api`)::

    import sandmod

    loaded = sandmod.load_world("examples/hourglass.toml")   # mods found as the CLI finds them
    world = loaded.world
    world.paint_shape(shape="circle", element="water", x=50, y=20, radius=6)
    world.run(100)
    world.counts()                 # {'sand:sand': 2400, 'water:water': 113, ...}
    world.temperature()            # degrees Celsius, (height, width)
    world.image()                  # palette indices; world.rgb() for colours
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
