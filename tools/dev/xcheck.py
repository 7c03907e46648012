"""Drive ``sandmod play`` under a real X server and compare its window with the world, cell for cell.

Needs Xvfb, xdotool, xwininfo and ImageMagick's ``import`` (Debian: xvfb xdotool x11-utils imagemagick).
It opens a copy of examples/hourglass.toml at scale 3, paints a stone stroke, then, after each
action (the stroke, an undo, running on), pauses, takes a screenshot of the window and a snapshot
(F5), and counts the cells whose colour on screen differs from ``world.rgb()`` of that snapshot::

    python tools/dev/xcheck.py            # prints one line per action: N cells wrong
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parents[2]
SCALE = 3


def window_id(display: dict) -> str:
    """The id of play's window, once it is mapped."""
    for _ in range(120):
        tree = subprocess.run(["xwininfo", "-root", "-tree"], env=display, capture_output=True, text=True).stdout
        for line in tree.splitlines():
            if '"sandmod"' in line:
                return line.split()[0]
        time.sleep(0.5)
    sys.exit("play's window never appeared")


def main() -> None:
    folder = Path(tempfile.mkdtemp(prefix="xcheck-"))
    shutil.copy(ROOT / "examples" / "hourglass.toml", folder)
    display = {**os.environ, "DISPLAY": ":99"}
    server = subprocess.Popen(["Xvfb", ":99", "-screen", "0", "1280x1024x24"], stderr=subprocess.DEVNULL)
    time.sleep(1)
    play = subprocess.Popen([sys.executable, "-m", "sandmod", "play", "hourglass.toml", "--scale", str(SCALE)], cwd=folder, env=display)
    try:
        window = window_id(display)
        time.sleep(3)

        def xdo(*args: str, wait: float = 0.3) -> None:
            subprocess.run(["xdotool", *args], env=display, check=True)
            time.sleep(wait)

        def look(name: str) -> None:
            xdo("key", "--window", window, "space", wait=0.5)  # pause, so the screen and the snapshot agree
            subprocess.run(["import", "-window", window, str(folder / f"{name}.png")], env=display, check=True)
            xdo("key", "--window", window, "F5", wait=1)
            shutil.copy(folder / "play-snapshot.npz", folder / f"{name}.npz")
            xdo("key", "--window", window, "space", wait=1)

        xdo("key", "--window", window, "3")  # the stone swatch
        xdo("mousemove", "--window", window, "200", "60", "mousedown", "1")
        xdo("mousemove", "--window", window, "300", "80")
        xdo("mousemove", "--window", window, "440", "100", "mouseup", "1")
        xdo("mousemove", "--window", window, "600", "10")  # the outline off the world
        look("stroke")
        xdo("key", "--window", window, "ctrl+z")
        look("undo")
        time.sleep(2)
        look("later")
    finally:
        play.kill()
        server.kill()
    compare(folder, ["stroke", "undo", "later"])


def compare(folder: Path, names: list[str]) -> None:
    from sandmod.world.loading import load_world

    world = load_world(folder / "hourglass.toml").world
    for name in names:
        world.load_snapshot(folder / f"{name}.npz")
        want = world.rgb()
        got = np.asarray(Image.open(folder / f"{name}.png").convert("RGB"))
        height, width = (size * SCALE for size in want.shape[:2])
        wrong = min(
            int((got[y + SCALE // 2 : y + height : SCALE, x + SCALE // 2 : x + width : SCALE] != want).any(axis=2).sum())
            for y in range(0, got.shape[0] - height + 1)
            for x in range(0, got.shape[1] - width + 1)
        )
        print(f"{name}: frame {world.frame}, {int((world.cells != 0).sum())} cells not empty, {wrong} cells wrong on screen")


if __name__ == "__main__":
    main()
