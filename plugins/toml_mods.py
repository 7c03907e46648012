"""Built-in plugin: mods are TOML files, and sandmod ships a folder of them."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from sandmod.api import TomlSource, hookimpl


def bundled_mods_dir() -> Path:
    """The folder of mods that ships with sandmod."""
    return Path(str(resources.files("sandmod.mods")))


@hookimpl
def register_mod_loaders(register):
    register(".toml", TomlSource.read)


@hookimpl
def register_mod_dirs(register):
    register(bundled_mods_dir())
