"""A first run's wait, as a new user has it: ``sandmod render`` of a world from an empty cache, in a
process of its own; prints the seconds from its start to its first frame drawn, and to its end.

    python tools/dev/firstframe.py [WORLD] [--runs 3]

The render compiles the kernel first (``sandmod.jobs.warmup``): its first frame waits for the parts
the world uses, and the others compile while it runs (the end waits for them).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent.parent


def _child(world: str, output: str, started: float) -> None:
    """Render ``world`` here (the command line's own code), saying when the first image is drawn."""
    from sandmod.tools.cli import cli
    from sandmod.world.world import World

    image = World.image

    def first_image(self, *args, **kwargs):
        if not getattr(World, "_drawn", False):
            World._drawn = True
            print(f"first frame {time.time() - started:.1f} s", flush=True)
        return image(self, *args, **kwargs)

    World.image = first_image
    try:
        cli(["render", world, "-q", "-o", output], standalone_mode=False)
    finally:
        print(f"done {time.time() - started:.1f} s", flush=True)


@click.command()
@click.argument("world", default="examples/hourglass.toml")
@click.option("--runs", default=1, show_default=True, help="How many first runs, one after another.")
@click.option("--child", nargs=2, hidden=True)
def main(world: str, runs: int, child) -> None:
    """Time a first run's render of WORLD from an empty cache: to its first frame, and to its end."""
    if child:
        _child(world, child[0], float(child[1]))
        return
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as cache:
            env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"} | {"XDG_CACHE_HOME": cache}
            started = time.time()
            command = [sys.executable, __file__, world, "--child", str(Path(cache) / "out.gif"), repr(started)]
            done = subprocess.run(command, env=env, cwd=ROOT, capture_output=True, text=True)
            if done.returncode != 0:
                sys.exit(done.stderr)
            click.echo(", ".join(done.stdout.split("\n")[:2]))


if __name__ == "__main__":
    main()
