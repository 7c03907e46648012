"""The world: a grid of cells stepped by the engine, and everything that builds one.

:class:`~.world.World` (state, stepping, painting, images),
:mod:`.scene` (a world file's shapes, pictures and timeline made into a
world), :mod:`.shapes` (masks), :mod:`.loading` (a world file or a mod
folder to a world, finding mods as the CLI does), :mod:`.snapshots`.
"""
