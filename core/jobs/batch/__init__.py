"""``sandmod batch``: the runs of a sweep (:mod:`sandmod.formats.sweepspec`), on a process pool or a
Dask cluster, each written whole into its own folder, and tables of what they measured.

A run is a world file, a seed, a number of frames and a value for each of the sweep's
parameters. Its id hashes these, the world file's path and text, every loaded mod's text and
sandmod's version, so a run already done is skipped by ``--resume``, and the same run on any
machine, executor or number of workers makes the same files bit for bit.

- :mod:`.plan`: the sweep read and checked, its runs planned;
- :mod:`.run`: one run, in a worker; :mod:`.metrics`: what it measures;
- :mod:`.pool`: many runs at once; :mod:`.folder`: the output folder, its lock and its runs done;
- :mod:`.tables` and :mod:`.sheet`: what a batch writes at the end.
"""

from .folder import OutputFolder
from .metrics import BUILT_IN, measure
from .plan import Sweep, read_sweep
from .pool import Interrupted, run_all
from .run import RUNS, Run, execute
from .sheet import contact_sheet
from .tables import write_tables

__all__ = ["BUILT_IN", "RUNS", "Interrupted", "OutputFolder", "Run", "Sweep", "contact_sheet", "execute", "measure", "read_sweep", "run_all", "write_tables"]
