"""Count the machine instructions the kernel runs a frame: a measure that does not drift.

A shared machine's speed drifts by up to 2x within minutes, so timings can
only tell kernels apart by 6% or more (see docs/performance.md). The
instructions a stretch of frames takes are exact instead: the same kernel
on the same frames counts the same to the instruction, so a change of 1%
shows as 1%. They are not time (a spilled register or a mispredicted branch
costs more than an add), so confirm a gain with ``tools/dev/bench.py against``::

    python tools/dev/instructions.py --scene halves --start 200 --frames 20
    python tools/dev/instructions.py --scene halves --start 200 --against /tmp/old_kernel.py

Each kernel runs one thread under valgrind's callgrind, which counts only
the frames from ``--start`` (stepped before counting) on; branches are
counted too, and mispredictions by callgrind's simple model of a predictor.
It needs valgrind and a C compiler with valgrind's headers (for the two
calls that switch counting on and off), on x86-64 Linux. The kernels are
compiled for this machine's CPU less what valgrind cannot run (AVX-512),
in a cache folder of their own: the first count of a version compiles it
(about half a minute, natively), later ones take seconds.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import click

from kernels import load_kernel, stepping_with  # numpy, not numba
from sandmod.jobs import benchmark

#: The two calls, through valgrind's client requests (no-ops when not under valgrind).
_SWITCH_C = """
#include <valgrind/callgrind.h>
void counting_on(void) { CALLGRIND_ZERO_STATS; CALLGRIND_START_INSTRUMENTATION; }
void counting_off(void) { CALLGRIND_STOP_INSTRUMENTATION; CALLGRIND_DUMP_STATS_AT("frames"); }
"""

#: What callgrind counts, in the order of its ``totals:`` line.
_EVENTS = ("Ir", "Bc", "Bcm", "Bi", "Bim")

#: This sandmod's kernel, counted as a file like any other, so that both counts run the same Python.
_THIS_KERNEL = str((Path(benchmark.__file__).parent.parent / "engine" / "kernel.py").resolve())

#: What valgrind cannot run, switched off in the code counted (the rest of AVX-512 and AMX need the first two).
_NOT_UNDER_VALGRIND = ("avx512f", "amx-tile", "avxvnni")


def _cpu() -> dict[str, str]:
    """The CPU the counted kernels are compiled for (and numba's cache is keyed by): this machine's, less
    what valgrind cannot run. The code counted is then the code timed: compiled for another CPU (a Haswell,
    say), the same kernel runs other instructions, and changes to it count differently."""
    from llvmlite import binding  # numba's compiler, without numba

    return {"NUMBA_CPU_NAME": binding.get_host_cpu_name(), "NUMBA_CPU_FEATURES": ",".join("-" + f for f in _NOT_UNDER_VALGRIND)}


@dataclass(frozen=True)
class Count:
    """One kernel's count over the frames: instructions and branches, and the state they ended in."""

    instructions: int
    branches: int
    mispredicted: int  # by callgrind's model
    digest: str  # of the cells' arrays after the last frame (not the chunks' marks: one kernel may wake finer than another)

    @classmethod
    def from_totals(cls, line: str, digest: str) -> Count:
        """From a callgrind dump's ``totals:`` line (events Ir Bc Bcm Bi Bim)."""
        values = dict(zip(_EVENTS, map(int, line.split()[1:])))
        return cls(values["Ir"], values["Bc"] + values["Bi"], values["Bcm"] + values["Bim"], digest)


class CannotCount(Exception):
    """Something this tool needs is missing (valgrind, a compiler, valgrind's headers)."""


def _cache_dir() -> Path:
    """Where the kernels compiled for counting are kept: one folder, this version's only."""
    from sandmod.engine.kernelcache import _versions, version_hash

    folder = _versions().parent / "numba-counting"
    if folder.is_dir():
        for other in folder.iterdir():
            if other.name != version_hash():
                shutil.rmtree(other, ignore_errors=True)
    return folder / version_hash()


def _switch_library(folder: Path) -> Path:
    """Compile the on and off switch into ``folder``."""
    compiler = shutil.which(os.environ.get("CC", "cc"))
    if compiler is None:
        raise CannotCount("no C compiler (cc) on PATH: one is needed to call valgrind")
    source = folder / "switch.c"
    source.write_text(_SWITCH_C, encoding="utf-8")
    library = folder / "switch.so"
    done = subprocess.run([compiler, "-O1", "-shared", "-fPIC", "-o", str(library), str(source)], capture_output=True, text=True)
    if done.returncode != 0:
        first = (done.stderr.strip().splitlines() or ["failed"])[0]
        raise CannotCount(f"cannot compile valgrind's switch ({first}): are valgrind's headers installed?")
    return library


def _environment() -> dict[str, str]:
    """The children's: compiled for :func:`_cpu` into :func:`_cache_dir`, and one hash seed for all."""
    return dict(os.environ, **_cpu(), NUMBA_CACHE_DIR=str(_cache_dir()), PYTHONHASHSEED="0")


def count(what: dict, kernel: str, folder: Path, env: dict[str, str]) -> Count:
    """Count ``what`` (the child's arguments) stepped by ``kernel`` (a kernel file), in ``env``."""
    if shutil.which("valgrind") is None:
        raise CannotCount("valgrind is not on PATH")
    # The job goes in a file, so that every child's command line is the same to the byte: where its
    # stack starts moves what Python does between frames, by a few thousand instructions.
    job = folder / "job.json"
    job.write_text(json.dumps(dict(what, kernel=kernel, switch=str(folder / "switch.so"))), encoding="utf-8")
    child = [sys.executable, __file__, "--child", str(job)]
    native = subprocess.run(child, env=env, capture_output=True, text=True)  # compiles, unless cached
    if native.returncode != 0:
        raise CannotCount(f"the frames did not run: {last_line(native.stderr)}")
    out = folder / "callgrind.out"
    counted = subprocess.run(
        ["valgrind", "--tool=callgrind", "--instr-atstart=no", "--cache-sim=no", "--branch-sim=yes", f"--callgrind-out-file={out}", *child],
        env=env,
        capture_output=True,
        text=True,
    )
    if counted.returncode != 0:
        raise CannotCount(f"valgrind failed: {last_line(counted.stderr)}")
    totals = [line for dump in folder.glob("callgrind.out*") for line in dump.read_text().splitlines() if line.startswith("totals:")]
    totals = [t for t in totals if t.split()[1:] != ["0"]]
    if len(totals) != 1:
        raise CannotCount(f"callgrind's dump has {len(totals)} counts of frames, not one")
    for dump in folder.glob("callgrind.out*"):
        dump.unlink()
    return Count.from_totals(totals[0], counted.stdout.strip().splitlines()[-1])


def last_line(text: str) -> str:
    """The last line of a child's stderr: what went wrong, for a one-line error."""
    lines = text.strip().splitlines()
    return lines[-1] if lines else "no message"


def _child(job: dict) -> None:
    """Under callgrind (or not, to compile): step to the start, count the frames, print the state's digest."""
    import ctypes
    import gc

    import numba

    from sandmod.world.loading import load_ruleset

    numba.set_num_threads(1)
    if job["world"]:
        bench, _ = benchmark.world_bench(Path(job["world"]))
    else:
        bench = benchmark.scene_bench(load_ruleset(None, []), job["scene"], job["size"])
    world = bench.make()
    with stepping_with(load_kernel(job["kernel"])):
        for _ in range(job["start"]):
            world.step()
        switch = ctypes.CDLL(job["switch"])
        gc.collect()
        gc.disable()  # a collection would land in some counts and not in others
        switch.counting_on()
        for _ in range(job["frames"]):
            world.step()
        switch.counting_off()
    print(benchmark.state_digest(world))


def _line(name: str, c: Count, frames: int, cells: int) -> str:
    return (
        f"{name}: {c.instructions / frames / 1e6:.2f} million instructions a frame ({c.instructions / frames / cells:.1f} a cell), "
        f"{c.branches / frames / 1e6:.2f} million branches, {c.mispredicted / frames / 1e3:.1f} thousand mispredicted"
    )


@click.command()
@click.option("--scene", default="halves", show_default=True, type=click.Choice(list(benchmark.SCENES)))
@click.option("--world", "world", type=click.Path(exists=True, dir_okay=False), help="A world file instead of a scene.")
@click.option("--size", default=512, show_default=True, type=click.IntRange(64, 2048), help="The scene's width and height.")
@click.option("--start", default=200, show_default=True, type=click.IntRange(0), help="Frames stepped before counting.")
@click.option("--frames", default=20, show_default=True, type=click.IntRange(1), help="Frames counted.")
@click.option("--against", type=click.Path(exists=True, dir_okay=False), metavar="KERNEL.py", help="Count another kernel file on the same frames.")
@click.option("--child", hidden=True)
def main(scene, world, size, start, frames, against, child) -> None:
    """Count the instructions the kernel runs a frame, on one thread, under valgrind."""
    if child:
        _child(json.loads(Path(child).read_text(encoding="utf-8")))
        return
    what = dict(scene=scene, world=world, size=size, start=start, frames=frames)
    if world:
        from sandmod.errors import ProblemsError

        try:
            bench, _ = benchmark.world_bench(Path(world))
        except ProblemsError as error:
            for problem in error.problems:
                click.echo(str(problem), err=True)
            sys.exit(2)
        name, cells = world, bench.width * bench.height
    else:
        name, cells = f"{scene} {size}x{size}", size * size
    if against:
        try:
            load_kernel(against)  # before counting anything: is it a kernel at all?
        except ValueError as error:
            raise click.BadParameter(str(error), param_hint="'--against'") from None
    span = f"frames {start + 1}-{start + frames}" if frames > 1 else f"frame {start + 1}"
    click.echo(f"{name}, {span}, one thread, counted by callgrind:")
    try:
        with tempfile.TemporaryDirectory(prefix="sandmod-count-") as scratch:
            folder = Path(scratch)
            _switch_library(folder)
            env = _environment()
            ours = count(what, _THIS_KERNEL, folder, env)
            click.echo("  " + _line("this kernel", ours, frames, cells))
            if against:
                theirs = count(what, str(Path(against).resolve()), folder, env)
                click.echo("  " + _line(against, theirs, frames, cells))
                same = "same frames" if theirs.digest == ours.digest else "OTHER FRAMES"
                click.echo(f"  this kernel runs {ours.instructions / theirs.instructions:.3f}x the instructions of {against}, {same}")
    except CannotCount as error:
        raise click.ClickException(str(error)) from None


if __name__ == "__main__":
    main()
