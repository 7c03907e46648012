"""``python -m sandmod`` runs the command line."""

from sandmod.tools.cli import main

main()
