"""Draw heap slope against friction from a friction sweep's results.csv (docs/how-to/batch.md's figure).

    sandmod batch docs/sweeps/friction.toml -o friction -j 2
    python tools/dev/slope_plot.py friction/results.csv docs/images/friction_slope.png

A heap's slope is atan(height / half its width), in degrees, from the sweep's extent metrics;
each dot is a run, the line joins each friction's mean, and the dashed line is atan(friction).
"""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

from PIL import Image, ImageDraw

W, H, LEFT, BOTTOM, TOP, RIGHT = 520, 340, 56, 44, 20, 20


def main(table: Path, out: Path) -> None:
    runs = [row for row in csv.DictReader(table.open()) if row["status"] == "done"]
    frame = max(int(k.split("@")[1]) for k in runs[0] if k.startswith("height.sand:sand@"))
    points = []
    for row in runs:
        height, width = float(row[f"height.sand:sand@{frame}"]), float(row[f"width.sand:sand@{frame}"])
        points.append((float(row["parameter.elements.sand.friction"]), math.degrees(math.atan(height / (width / 2)))))
    frictions = sorted({f for f, _ in points})
    means = [(f, sum(s for g, s in points if g == f) / sum(1 for g, _ in points if g == f)) for f in frictions]
    image = Image.new("RGB", (W, H), "white")
    draw = ImageDraw.Draw(image)
    x_max, y_max = max(frictions) * 1.05, 50.0

    def at(friction: float, slope: float) -> tuple[float, float]:
        return LEFT + friction / x_max * (W - LEFT - RIGHT), H - BOTTOM - slope / y_max * (H - BOTTOM - TOP)

    draw.line([at(0, 0), at(x_max, 0)], fill="black")
    draw.line([at(0, 0), at(0, y_max)], fill="black")
    for tick in range(0, 51, 10):
        draw.text((LEFT - 26, at(0, tick)[1] - 6), f"{tick}°", fill="black")
    for friction in frictions:
        draw.text((at(friction, 0)[0] - 8, H - BOTTOM + 6), f"{friction:g}", fill="black")
    draw.text((W // 2 - 30, H - 18), "friction", fill="black")
    draw.text((LEFT + 6, 4), "heap slope, degrees (dashed: atan(friction))", fill="black")
    curve = [at(f / 20 * x_max, min(math.degrees(math.atan(f / 20 * x_max)), 45)) for f in range(21)]
    for a, b in zip(curve[::2], curve[1::2]):
        draw.line([a, b], fill=(150, 150, 150))
    draw.line([at(f, s) for f, s in means], fill=(200, 120, 30), width=2)
    for friction, slope in points:
        x, y = at(friction, slope)
        draw.ellipse([x - 3, y - 3, x + 3, y + 3], fill=(40, 90, 200))
    image.save(out)


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))
