"""The ``sandmod`` console script's entry point, apart from the command line so that a signal
arriving while it loads (click, numpy, the commands) ends it as cleanly as one arriving later."""

from __future__ import annotations

import signal
import sys

EXIT_INTERRUPTED = 130  # 128 + SIGINT


def main() -> None:
    """Run the command line. SIGTERM and SIGHUP end it as Ctrl-C does: by an exception, so that
    every half-written output is removed on the way out; the exit status is 128 plus the signal's
    number, as a shell reports a process the signal killed. Ctrl-C while loading exits 130 quietly."""

    def leave(signum, frame):
        raise SystemExit(128 + signum)

    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name) and signal.getsignal(getattr(signal, name)) is signal.SIG_DFL:
            signal.signal(getattr(signal, name), leave)
    if _load_interrupted():
        sys.stderr.write("interrupted\n")
        sys.exit(EXIT_INTERRUPTED)
    from .cli import cli

    cli(prog_name="sandmod")


def _load_interrupted() -> bool:
    """Import the command line with Ctrl-C noted rather than raised: pydantic builds its validators
    as the file formats load, and a KeyboardInterrupt raised inside that is swallowed (printed as
    "Exception ignored") and leaves a broken validator behind, which then refuses good files."""
    noted: list[int] = []
    before = signal.signal(signal.SIGINT, lambda signum, frame: noted.append(signum))
    try:
        from . import cli  # noqa: F401
    finally:
        signal.signal(signal.SIGINT, before)
    return bool(noted)
