"""Work on the cells after the kernel's step, for what the kernel does not do itself, compiled apart
from it (the kernel's code and cache never change for it): neighbour-count rules (:mod:`.counts`),
and the plugins' per-cell behaviours (:mod:`.behaviours`: one generated, cached numba function per
set of behaviours a ruleset uses; :mod:`.helpers`, what they read and change cells with). A pass
runs only where the mods ask for it, and looks only at the tiles whose updated rows held an element
it concerns (:mod:`.visit`), and, for behaviours, at the chunks that held their cells."""
