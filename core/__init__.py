"""sandmod: a falling-sand engine in which every element is data.

The engine's parts, each a small module:

- :mod:`sandmod.modspec`, :mod:`sandmod.worldspec`: the file formats (pydantic models);
- :mod:`sandmod.modset`: find, validate and order mods;
- :mod:`sandmod.compiler`: mods to numpy tables;
- :mod:`sandmod.world`, :mod:`sandmod.kernel`: the state and the numba step;
- :mod:`sandmod.hooks`, :mod:`sandmod.registry`: the plugin API;
- :mod:`sandmod.loading`, :mod:`sandmod.render`: files in, animations out.

Importing ``sandmod`` imports none of them, and nothing but the kernel imports numba.
"""

__version__ = "0.1.0"
