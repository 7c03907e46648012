"""The engine: one frame of the cellular automaton, compiled by numba.

The lowest layer: it imports nothing from sandmod outside this package, and
the kernel cache is named after this package's files alone. The cell layout
and flag bits (:mod:`.layout`), hashing for rolls (:mod:`.hashing`), the line
traversal (:mod:`.traversal`), the kernel and its phases (:mod:`.kernel`,
:mod:`.heat`, :mod:`.moves`, :mod:`.cells`, :mod:`.blasts`, :mod:`.paint`),
pixels from cells (:mod:`.pixels`), threads and the kernel cache.

A new movement archetype goes here: its code in :mod:`.layout`'s
``ARCHETYPES`` and a phase in :mod:`.moves`.
"""
