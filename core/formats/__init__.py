"""The files: what mods, worlds and pictures may say, and how they are read and written.

TOML with line numbers (:mod:`.tomlsource`), the pydantic models of mod and
world files (:mod:`.modspec`, :mod:`.worldspec`) and their one-line problems
(:mod:`.validation`), pictures, the limits on what a stranger's file may ask
for (:mod:`.limits`, :mod:`.userfiles`), and the interface output formats
implement (:mod:`.recording`). Above the engine, below everything else.

A new world-file field goes in :mod:`.worldspec` (its model), then where the
world is built (:mod:`sandmod.world.scene`).
"""
