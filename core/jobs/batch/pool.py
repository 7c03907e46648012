"""Many runs at once: a pool of local worker processes, or a Dask cluster.

A stopping signal (Ctrl-C, SIGTERM, SIGHUP) is noted while runs are going, and ends them: the
pool's workers ignore Ctrl-C, so that the batch alone sees it and terminates them; what they were
writing is a ``.part`` folder the batch then clears.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from typing import Any, Iterator

from ...errors import Problem, ProblemsError
from .run import Run, execute


def _worker_start() -> None:
    """A worker process: one numba thread (the workers are the parallelism), Ctrl-C left to the
    batch, SIGTERM ending it, and on Linux gone with the batch (a batch killed outright must not leave workers
    writing into its folder)."""
    import signal

    if "numba" not in sys.modules:  # a fresh interpreter; a forked one keeps numba's settings as they are
        os.environ["NUMBA_NUM_THREADS"] = "1"
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for name in ("SIGTERM", "SIGHUP"):  # as a process is by default, whatever the batch had set when it forked
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)
    if sys.platform.startswith("linux"):
        import ctypes

        PR_SET_PDEATHSIG = 1
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)


class Interrupted(Exception):
    """The batch was asked to stop (Ctrl-C, SIGTERM, SIGHUP); ``status`` is the exit status a shell
    would report for the signal."""

    def __init__(self, signum: int) -> None:
        super().__init__(f"interrupted by signal {signum}")
        self.status = 128 + signum


def run_all(runs: list[Run], executor: str, jobs: int, scheduler: str | None) -> Iterator[dict[str, Any]]:
    """Each run's row as it finishes, on ``jobs`` worker processes or a Dask cluster. Raises
    Interrupted once a stopping signal arrives, with the workers ended."""
    if not runs:
        return
    with _signals_noted() as noted:
        if executor == "dask":
            yield from _on_dask(runs, jobs, scheduler, noted)
        else:
            yield from _on_pool(runs, jobs, noted)


@contextlib.contextmanager
def _signals_noted():
    """Ctrl-C, SIGTERM and SIGHUP noted in a list rather than raised wherever the main thread is
    (inside a lock of concurrent.futures, a raised KeyboardInterrupt can leave the pool hung)."""
    noted: list[int] = []
    names = [n for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n)]
    if threading.current_thread() is not threading.main_thread():
        yield noted
        return
    previous = {name: signal.signal(getattr(signal, name), lambda signum, frame: noted.append(signum)) for name in names}
    try:
        yield noted
    finally:
        for name, handler in previous.items():
            signal.signal(getattr(signal, name), handler)


def _on_pool(runs: list[Run], jobs: int, noted: list[int]) -> Iterator[dict[str, Any]]:
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    # Linux: forked workers start at once with what this process loaded (it has started no threads:
    # it never steps a world); elsewhere each starts a fresh interpreter.
    context = multiprocessing.get_context("fork" if sys.platform.startswith("linux") else "spawn")
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=context, initializer=_worker_start)
    pending = {pool.submit(execute, run) for run in runs}
    try:
        while pending:
            if noted:
                raise Interrupted(noted[0])
            finished, pending = wait(pending, timeout=0.1, return_when=FIRST_COMPLETED)
            for future in finished:
                try:
                    row = future.result()
                except BrokenProcessPool:
                    if noted:  # a signal to the whole process group ended the workers first
                        raise Interrupted(noted[0]) from None
                    raise ProblemsError([Problem("batch", None, "", "a worker process died (killed, or out of memory?): "
                                                 "the runs done are kept, and --resume goes on with the others")]) from None
                yield row
    except BaseException:
        pool.shutdown(wait=False, cancel_futures=True)
        children = multiprocessing.active_children()
        for child in children:
            child.terminate()
        for child in children:
            child.join(5)
            if child.is_alive():
                child.kill()
        raise
    pool.shutdown()


def _on_dask(runs: list[Run], jobs: int, scheduler: str | None, noted: list[int]) -> Iterator[dict[str, Any]]:
    try:
        from dask.distributed import LocalCluster, wait
    except ImportError:
        raise ProblemsError([Problem("batch", None, "", 'the dask executor needs dask: pip install "sandmod[dask]"')]) from None
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None, env={"NUMBA_NUM_THREADS": "1"})
    client = connect(cluster if cluster is not None else scheduler)
    futures = []
    try:
        client.run(_warm)  # each worker loads its kernels from the cache once
        futures = [client.submit(execute, run, pure=False, key=f"sandmod-run-{run.id}") for run in runs]
        pending = set(futures)
        while pending:
            if noted:
                raise Interrupted(noted[0])
            try:
                done = wait(pending, timeout=0.2, return_when="FIRST_COMPLETED").done
            except TimeoutError:
                continue
            pending -= done
            for future in done:
                yield future.result()
    finally:
        if futures:
            client.cancel(futures)
        client.close()
        if cluster is not None:
            cluster.close()


def connect(address):
    """A Dask client of ``address`` (a scheduler's, or a local cluster); ProblemsError, one line,
    when nothing answers there or the address is not one."""
    from dask.distributed import Client

    try:
        return Client(address, timeout="10s")
    except (OSError, ValueError, TypeError) as error:  # refused, timed out, a malformed address
        if not isinstance(address, str):
            raise
        raise ProblemsError([Problem("--scheduler", None, "", f"no Dask scheduler answers at {address!r} ({type(error).__name__}: {error})")]) from None


def _warm() -> None:
    from ..warmup import compile_kernels

    compile_kernels()
