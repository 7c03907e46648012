"""The rules: mods found, checked against each other and compiled into the engine's tables.

:mod:`.modset` finds and loads mods through the plugins' loaders and checks
their ``requires``; :mod:`.compiler` turns the elements into the numpy
tables the kernel reads (:class:`~.compiler.Ruleset`).
"""
