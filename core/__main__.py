"""``python -m sandmod`` runs the command line."""

from sandmod.tools.entry import main

main()
