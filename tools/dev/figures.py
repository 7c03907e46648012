"""The figures written in the prose of README.md and the docs pages, as data: for each, its page,
the page's text that holds it, the command that makes it and how to read it from what that prints.

    python tools/dev/figures.py --check             # the cheap ones made again: exit 1 where a page differs
    python tools/dev/figures.py --measure [--only TEXT] [--write]  # the measured ones, run once, beside the pages'

A cheap figure is exact and quick (a count, a limit, a figure of a bundled mod): ``--check`` runs its
command and says where the page differs (``tests/dev/test_figures.py`` does so in plain ``pytest``).
A measured one is a time, a speed or a ratio: the page names its command and machine, and ``--measure``
runs it and prints what it gives now; ``--write`` puts the new value into the page where the figure is
one number (a range, "two to three minutes", is for a person to reword).

Not listed: what a command prints in a page's output block (``pages.py`` makes those again), the
reference pages (written from the code by ``reference.py``), and history: the changelog, and the records
of past measurements that say what they compared (a change tried, "what did not help", a version before).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent.parent
FACTS = "python tools/dev/facts.py"
WORDS = dict(zip("one two three four five six seven eight nine ten eleven twelve thirteen fourteen fifteen".split(), range(1, 16)))


@dataclass(frozen=True)
class Figure:
    page: str  # relative to the checkout
    text: str  # the page's text that holds the figure, found there exactly once
    figure: str  # the figure as ``text`` writes it (every time it appears in ``text``)
    command: str  # a shell command, run in the checkout's root
    read: str | Callable[[str], str]  # a pattern whose first group in the output is the figure, or a function of the output
    measured: bool = False
    digits: int | None = None  # round what is read to this many decimals

    def now(self, output: str) -> str:
        """The figure as ``output`` gives it."""
        if callable(self.read):
            found = self.read(output)
        else:
            match = re.search(self.read, output, re.M)
            if not match:
                raise ValueError(f"{self.command} printed nothing that {self.read!r} matches")
            found = match.group(1)
        return found if self.digits is None else f"{float(found):.{self.digits}f}"

    def agrees(self, now: str) -> bool:
        return self.figure == now or str(WORDS.get(self.figure)) == now


def fact(page: str, text: str, figure: str, name: str) -> Figure:
    """A figure that ``tools/dev/facts.py`` prints, as ``name: figure``."""
    return Figure(page, text, figure, FACTS, rf"^{name}: (.*)$")


def measured(page: str, text: str, figure: str, command: str, read: str | Callable[[str], str], digits: int | None = None) -> Figure:
    return Figure(page, text, figure, command, read, measured=True, digits=digits)


def _json(key: str, **where: object) -> str:
    """A pattern for ``key``'s number in the JSON line (as the tools print it) whose fields are ``where``."""
    fields = ".*?".join(f'[{{ ]"{k}": {json.dumps(v)}[,}}]' for k, v in where.items())
    return rf'^(?={{).*?{fields}.*?[{{ ]"{key}": ([\d.]+)'


def _settled(output: str, what: str) -> str:
    """``sandmod bench --json`` asleep, then with every chunk updated: a step's milliseconds, or their ratio."""
    asleep, awake = (json.loads(line) for line in output.splitlines() if line.startswith("{"))
    ms = [1000 * run["seconds"] / run["steps"] for run in (asleep, awake)]
    return {"asleep": f"{ms[0]:.3f}", "awake": f"{ms[1]:.1f}", "ratio": f"{ms[1] / ms[0]:.0f}"}[what]


FIRST = "python tools/dev/firstframe.py"  # from an empty cache: the hourglass's first frame, and its end
FIRST_FRAME = r"^first frame ([\d.]+) s"


def _runs(output: str) -> str:
    """Each run's first frame, as a page lists them: "19.5, 20.1 and 19.9"."""
    seconds = re.findall(FIRST_FRAME, output, re.M)
    return ", ".join(seconds[:-1]) + " and " + seconds[-1]
PYTEST = "bash -c 'SECONDS=0; python -m pytest -q {} >/dev/null 2>&1; echo took $((SECONDS / 60)) min $((SECONDS % 60)) s'"
TURNS = "python tools/dev/bench.py in-turns --scene mix --scene halves --scene everything --threads 1 --threads 2 --json"
SETTLED = "sandmod bench --scene settled --size 1024 --steps 200 --threads 1 --json && sandmod bench --scene settled --size 1024 --steps 200 --threads 1 --no-sleep --json"
YARDSTICK = "python tools/dev/bench.py yardstick --scene mix --scene halves --threads 1 --json"
LOADED = "python tools/dev/bench.py loaded --scene mix --scene halves --scene everything --elements 500 --threads 1 --json"
FLUIDS = "python tools/dev/fluids.py"
HALVES = ("python -c 'from sandmod.jobs import benchmark; from sandmod.world.loading import load_ruleset; "
          "w = benchmark.scene_bench(load_ruleset(), \"halves\", 512).make(); w.threads = 1; "
          "print(\"steps with chunks awake:\", sum((w.awake_fraction > 0, w.step())[0] for _ in range(1000)))'")
SLOW = (FLUIDS, HALVES)  # cheap but seconds of the engine each: their test is marked slow
README_PYTHON = """python -c 'import re; exec(re.search(r"\\x60{3}python\\n(import sandmod.*?)\\x60{3}", open("README.md").read(), re.S).group(1))'"""
PLAY_ONE = "sandmod play --benchmark 1"
FOREST = "sandmod play examples/forest_fire.toml --benchmark 600"
PLAY_THREADS = "sandmod play --benchmark 600 && NUMBA_NUM_THREADS=1 sandmod play --benchmark 600"
MEMORY = "sandmod bench --memory 8192 --memory 16384 --json"
BATCH = ("bash -c 'for j in 1 2; do rm -rf /tmp/figures-batch; /usr/bin/time -f \"$j: %e s\" "
         "sandmod batch examples/seeds.toml -o /tmp/figures-batch -j $j -q; done'")
# with the garden plugin installed (pip install ./examples/garden-plugin); it empties the behaviours' cache
BEHAVIOURS = ("rm -rf \"$(python -c 'from sandmod.engine.kernelcache import kernel_cache_dir as d; print(d())')/behaviours\" && "
              "/usr/bin/time -f '%e s' sandmod render examples/garden-plugin/garden.toml --frames 1 -q -o /tmp/garden.gif")


def _fps_ratio(output: str) -> str:
    """The frames a second of the second run over the first's."""
    first, second = (float(fps) for fps in re.findall(r'"fps": ([\d.]+)', output))
    return f"{second / first:.2f}"


def _gigabytes(width: int) -> Callable[[str], str]:
    return lambda output: f"{float(re.search(_json('peak_mb', width=width), output, re.M).group(1)) / 1024:.2f}"


def _runs_a_minute(workers: int) -> Callable[[str], str]:
    """``BATCH``'s 64 runs a minute on ``workers``, or (0) two workers' over one's."""
    seconds = lambda output, j: float(re.search(rf"^{j}: ([\d.]+) s$", output, re.M).group(1))  # noqa: E731
    return lambda output: f"{seconds(output, 1) / seconds(output, 2):.2f}" if not workers else f"{64 * 60 / seconds(output, workers):.0f}"


def _speeds(page: str, rows: dict[str, tuple[str, ...]]) -> list[Figure]:
    """A table of in-turns speeds: for each scene, its texts holding the 1-thread figure, the 2-thread one
    (and the ratio, where the table shows it), each text followed by its figure."""
    found = []
    for scene, texts in rows.items():
        reads = [("mcell_updates_per_second", 1, 0), ("mcell_updates_per_second", 2, 0), ("speedup", 2, 2)]
        for (text, figure), (key, threads, digits) in zip(zip(texts[::2], texts[1::2]), reads):
            found.append(measured(page, text, figure, TURNS, _json(key, scene=scene, threads=threads), digits))
    return found


FIGURES: list[Figure] = [
    # README.md
    fact("README.md", "With Python 3.11 or newer and pip", "3.11", "python_min"),
    Figure("README.md", "the 34 tests marked slow", "34", "python -m pytest --collect-only -q -m slow -p no:cacheprovider", r"^(\d+)/\d+ tests collected"),
    fact("README.md", "up to 4,096 elements", "4,096", "max_elements"),
    fact("README.md", "(512², 1000 steps", "512", "bench_size"),
    fact("README.md", "(512², 1000 steps", "1000", "bench_steps"),
    Figure("README.md", "# {'base:empty': 8968, 'base:stone': 794, 'sand:sand': 1503, 'water:water': 1135}",
           "{'base:empty': 8968, 'base:stone': 794, 'sand:sand': 1503, 'water:water': 1135}", README_PYTHON, r"^(\{.*\})$"),
    measured("README.md", "kernel (its first frame after 17 s on two idle cores", "17", FIRST, FIRST_FRAME, 0),
    measured("README.md", "This takes about five minutes on two cores", "about five", PYTEST.format(""), r"^took (.*)$"),
    measured("README.md", "about\nseven minutes more", "about\nseven", PYTEST.format("-m slow"), r"^took (.*)$"),
    *_speeds("README.md", {"mix": ("a quarter water) | 215", "215", "| 267 | `python tools/dev/bench.py", "267"),
                           "halves": ("every cell full) | 139", "139", "| 203 | `... --scene halves", "203"),
                           "everything": ("reactions, blasts) | 16", "16", "| 26 | `... --scene everything", "26")}),
    measured("README.md", "| 0.044 ms a step", "0.044", SETTLED, lambda out: _settled(out, "asleep")),
    measured("README.md", "against 8.6", "8.6", SETTLED, lambda out: _settled(out, "awake")),
    measured("README.md", "(195x) |", "195", SETTLED, lambda out: _settled(out, "ratio")),
    # docs/index.md, docs/tutorial.md, docs/troubleshooting.md
    fact("docs/index.md", "With Python 3.11 or newer:", "3.11", "python_min"),
    measured("docs/index.md", "kernel (its first frame after 17 s on two idle", "17", FIRST, FIRST_FRAME, 0),
    measured("docs/tutorial.md", "caches it: about 17 s on two cores", "17", FIRST, FIRST_FRAME, 0),
    measured("docs/how-to/mods.md", "kernel first (about 17 s)", "17", FIRST, FIRST_FRAME, 0),
    fact("docs/tutorial.md", "With Python 3.11 or newer", "3.11", "python_min"),
    measured("docs/troubleshooting.md", "(once per version, about 17 s on two cores)", "17", FIRST, FIRST_FRAME, 0),
    measured("docs/troubleshooting.md", "first frame after 17 s on two idle cores", "17", FIRST, FIRST_FRAME, 0),
    measured("docs/troubleshooting.md", "16.4, 16.8 and 16.8 s; the version before", "16.4, 16.8 and 16.8", FIRST + " --runs 3", _runs),
    fact("docs/troubleshooting.md", "sandmod needs Python 3.11 or newer", "3.11", "python_min"),
    fact("docs/troubleshooting.md", "numba 0.68 or newer", "0.68", "numba_min"),
    fact("docs/troubleshooting.md", "(4G unless you say)", "4G", "max_memory"),
    # docs/performance.md
    *_speeds("docs/performance.md", {"mix": ("scattered | 215", "215", "x | 267 |", "267", "| 1.24", "1.24"),
                                     "halves": ("bottom half water | 139", "139", "x | 203 |", "203", "| 1.46", "1.46"),
                                     "everything": ("fire, blasts | 16", "16", "x | 26 |", "26", "| 1.67", "1.67")}),
    fact("docs/performance.md", "everything: twelve elements", "twelve", "everything_elements"),
    fact("docs/performance.md", "minutes: 512², 1000 steps", "512", "bench_size"),
    fact("docs/performance.md", "minutes: 512², 1000 steps", "1000", "bench_steps"),
    measured("docs/performance.md", "mix 0.78 of it", "0.78", YARDSTICK, _json("over_yardstick", scene="mix"), 2),
    measured("docs/performance.md", "halves 0.64.", "0.64", YARDSTICK, _json("over_yardstick", scene="halves"), 2),
    measured("docs/performance.md", "take\n0.044 ms a step asleep", "0.044", SETTLED, lambda out: _settled(out, "asleep")),
    measured("docs/performance.md", "against 8.6 ms with", "8.6", SETTLED, lambda out: _settled(out, "awake")),
    measured("docs/performance.md", "updated (195x)", "195", SETTLED, lambda out: _settled(out, "ratio")),
    Figure("docs/performance.md", "about 440 steps of the 1000", "440", HALVES,
           lambda output: str(round(int(re.search(r"awake: (\d+)", output).group(1)), -1))),
    Figure("docs/performance.md", "sinks at 0.9 cell a frame", "0.9", FLUIDS, r"sinks ([\d.]+) cell a frame", digits=1),
    fact("docs/performance.md", "into 32x32 chunks", "32", "chunk"),
    fact("docs/performance.md", "block (4 columns by", "4", "plume_columns"),
    fact("docs/performance.md", "by 16 rows, the grid", "16", "plume_rows"),
    fact("docs/performance.md", "its run (up to 16 rows", "16", "plume_rows"),
    fact("docs/performance.md", "reaches further than 17 cells", "17", "reach"),
    fact("docs/performance.md", "pass are 64 apart", "64", "tile"),
    fact("docs/performance.md", "smaller than 256x256 cells steps on one thread", "256", "one_thread_below"),
    fact("docs/performance.md", "one 64-bit word", "64", "mask_bits"),
    fact("docs/performance.md", "loaded: 3 bytes a pair", "3", "pair_bytes"),
    fact("docs/performance.md", "`Ruleset.colours`, 15 an element", "15", "colours_per_element"),
    fact("docs/performance.md", "(7 declared", "7", "apng_declared"),
    fact("docs/performance.md", "(5 declared)", "5", "webp_declared"),
    fact("docs/performance.md", "over 25-step stretches", "25", "turns_segment"),
    fact("docs/performance.md", "stretch three times", "three", "turns_repeats"),
    fact("docs/performance.md", "**Memory.** 16 bytes a cell", "16", "cell_bytes"),
    fact("docs/performance.md", "16.13 bytes a cell in all", "16.13", "bytes_per_cell"),
    fact("docs/performance.md", "48 MB for the most, 4,096", "4,096", "max_elements"),
    fact("docs/performance.md", "with 16\n  generated packs", "16", "loaded_500_packs"),
    fact("docs/performance.md", "(519 elements)", "519", "loaded_500_elements"),
    measured("docs/performance.md", "mix 0.959x", "0.959", LOADED, _json("ratio", scene="mix"), 3),
    measured("docs/performance.md", "halves 0.950x", "0.950", LOADED, _json("ratio", scene="halves"), 3),
    measured("docs/performance.md", "everything 0.981x", "0.981", LOADED, _json("ratio", scene="everything"), 3),
    measured("docs/performance.md", "17.0 s against 19.6", "17.0", FIRST + " --runs 3", lambda output: _runs(output).split()[-1]),
    # docs/architecture.md
    fact("docs/architecture.md", "(4,096\nelements x 15 = 61,440", "4,096", "max_elements"),
    fact("docs/architecture.md", "elements x 15 =", "15", "colours_per_element"),
    fact("docs/architecture.md", "each element gets 15 of its own", "15", "colours_per_element"),
    fact("docs/architecture.md", "chance 2.5 times the density gap's share", "2.5", "eagerness"),
    fact("docs/architecture.md", "0.94 (`compiler.exchange_chance`", "0.94", "exchange_most"),
    fact("docs/architecture.md", "sand in water 0.94", "0.94", "sand_into_water"),
    fact("docs/architecture.md", "0.38). The chance", "0.38", "water_into_oil"),
    fact("docs/architecture.md", "*plume block* (4 columns", "4", "plume_columns"),
    fact("docs/architecture.md", "by 16\n     rows, `layout.PLUME`", "16", "plume_rows"),
    fact("docs/architecture.md", "(up to 16 rows of its column, shifted", "16", "plume_rows"),
    fact("docs/architecture.md", "(1.5 times the gap's share", "1.5", "into_air"),
    fact("docs/architecture.md", "that is 3 bytes a pair", "3", "pair_bytes"),
    fact("docs/architecture.md", "a 64-bit mask of its partners", "64", "mask_bits"),
    fact("docs/architecture.md", "Elements 0 to 31 have a bit each", "31", "last_own_bit"),
    fact("docs/architecture.md", "with more than 32 elements", "32", "own_mask_bits"),
    fact("docs/architecture.md", "less 4 per cell", "4", "handed_on_cost"),
    fact("docs/architecture.md", "every 8 frames when it does", "8", "fast_trial"),
    fact("docs/architecture.md", "= 61,440 <", "61,440", "colours_max"),
    fact("docs/architecture.md", "**chunks** of 32 x 32 cells", "32", "chunk"),
    fact("docs/architecture.md", "`WAKE_MARGIN` = 2 cells", "2", "wake_margin"),
    fact("docs/architecture.md", "chunks (64 x 64 cells)", "64", "tile"),
    fact("docs/architecture.md", "smaller than 256 x 256 never does", "256", "one_thread_below"),
    fact("docs/architecture.md", "`REACH` = 17 cells", "17", "reach"),
    fact("docs/architecture.md", "`MAX_SPEED` = 16 cells", "16", "max_speed"),
    fact("docs/architecture.md", "48 MB with the most, 4,096", "4,096", "max_elements"),
    fact("docs/architecture.md", "`CACHED_CELLS` (65,536)", "65,536", "cached_cells"),
    fact("docs/architecture.md", "(int32): 16 bytes a cell", "16", "cell_bytes"),
    fact("docs/architecture.md", "Per chunk, 131 bytes", "131", "chunk_bytes"),
    fact("docs/architecture.md", "per tile three 8-byte words", "three", "tile_words"),
    fact("docs/architecture.md", "16.13 bytes a cell in all", "16.13", "bytes_per_cell"),
    fact("docs/architecture.md", "Up to 4,096 elements load at once", "4,096", "max_elements"),
    measured("docs/architecture.md", "first frame comes 17 s after the command starts", "17", FIRST, FIRST_FRAME, 0),
    # docs/how-to/play.md
    fact("docs/how-to/play.md", "a GIF of the last ten seconds", "ten", "play_capture_seconds"),
    fact("docs/how-to/play.md", "three rows of them", "three", "play_menu_rows"),
    fact("docs/how-to/play.md", "in a 640-pixel window", "640", "play_min_width"),
    fact("docs/how-to/play.md", "A player starts with nine favourites", "nine", "play_favourites"),
    fact("docs/how-to/play.md", "and so on, up to nine.", "nine", "play_favourites"),
    fact("docs/how-to/play.md", "Up to 32 steps are kept", "32", "undo_depth"),
    fact("docs/how-to/play.md", "kept, within 512 MB", "512", "undo_mb"),
    fact("docs/how-to/play.md", "the steps pass 512 MB", "512", "undo_mb"),
    fact("docs/how-to/play.md", "the 64x64 blocks", "64x64", "undo_block"),
    fact("docs/how-to/play.md", "(more than about 34 million cells)", "34", "undo_million_cells"),
    fact("docs/how-to/play.md", "50,000 events", "50,000", "session_events"),
    fact("docs/how-to/play.md", "and 3.75 MB of them", "3.75", "session_mb"),
    fact("docs/how-to/play.md", "(3,932,160 bytes", "3,932,160", "session_bytes"),
    fact("docs/how-to/play.md", "the 4 MB a world file may take", "4", "world_file_mb"),
    fact("docs/how-to/play.md", "and 1,000,000 frames", "1,000,000", "max_frames"),
    fact("docs/how-to/play.md", "runs at 60 steps a second", "60", "play_steps_a_second"),
    fact("docs/how-to/play.md", "display's 60 frames a second", "60", "play_display_fps"),
    Figure("docs/how-to/play.md", "on a new 512x384 world", "512x384", PLAY_ONE,
           lambda output: "{width}x{height}".format(**json.loads(output.splitlines()[-1]))),
    Figure("docs/how-to/play.md", "blasts) at scale 2", "2", PLAY_ONE, r'"scale": (\d+)'),
    measured("docs/how-to/play.md", "it shows about two thirds as many frames", "two thirds", PLAY_THREADS, _fps_ratio),
    measured("docs/how-to/play.md", "run at several hundred frames a second", "several hundred", FOREST, r'"fps": ([\d.]+)'),
    # docs/how-to/heat-and-fire.md, rendering.md, batch.md, plugins.md, reactions.md, worlds.md
    fact("docs/how-to/heat-and-fire.md", "Cells hotter than 525 °C glow", "525", "glow_from"),
    fact("docs/how-to/heat-and-fire.md", "Water at 100 °C", "100", "water_boils_at"),
    fact("docs/how-to/heat-and-fire.md", "holds 400 (", "400", "water_boiling_holds"),
    fact("docs/how-to/heat-and-fire.md", "its heat capacity of 4)", "4", "water_heat_capacity"),
    fact("docs/how-to/heat-and-fire.md", "boiling takes 340", "340", "boiling_latent_heat"),
    fact("docs/how-to/heat-and-fire.md", "capacity 0.5) is born", "0.5", "steam_heat_capacity"),
    fact("docs/how-to/heat-and-fire.md", "= 120 °C", "120", "steam_born_at"),
    fact("docs/how-to/heat-and-fire.md", "98 °C holds", "98", "steam_condenses_below"),
    fact("docs/how-to/heat-and-fire.md", "holds at most 49;", "49", "steam_condensing_holds"),
    fact("docs/how-to/heat-and-fire.md", "≈ 97 °C", "97", "water_born_at"),
    fact("docs/how-to/explosions.md", "in cells (at most 32)", "32", "blast_max_radius"),
    fact("docs/how-to/explosions.md", "| air, gases, particles | 0 |", "0", "resistance_gas"),
    fact("docs/how-to/explosions.md", "| powders and liquids | 0.5 |", "0.5", "resistance_powder"),
    fact("docs/how-to/explosions.md", "| static solids | 2 |", "2", "resistance_static"),
    fact("docs/how-to/explosions.md", "| titanium (bundled) | 1000000 |", "1000000", "resistance_titanium"),
    fact("docs/how-to/rendering.md", "hotter than 525 °C (or", "525", "glow_from"),
    fact("docs/how-to/rendering.md", "15 colours an element", "15", "colours_per_element"),
    fact("docs/how-to/rendering.md", "61,440 for 4,096", "61,440", "colours_max"),
    fact("docs/how-to/rendering.md", "for 4,096\nelements", "4,096", "max_elements"),
    fact("docs/how-to/rendering.md", "65,535 pixels a side", "65,535", "gif_max_side"),
    fact("docs/how-to/rendering.md", "WebP 16,383)", "16,383", "webp_max_side"),
    fact("docs/how-to/rendering.md", "frames to simulate (300)", "300", "render_frames"),
    fact("docs/how-to/rendering.md", "frames simulated per image written (2)", "2", "render_every"),
    fact("docs/how-to/rendering.md", "images per second when played (25)", "25", "render_fps"),
    fact("docs/how-to/rendering.md", "pixels per cell (3)", "3", "render_scale"),
    fact("docs/how-to/rendering.md", "0 (the default) forever", "0", "render_loop"),
    fact("docs/how-to/rendering.md", "a world smaller than 256x256 cells steps on one", "256", "one_thread_below"),
    fact("docs/how-to/rendering.md", "to 4 MB; mods are data", "4", "world_file_mb"),
    fact("docs/how-to/rendering.md", "allows 0.5 GB for Python", "0.5", "baseline_gb"),
    fact("docs/how-to/rendering.md", "a 16384x16384 world would", "16384", "max_size"),
    fact("docs/how-to/rendering.md", "world would take about\n  6 GB", "6", "refusal_world"),
    fact("docs/how-to/rendering.md", "6.5 GB in all", "6.5", "refusal_total"),
    fact("docs/how-to/rendering.md", "the limit of 4 GB", "4", "refusal_limit"),
    fact("docs/how-to/rendering.md", "(estimated 2.75)", "2.75", "estimate_8192"),
    fact("docs/how-to/rendering.md", "for 16384², the\nlargest", "16384", "max_size"),
    fact("docs/how-to/rendering.md", "(estimated 9.5;", "9.5", "estimate_largest"),
    fact("docs/how-to/rendering.md", "worlds up to about 10000² render", "10000", "largest_under_default"),
    measured("docs/how-to/rendering.md", "2.37 GB", "2.37", MEMORY, _gigabytes(8192)),
    measured("docs/how-to/rendering.md", "8.95 GB", "8.95", MEMORY, _gigabytes(16384)),
    fact("docs/how-to/batch.md", "(4G unless", "4G", "max_memory"),
    fact("docs/how-to/batch.md", "at most 100,000 runs", "100,000", "sweep_max_runs"),
    fact("docs/how-to/batch.md", "most 240 pixels a side", "240", "sheet_tile"),
    fact("docs/how-to/batch.md", "the sheet 16,384", "16,384", "sheet_max_side"),
    fact("docs/how-to/batch.md", "The 24 heaps", "24", "friction_runs"),
    fact("docs/how-to/batch.md", "idle, 64 runs of the hourglass", "64", "seeds_runs"),
    measured("docs/how-to/batch.md", "one worker made 596 runs a minute", "596", BATCH, _runs_a_minute(1)),
    measured("docs/how-to/batch.md", "and two 904", "904", BATCH, _runs_a_minute(2)),
    measured("docs/how-to/batch.md", "1.52 times as many", "1.52", BATCH, _runs_a_minute(0)),
    measured("docs/how-to/plugins.md", "steps: 3 to 5 seconds on two busy cores", "3 to 5", BEHAVIOURS, r"^([\d.]+) s$"),
    fact("docs/how-to/plugins.md", "up to 61,440 of them", "61,440", "colours_max"),
    fact("docs/how-to/plugins.md", "at most `REACH` (2)", "2", "behaviour_reach"),
    fact("docs/how-to/plugins.md", "the chunks (32 x 32", "32", "chunk"),
    fact("docs/how-to/plugins.md", "the tiles (64 x 64)", "64", "tile"),
    fact("docs/how-to/reactions.md", "over the 64 x 64", "64", "tile"),
    fact("docs/how-to/worlds.md", "`examples/level.png`, 96x64 pixels", "96x64", "level_png"),
    fact("docs/how-to/worlds.md", "for `frames` frames (1 by\ndefault)", "1", "heat_event_frames"),
    fact("docs/how-to/heat-and-fire.md", "`cooling` (0 to 0.5)", "0.5", "cooling_most"),
    # docs/gallery: written from the examples' first comments by tools/dev/reference.py, which show again in the
    # examples' files on the page: where a figure's text is in both, its entry names the example
    *[fact(page, "level.png is 96x64 pixels", "96x64", "level_png") for page in ("examples/picture_level.toml", "docs/gallery/index.md")],
    *[fact(page, "into a 192x128", "192x128", "level_world") for page in ("examples/picture_level.toml", "docs/gallery/index.md")],
    fact("examples/picture_level.toml", "At frame 60 a torch", "60", "level_torch"),
    fact("examples/lava_lake.toml", "below 900 degrees into basalt", "900", "lava_sets_below"),
    fact("examples/timeline.toml", "starts to boil it (for 150 frames)", "150", "timeline_heat_frames"),
    fact("docs/gallery/timeline.md", "- frame 90: a burst", "90", "timeline_spawn"),
    fact("docs/gallery/timeline.md", "- frame 150: the tap stops", "150", "timeline_stop"),
    fact("docs/gallery/timeline.md", "- frame 230: a blast", "230", "timeline_explode"),
    fact("docs/gallery/timeline.md", "- frame 300: the left wall is erased", "300", "timeline_erase"),
    fact("docs/gallery/timeline.md", "- frame 330: the tap starts again", "330", "timeline_start"),
]


def outputs(figures: list[Figure]) -> dict[str, str]:
    """What each of ``figures``' commands prints (stdout and stderr), each command run once, in the checkout."""
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
    printed = {}
    for command in dict.fromkeys(figure.command for figure in figures):
        done = subprocess.run(command, shell=True, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if done.returncode:
            raise RuntimeError(f"{command} exited {done.returncode}:\n{done.stdout}")
        printed[command] = done.stdout
    return printed


def missing(figures: list[Figure]) -> list[Figure]:
    """Each of ``figures`` whose text is not on its page once (reworded, or the figure changed by hand)."""
    return [figure for figure in figures if (ROOT / figure.page).read_text(encoding="utf-8").count(figure.text) != 1]


def differences(figures: list[Figure]) -> list[tuple[Figure, str]]:
    """Each of ``figures`` whose page says other than its command gives now, with what it gives."""
    printed = outputs(figures)
    return [(figure, now) for figure in figures if not figure.agrees(now := figure.now(printed[figure.command]))]


def rewritten(page: str, figure: Figure, now: str) -> str:
    """``page`` with ``figure``'s text holding ``now`` instead; ValueError if the text is not there."""
    if figure.text not in page:
        raise ValueError(f"{_where(figure)} is not on the page")
    return page.replace(figure.text, figure.text.replace(figure.figure, now), 1)


def _where(figure: Figure) -> str:
    return f"{figure.page}: {figure.text!r}"


def check() -> int:
    """Make the cheap figures again and say which differ, or are lost; 1 if any."""
    cheap = [figure for figure in FIGURES if not figure.measured]
    lost, wrong = missing(FIGURES), differences(cheap)
    for figure in lost:
        click.echo(f"{_where(figure)} is not on the page once: change its entry in tools/dev/figures.py")
    for figure, now in wrong:
        click.echo(f"{_where(figure)} says {figure.figure}, the code gives {now}")
    click.echo(f"{len(cheap)} cheap figures, {len(wrong)} differ; {len(lost)} of {len(FIGURES)} not found")
    return 1 if wrong or lost else 0


def measure(only: str, write: bool) -> int:
    """Run the measured figures' commands (those whose page or command holds ``only``) one at a time and
    print each figure beside the page's; ``write`` the new ones that are one number. 1 if a command failed."""
    status = 0
    chosen = [figure for figure in FIGURES if figure.measured and (only in figure.page or only in figure.command)]
    for command in dict.fromkeys(figure.command for figure in chosen):
        try:
            printed = outputs([Figure("", "", "", command, "")])[command]
        except RuntimeError as failed:
            click.echo(f"failed, its figures left as they are: {str(failed)[:500]}", err=True)
            status = 1
            continue
        for figure in (f for f in chosen if f.command == command):
            now = figure.now(printed)
            click.echo(f"{_where(figure)}: {figure.figure} on the page, {now} now")
            if write and re.fullmatch(r"[\d.,]+", figure.figure) and now != figure.figure:
                page = ROOT / figure.page
                try:
                    page.write_text(rewritten(page.read_text(encoding="utf-8"), figure, now), encoding="utf-8")
                except ValueError as lost:
                    click.echo(f"not written: {lost}", err=True)
    return status


@click.command()
@click.option("--check", "mode", flag_value="check", help="Make the cheap figures again (seconds); exit 1 where a page differs.")
@click.option("--measure", "mode", flag_value="measure", help="Run the measured figures' commands once (the better part of an hour) and print each beside the page's.")
@click.option("--only", default="", metavar="TEXT", help="With --measure: only the figures whose page or command holds TEXT (`performance.md`, `bench.py`).")
@click.option("--write", is_flag=True, help="With --measure: write the new figures (those that are one number) into the pages.")
def main(mode: str | None, only: str, write: bool) -> None:
    """The docs' prose figures, made again from their commands."""
    if mode is None:
        raise click.UsageError("give --check or --measure")
    sys.exit(check() if mode == "check" else measure(only, write))


if __name__ == "__main__":
    main()
