"""Count how often each line of the kernel runs: the paths a scene's cells take.

:mod:`instructions` says what a stretch of frames costs; this says which way
the cells went. It steps a scene or world natively to ``--start``, then runs
the next ``--frames`` a second time from that state in a child process,
through the engine's own Python source (numba's ``NUMBA_DISABLE_JIT``) under
a tracer. It prints how many times each engine function was called, and each
line of the engine that ran, with how often::

    python tools/dev/lines.py --scene halves --start 500 --frames 2
    python tools/dev/lines.py --scene mix --start 100 --min 5000 --function move

The cells' update is counted per version of ``step_region``, with the fast
loop and without (``fast``), since each tile takes one or the other. The
Python run must end in the state the compiled kernel reaches from the same
start; the tool checks, and says so (exit 1 where they differ). So the counts
are those of the real frames. A 512x512 frame takes some ten seconds this way.

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


def _engine_modules() -> list:
    import importlib
    import pkgutil

    from sandmod import engine

    return [importlib.import_module(f"sandmod.engine.{m.name}") for m in pkgutil.iter_modules(engine.__path__)]


def _as_python() -> None:
    """Make the engine's source run as plain Python, to the same results (see the module's docstring)."""
    for module in _engine_modules():
        for name, plain in (
            ("prefetch", lambda array, y, x: None),
            ("_within", lambda v, limit: 0 <= int(v) < int(limit)),
            ("_inside", lambda x, y, width, height: 0 <= int(x) < int(width) and 0 <= int(y) < int(height)),
        ):
            if hasattr(module, name):
                setattr(module, name, plain)


def _child(job: dict) -> None:
    """Without numba: step the frames from the saved state under a tracer; write the counts and digest."""
    _as_python()
    world = _make(job)
    world.tables = world.tables._replace(**{name: np.asarray(table).astype(np.int64) for name, table in world.tables._asdict().items()})
    _restore(world, Path(job["state"]))
    kinds = [array.dtype for array in world.state]
    world.state = type(world.state)(*(array.astype(np.int64) for array in world.state))
    engine = str(Path(_engine_modules()[0].__file__).parent)
    lines: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)  # version -> "file:function:line" -> runs
    calls: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)  # version -> function -> calls
    version = ["all"]  # the fast loop's, of the step_region running

    def each_call(frame, event, arg):
        code = frame.f_code
        if not code.co_filename.startswith(engine):
            return None
        if code.co_name == "step_region":
            version[0] = str(frame.f_locals.get("fast"))
        calls[version[0]][code.co_name] += 1
        where = f"{Path(code.co_filename).name}:{code.co_name}:"

        def each_line(frame, event, arg):
            if event == "line":
                lines[version[0]][where + str(frame.f_lineno)] += 1
            return each_line

        return each_line

    from sandmod.world import world as world_module

    world_module._STEP_COMPILED = True  # the step later runs take, with the fast loop (a first run's quick step has none)
    sys.settrace(each_call)
    try:
        for _ in range(job["frames"]):
            world.step()
    finally:
        sys.settrace(None)
    world.state = type(world.state)(*(array.astype(kind) for array, kind in zip(world.state, kinds)))
    result = {"digest": benchmark.state_digest(world), "lines": lines, "calls": calls}
    Path(job["out"]).write_text(json.dumps(result), encoding="utf-8")


def _report(result: dict, sources: dict[str, list[str]], function: str | None, least: int) -> list[str]:
    """For each version: the calls of each function, and the lines run (of ``function``, or all) at least ``least`` times."""
    out = []
    for version in sorted(result["calls"]):
        label = {"True": "with the fast loop", "None": "without the fast loop"}.get(version, "outside the cells' update")
        counted = result["calls"][version]
        out.append(f"{label}: calls " + ", ".join(f"{name} {n}" for name, n in sorted(counted.items(), key=lambda item: -item[1])))
        for where, runs in sorted(result["lines"].get(version, {}).items(), key=lambda item: _place(item[0])):
            file, name, line = where.split(":")
            if runs >= least and function in (None, name):
                out.append(f"{runs:10d}  {file}:{line:<5} {sources[file][int(line) - 1].strip()[:100]}")
    return out


def _place(where: str) -> tuple[str, int]:
    file, _, line = where.split(":")
    return file, int(line)


@click.command()
@click.option("--scene", default="halves", show_default=True, type=click.Choice(list(benchmark.SCENES)))
@click.option("--world", "world", type=click.Path(exists=True, dir_okay=False), help="A world file instead of a scene.")
@click.option("--size", default=512, show_default=True, type=click.IntRange(16, 2048), help="The scene's width and height.")
@click.option("--start", default=200, show_default=True, type=click.IntRange(0), help="Frames stepped (compiled) before counting.")
@click.option("--frames", default=1, show_default=True, type=click.IntRange(1), help="Frames counted.")
@click.option("--function", "function", help="Show the lines of this engine function only (default: every one).")
@click.option("--min", "least", default=1, show_default=True, type=click.IntRange(1), help="Show lines run at least this often.")
@click.option("--child", hidden=True)
def main(scene, world, size, start, frames, function, least, child) -> None:
    """Count the engine's calls and lines over some frames (the kernel run as Python)."""
    if child:
        _child(json.loads(Path(child).read_text(encoding="utf-8")))
        return
    from sandmod.errors import ProblemsError

    job = dict(scene=scene, world=world, size=size, frames=frames)
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
    click.echo(f"{name}, {span}, the kernel run as Python:")
    sources = {Path(m.__file__).name: Path(m.__file__).read_text(encoding="utf-8").splitlines() for m in _engine_modules()}
    for line in _report(result, sources, function, least):
        click.echo("  " + line)
    if result["digest"] != benchmark.state_digest(native):
        click.echo("  OTHER FRAMES than the compiled kernel's: these counts are not the real frames'", err=True)
        sys.exit(1)
    click.echo("  the same frames as the compiled kernel")


if __name__ == "__main__":
    main()
