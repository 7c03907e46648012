"""Count how often each line of a kernel function runs: the paths a scene's cells take.

:mod:`instructions` says what a stretch of frames costs; this
says which way the cells went. It steps a scene or world natively to
``--start``, then runs the next ``--frames`` a second time from that state in
a child process, through the kernel's own Python source (numba's
``NUMBA_DISABLE_JIT``) under a line tracer. It prints, for each line of the
function that ran, how many times it did::

    python tools/dev/lines.py --scene halves --start 500 --frames 2
    python tools/dev/lines.py --scene mix --start 100 --min 5000 --from 470

``step_region`` is counted per version, with the fast loop and without
(``fast``), since each tile takes one or the other. The Python run must end
in the state the compiled kernel reaches from the same start; the tool
checks, and says so (exit 1 where they differ). So the counts are those of
the real frames. A 512x512 frame takes some ten seconds this way.

The child changes three things so that the source runs as plain Python. It
widens the tables and the world's arrays to int64, as numba's arithmetic
does (numpy would keep an int8 and overflow), and narrows the arrays back
at the end. ``_within`` and ``_inside`` become plain comparisons
(numba's unsigned casts wrap a negative number; numpy's raise). ``prefetch``
(an intrinsic) does nothing.
"""

from __future__ import annotations

import collections
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import click
import numpy as np

from sandmod.jobs import benchmark  # numpy, not numba
from instructions import last_line

#: The kernel functions worth counting (the ones a frame spends its time in).
FUNCTIONS = ("step_region", "conduct", "explode")

#: What a world carries from one frame to the next besides its cells (the rest is scratch).
_CARRIED = ("awake", "_even", "_fast_gain")


def _save(world, path: Path) -> None:
    np.savez(path, *world.state, frame=np.array(world.frame), **{name: getattr(world, name) for name in _CARRIED})


def _restore(world, path: Path) -> None:
    saved = np.load(path)
    for number, array in enumerate(world.state):
        array[...] = saved[f"arr_{number}"]
    for name in _CARRIED:
        getattr(world, name)[...] = saved[name]
    world.frame = int(saved["frame"])


def _make(job: dict):
    from sandmod.world.loading import load_ruleset

    if job["world"]:
        bench, _ = benchmark.world_bench(Path(job["world"]))
    else:
        bench = benchmark.scene_bench(load_ruleset(None, []), job["scene"], job["size"])
    return bench.make()


def _as_python(kernel) -> None:
    """Make the kernel's source run as plain Python, to the same results (see the module's docstring)."""
    kernel.prefetch = lambda array, y, x: None
    kernel._within = lambda v, limit: 0 <= int(v) < int(limit)
    kernel._inside = lambda x, y, width, height: 0 <= int(x) < int(width) and 0 <= int(y) < int(height)


def _child(job: dict) -> None:
    """Without numba: step the frames from the saved state under a line tracer; write the counts and digest."""
    from sandmod.engine import kernel

    _as_python(kernel)
    world = _make(job)
    world.tables = world.tables._replace(**{name: np.asarray(table).astype(np.int64) for name, table in world.tables._asdict().items()})
    _restore(world, Path(job["state"]))
    kinds = [array.dtype for array in world.state]
    world.state = type(world.state)(*(array.astype(np.int64) for array in world.state))
    code = getattr(kernel, job["function"]).__code__
    counts: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)

    def calls(frame, event, arg):
        if frame.f_code is not code:
            return None
        lines = counts[str(frame.f_locals.get("fast", "all"))]

        def each_line(frame, event, arg):
            if event == "line":
                lines[frame.f_lineno] += 1
            return each_line

        return each_line

    sys.settrace(calls)
    try:
        for _ in range(job["frames"]):
            world.step()
    finally:
        sys.settrace(None)
    world.state = type(world.state)(*(array.astype(kind) for array, kind in zip(world.state, kinds)))
    Path(job["out"]).write_text(json.dumps({"digest": benchmark.state_digest(world), "counts": counts}), encoding="utf-8")


def _report(counts: dict[str, dict[str, int]], source: list[str], first: int, least: int) -> list[str]:
    out = []
    for version in sorted(counts):
        lines = {int(n): c for n, c in counts[version].items()}
        label = {"True": "with the fast loop", "False": "without the fast loop"}.get(version, "")
        out.append(f"{label or 'all calls'}: {sum(lines.values())} lines run")
        out.extend(f"{c:10d} {n:5d}  {source[n - 1].strip()[:100]}" for n, c in sorted(lines.items()) if n >= first and c >= least)
    return out


@click.command()
@click.option("--scene", default="halves", show_default=True, type=click.Choice(list(benchmark.SCENES)))
@click.option("--world", "world", type=click.Path(exists=True, dir_okay=False), help="A world file instead of a scene.")
@click.option("--size", default=512, show_default=True, type=click.IntRange(16, 2048), help="The scene's width and height.")
@click.option("--start", default=200, show_default=True, type=click.IntRange(0), help="Frames stepped (compiled) before counting.")
@click.option("--frames", default=1, show_default=True, type=click.IntRange(1), help="Frames counted.")
@click.option("--function", "function", default="step_region", show_default=True, type=click.Choice(FUNCTIONS))
@click.option("--from", "first", default=1, show_default=True, type=click.IntRange(1), help="Show lines from this line number on.")
@click.option("--min", "least", default=1, show_default=True, type=click.IntRange(1), help="Show lines run at least this often.")
@click.option("--child", hidden=True)
def main(scene, world, size, start, frames, function, first, least, child) -> None:
    """Count how often each line of a kernel function runs over some frames (the kernel run as Python)."""
    if child:
        _child(json.loads(Path(child).read_text(encoding="utf-8")))
        return
    from sandmod.engine import kernel
    from sandmod.errors import ProblemsError

    job = dict(scene=scene, world=world, size=size, frames=frames, function=function)
    try:
        native = _make(job)
    except ProblemsError as error:
        for problem in error.problems:
            click.echo(str(problem), err=True)
        sys.exit(2)
    for _ in range(start):
        native.step()
    name = world or f"{scene} {native.width}x{native.height}"
    span = f"frames {start + 1}-{start + frames}" if frames > 1 else f"frame {start + 1}"
    with tempfile.TemporaryDirectory(prefix="sandmod-lines-") as scratch:
        job.update(state=str(Path(scratch) / "state.npz"), out=str(Path(scratch) / "counts.json"))
        _save(native, Path(job["state"]))
        for _ in range(frames):
            native.step()
        (Path(scratch) / "job.json").write_text(json.dumps(job), encoding="utf-8")
        env = dict(os.environ, NUMBA_DISABLE_JIT="1")
        ran = subprocess.run([sys.executable, __file__, "--child", str(Path(scratch) / "job.json")], env=env, capture_output=True, text=True)
        if ran.returncode != 0:
            raise click.ClickException(f"the frames did not run as Python: {last_line(ran.stderr)}")
        result = json.loads(Path(job["out"]).read_text(encoding="utf-8"))
    click.echo(f"{name}, {span}, {function}, the kernel run as Python:")
    source = Path(kernel.__file__).read_text(encoding="utf-8").splitlines()
    for line in _report(result["counts"], source, first, least):
        click.echo("  " + line)
    if result["digest"] != benchmark.state_digest(native):
        click.echo("  OTHER FRAMES than the compiled kernel's: these counts are not the real frames'", err=True)
        sys.exit(1)
    click.echo("  the same frames as the compiled kernel")


if __name__ == "__main__":
    main()
