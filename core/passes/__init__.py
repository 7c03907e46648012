"""Work on the cells after the kernel's step, for what the kernel does not do itself: neighbour-count
rules (:mod:`.counts`). A pass runs only where the mods ask for it, and looks only at the tiles whose
updated rows held an element it concerns (:mod:`.visit`); the kernel's code never changes for it."""
