"""Developers' timings, run from a checkout: kernels against each other, thread counts, the yardstick.

    python tools/dev/bench.py against /tmp/old_kernel.py --scene mix --threads 1
    python tools/dev/bench.py in-turns --scene everything --threads 1 --threads 2
    python tools/dev/bench.py yardstick --scene mix --threads 1 --threads 2
    python tools/dev/bench.py loaded --scene mix --elements 500 --threads 1

Each takes turns over stretches of 25 steps, each stretch three times from
the same state, and counts the best times: a fair comparison on a machine
whose speed drifts (see :func:`kernels.in_turns`). Users' timings are
``sandmod bench``.

``against`` times this kernel and another version of it (``git show
REV:core/engine/kernel.py > /tmp/old_kernel.py``) on the same frames: both
must reach them (exit 1 where they do not), unless ``--own-frames`` says
their rules differ. ``in-turns`` does the same for the ``--threads`` counts,
and checks that every count steps to the same frames. ``yardstick`` times the
kernel with the yardstick (:mod:`yardstick`) on each ``--threads`` count: what
this machine allows at the time, the kernel's speed as a share of it, and what
more threads give each of them. ``loaded`` times a scene with only the mods
it paints with loaded (sand's and water's; the bundled ones for
``everything``) against the same scene with generated packs
(``packs.py``) loaded too, ``--elements`` in all: what loading many elements
costs a world that uses few.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path

import click

from sandmod.jobs import benchmark
from sandmod.tools.cli import ThreadCount, _named, _report, _thread_pool, _threads, _what

SCENES = ["mix", "halves", "everything", "settled", "patch"]


@dataclass(frozen=True)
class Comparison(benchmark._Result):
    """Two kernels timed on the same frames (``against --json``)."""

    scene: str
    width: int
    height: int
    steps: int
    threads: int | str  # a count, or "auto"
    mcell_updates_per_second: float  # this kernel
    against: str
    against_mcell_updates_per_second: float
    speedup: float  # this kernel's speed over the other's
    same_frames: bool  # False: each stepped on from its own frames (--own-frames)


@dataclass(frozen=True)
class Turns(benchmark._Result):
    """One thread count, timed in turns with others on the same frames (``in-turns --json``)."""

    scene: str
    width: int
    height: int
    steps: int
    threads: int | str  # a count, or "auto"
    mcell_updates_per_second: float
    speedup: float  # over the first thread count asked for
    over_threads: int | str  # that count


@dataclass(frozen=True)
class Yardstick(Turns):
    """One thread count: this kernel and the yardstick in turns (``yardstick --json``)."""

    yardstick_mcell_updates_per_second: float
    over_yardstick: float  # this kernel's speed over the yardstick's
    yardstick_speedup: float  # the yardstick's, over the first thread count asked for


def _runs(scenes, worlds, size, steps, thread_counts) -> list[tuple[benchmark.Bench, int]]:
    """The scenes and worlds to time, with the kernels compiled."""
    from sandmod.jobs.warmup import compile_kernels, compile_parallel
    from sandmod.world.loading import load_ruleset

    _thread_pool(max((c for c in thread_counts if c is not None), default=1))
    benches = [benchmark.world_bench(path)[0] for path in worlds]
    ruleset = load_ruleset()
    if scenes or not worlds:
        benches[:0] = [benchmark.scene_bench(ruleset, scene, size, 0) for scene in scenes or ("mix",)]
    compile_kernels(ruleset)
    if any(count != 1 for count in thread_counts):
        compile_parallel()
    return [(b, steps or b.steps) for b in benches]


def _options(command):
    for option in reversed([
        click.option("--scene", "scenes", multiple=True, type=click.Choice(SCENES), help="Scene (repeatable; default: mix)."),
        click.option("--world", "worlds", multiple=True, type=click.Path(exists=True, dir_okay=False, path_type=Path), help="A world file (repeatable)."),
        click.option("--size", type=click.IntRange(64, 2048), default=512, show_default=True, help="The scenes' side in cells."),
        click.option("--steps", type=click.IntRange(1, 100000), help="Steps to time.  [default: 1000; a world's own frames]"),
        click.option("--threads", "thread_counts", multiple=True, type=ThreadCount(), help="Threads, or auto (repeatable)."),
        click.option("--busy", type=click.IntRange(0, 256), default=0, help="Keep this many other processes busy meanwhile."),
        click.option("--json", "as_json", is_flag=True, help="One JSON object per run."),
    ]):
        command = option(command)
    return command


@click.group()
def main() -> None:
    """Developers' timings (see this file's docstring)."""


@main.command()
@click.argument("kernel_file", type=click.Path(exists=True, dir_okay=False), metavar="KERNEL.py")
@click.option("--own-frames", is_flag=True, help="The kernels' rules differ: each steps on from its own frames.")
@_options
def against(kernel_file, own_frames, scenes, worlds, size, steps, thread_counts, busy, as_json) -> None:
    """Time this kernel against another version of it, on the same frames."""
    from numba.core.errors import NumbaError

    from kernels import FramesDiffer, compare, load_kernel
    from sandmod.engine import kernel

    try:
        other = load_kernel(kernel_file)
    except ValueError as error:
        raise click.BadParameter(str(error), param_hint="'KERNEL.py'") from None
    thread_counts = thread_counts or (None,)
    runs = _runs(scenes, worlds, size, steps, thread_counts)
    with benchmark.busy_processes(busy):
        for b, count in runs:
            cells = b.width * b.height * count / 1e6
            for threads in thread_counts:
                try:
                    ours, theirs = compare(b, count, threads, [kernel, other], own_frames=own_frames)
                except FramesDiffer as differ:
                    click.echo(f"error: {b.name}: {kernel_file} steps to other frames than this kernel (by frame {differ.frame})", err=True)
                    sys.exit(1)
                except NumbaError as error:  # it imports, but its code does not fit this sandmod's arrays
                    first = str(error).strip().splitlines()[0]
                    raise click.BadParameter(f"{kernel_file}: does not compile beside this sandmod ({type(error).__name__}: {first})", param_hint="'KERNEL.py'") from None
                result = Comparison(
                    b.name, b.width, b.height, count, _named(threads), round(cells / ours, 1), str(kernel_file), round(cells / theirs, 1),
                    round(theirs / ours, 3), not own_frames,
                )
                _report(
                    result,
                    as_json,
                    f"{_what(b, count)}, {_threads(threads)}: this kernel {result.mcell_updates_per_second:.1f} million cell-updates/s, "
                    f"{kernel_file} {result.against_mcell_updates_per_second:.1f}: {result.speedup:.3f}x, "
                    f"{'same frames' if result.same_frames else 'each on its own frames'}",
                )


@main.command("in-turns")
@_options
def in_turns(scenes, worlds, size, steps, thread_counts, busy, as_json) -> None:
    """Time the --threads counts in turns on the same frames."""
    from kernels import FramesDiffer, compare
    from sandmod.engine import kernel

    thread_counts = thread_counts or (1, None)
    runs = _runs(scenes, worlds, size, steps, thread_counts)
    with benchmark.busy_processes(busy):
        for b, count in runs:
            cells = b.width * b.height * count / 1e6
            try:
                seconds = compare(b, count, list(thread_counts), [kernel] * len(thread_counts))
            except FramesDiffer as differ:  # a bug in the kernel: threads must never change the frames
                click.echo(f"error: {b.name}: {_threads(thread_counts[0])} and more step to other frames (by frame {differ.frame})", err=True)
                sys.exit(1)
            results = [
                Turns(b.name, b.width, b.height, count, _named(threads), round(cells / took, 1), round(seconds[0] / took, 3), _named(thread_counts[0]))
                for threads, took in zip(thread_counts, seconds)
            ]
            if as_json:
                for result in results:
                    click.echo(json.dumps(result.as_dict()))
                continue
            speeds = [f"{_threads(r.threads)} {r.mcell_updates_per_second:.1f}" + (f" ({r.speedup:.2f}x)" if i else "") for i, r in enumerate(results)]
            click.echo(f"{_what(b, count)}, in turns: {', '.join(speeds)} million cell-updates/s, same frames")


@dataclass(frozen=True)
class Loaded(benchmark._Result):
    """One scene with its own mods loaded, and with generated packs beside them (``loaded --json``)."""

    scene: str
    width: int
    height: int
    steps: int
    threads: int | str
    elements: int  # loaded in all, the packs' and the bundled mods'
    few_elements: int  # loaded with the scene's own mods only
    mcell_updates_per_second: float  # with all loaded
    few_mcell_updates_per_second: float
    ratio: float  # the speed with all loaded over the speed with few


@main.command()
@click.option("--elements", type=click.IntRange(30, 4096), default=500, show_default=True, help="Elements loaded in all: generated packs of 25 beside the bundled mods.")
@_options
def loaded(elements, scenes, worlds, size, steps, thread_counts, busy, as_json) -> None:
    """Time a scene with only its mods loaded against the same scene with many more elements loaded (generated packs), in turns on the same cells."""
    import tempfile

    from kernels import FramesDiffer, compare_worlds
    from packs import write_packs
    from sandmod.world.loading import load_ruleset

    if worlds:
        raise click.UsageError("loaded times the built-in scenes (sand and water), not a --world")
    thread_counts = thread_counts or (1,)
    with tempfile.TemporaryDirectory() as folder:
        bundled = len(load_ruleset().elements)
        packs = max(1, -(-(elements - bundled) // 25))
        write_packs(Path(folder), packs, 25)
        many = load_ruleset(None, [Path(folder)])
    runs = _runs(scenes, (), size, steps, thread_counts)
    with benchmark.busy_processes(busy):
        for b, count in runs:
            cells = b.width * b.height * count / 1e6
            few = load_ruleset(None if b.name == "everything" else ["sand", "water"])  # what the scene paints
            pair = [benchmark.scene_bench(ruleset, b.name, size) for ruleset in (few, many)]
            for threads in thread_counts:
                try:
                    mine, theirs = compare_worlds(pair, count, threads)
                except FramesDiffer as differ:
                    click.echo(f"error: {b.name}: with {len(many.elements)} elements loaded the cells differ (by frame {differ.frame})", err=True)
                    sys.exit(1)
                result = Loaded(b.name, b.width, b.height, count, _named(threads), len(many.elements), len(few.elements),
                                round(cells / theirs, 1), round(cells / mine, 1), round(mine / theirs, 3))
                _report(
                    result,
                    as_json,
                    f"{_what(b, count)}, {_threads(threads)}, in turns: {result.few_elements} elements loaded "
                    f"{result.few_mcell_updates_per_second:.1f} million cell-updates/s, {result.elements} loaded "
                    f"{result.mcell_updates_per_second:.1f}: {result.ratio:.3f}x, same cells",
                )


@main.command()
@_options
def yardstick(scenes, worlds, size, steps, thread_counts, busy, as_json) -> None:
    """Time the kernel in turns with the simplest sand and water step, on each --threads count."""
    from yardstick import against_yardstick

    if worlds:
        raise click.UsageError("the yardstick runs on the built-in scenes (its rules know sand and water only), not on a --world")
    if None in thread_counts:
        raise click.UsageError("the yardstick times fixed thread counts: give --threads N")
    thread_counts = thread_counts or (1,)
    runs = _runs(scenes, worlds, size, steps, thread_counts)
    with benchmark.busy_processes(busy):
        for b, count in runs:
            cells = b.width * b.height * count / 1e6
            ours, theirs = against_yardstick(b, count, thread_counts)
            results = [
                Yardstick(
                    b.name, b.width, b.height, count, threads, round(cells / mine, 1), round(ours[0] / mine, 3), thread_counts[0],
                    yardstick_mcell_updates_per_second=round(cells / its, 1),
                    over_yardstick=round(its / mine, 3),
                    yardstick_speedup=round(theirs[0] / its, 3),
                )
                for threads, mine, its in zip(thread_counts, ours, theirs)
            ]
            if as_json:
                for result in results:
                    click.echo(json.dumps(result.as_dict()))
                continue
            parts = [
                f"{_threads(r.threads)}: this kernel {r.mcell_updates_per_second:.1f}, the yardstick "
                f"{r.yardstick_mcell_updates_per_second:.1f} ({r.over_yardstick:.2f} of it)"
                for r in results
            ]
            parts += [f"{r.threads} over {r.over_threads}: this kernel {r.speedup:.2f}x, the yardstick {r.yardstick_speedup:.2f}x" for r in results[1:]]
            click.echo(f"{_what(b, count)}, in turns, million cell-updates/s: {'; '.join(parts)}")


if __name__ == "__main__":
    main()
