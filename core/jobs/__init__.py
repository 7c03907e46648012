"""The jobs the commands run, on top of the world: render an animation, check a mod folder,
run mods' tests, benchmark, warm the kernel cache, write new mods and worlds.

A new output format is not added here but as a recorder plugin (see
:mod:`sandmod.plugins` and :mod:`sandmod.formats.recording`); :mod:`.render`
drives whichever recorder the world file names.
"""
