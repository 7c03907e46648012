"""Passes over the world after the kernel's step, compiled apart from it (so its cache is untouched).

- :mod:`.behaviours`: the plugins' per-cell behaviours (one generated, cached numba function per
  set of behaviours a ruleset uses), walked serially in a fixed order; :mod:`.helpers`, what they
  read and change cells with.

Nothing here is imported by a world whose ruleset uses no behaviour.
"""
