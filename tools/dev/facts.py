"""The figures the docs quote from the code and the bundled mods, one a line, ``name: value``,
each written as the pages write it (``4,096``, ``3.75``): what ``figures.py --check`` reads them from.

    python tools/dev/facts.py

Quick (no kernel compiled or run): bundled mods are loaded, a world allocated, sweeps planned.
"""

from __future__ import annotations

import inspect
import math
import re
import sys
import tempfile
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))

SIDE = 1024  # the world whose bytes are counted


def facts() -> dict[str, object]:
    """Each figure's name and value, read from the code at the time of asking."""
    from sandmod.world.loading import load_ruleset

    ruleset = load_ruleset()  # every bundled mod
    return {**_install(), **_engine(ruleset), **_elements(ruleset), **_limits(), **_play(), **_tools(ruleset), **_examples()}


def _n(value: float) -> str:
    """A number as a page writes it: 4, 0.5, 1000000."""
    return f"{value:.15g}"


def _install() -> dict[str, object]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    return {"python_min": project["requires-python"].removeprefix(">="),
            "numba_min": next(d for d in project["dependencies"] if d.startswith("numba")).split(">=")[1]}


def _engine(ruleset) -> dict[str, object]:
    """The kernel's constants, and the bytes a world and the element tables take."""
    import numpy as np

    from sandmod.engine import kernel, layout, threads
    from sandmod.jobs import benchmark, undo
    from sandmod.rules.colours import GLOW_COLOURS, SCORCHED_SHADES, SHADES
    from sandmod.world.world import World

    world = World(ruleset, SIDE, SIDE)
    whole = lambda a: a if a.base is None else a.base  # noqa: E731 (as benchmark.state_bytes counts them)
    per_chunk = sum(whole(a).nbytes for a in (world.awake, world._woken, world._even, world._stirred)) // (SIDE // layout.CHUNK) ** 2
    per_tile = sum(a.nbytes for a in (world._detonations, world._fast_gain, world._seen)) // (SIDE // layout.TILE) ** 2
    cell = sum(a.nbytes for a in world.state) // SIDE**2
    n, tables = len(ruleset.elements), ruleset.tables
    pairs = sum(a.nbytes for a in tables._asdict().values() if isinstance(a, np.ndarray) and a.shape[:2] == (n, n))
    colours = SHADES + SCORCHED_SHADES + len(GLOW_COLOURS)
    return {
        "max_elements": f"{layout.MAX_ELEMENTS:,}", "colours_per_element": colours, "colours_max": f"{colours * layout.MAX_ELEMENTS:,}",
        "cell_bytes": cell, "chunk_bytes": per_chunk, "tile_words": per_tile // 8, "pair_bytes": pairs // n**2,
        "bytes_per_cell": f"{benchmark.state_bytes(world) / SIDE**2:.2f}",
        "undo_million_cells": round(undo.UNDO_MEMORY / cell / 1e6),
        "chunk": layout.CHUNK, "tile": layout.TILE, "wake_margin": layout.WAKE_MARGIN, "reach": layout.REACH,
        "max_speed": layout.MAX_SPEED, "cached_cells": f"{layout.CACHED_CELLS:,}", "plume_columns": layout.PLUME,
        "plume_rows": layout.PLUME_RUN, "mask_bits": tables.reactive.dtype.itemsize * 8, "own_mask_bits": layout.UNIQUE_BITS,
        "last_own_bit": layout.UNIQUE_BITS - 1, "handed_on_cost": kernel.HANDED_ON_COST, "fast_trial": kernel.FAST_TRIAL,
        "one_thread_below": layout.TILE * 2 * math.isqrt(threads.MIN_TILES_A_PASS),  # a pass's tiles are 2 apart
    }


def _elements(ruleset) -> dict[str, object]:
    """Figures of the bundled mods and of the rules their fields become."""
    from sandmod.formats import modspec
    from sandmod.rules import compiler
    from sandmod.rules.glow import GLOW_FROM

    spec = {e.id.split(":")[1]: e.spec for e in ruleset.elements}
    water, steam = spec["water"], spec["steam"]
    chance = lambda mover, fluid: f"{compiler.exchange_chance(spec[mover].density, spec[fluid].density, 1) / compiler.ALWAYS:.2f}"  # noqa: E731
    cooling = modspec._ElementBase.model_fields["cooling"]
    return {
        "glow_from": f"{GLOW_FROM:.0f}", "water_heat_capacity": _n(water.heat_capacity), "water_boils_at": _n(water.heated.above),
        "boiling_latent_heat": _n(water.heated.latent_heat), "steam_heat_capacity": _n(steam.heat_capacity),
        "steam_condenses_below": _n(steam.cooled.below), "water_boiling_holds": _n(water.heated.above * water.heat_capacity),
        "steam_condensing_holds": _n(steam.cooled.below * steam.heat_capacity),
        "steam_born_at": _n((water.heated.above * water.heat_capacity - water.heated.latent_heat) / steam.heat_capacity),
        "water_born_at": math.floor((steam.cooled.below * steam.heat_capacity + steam.cooled.latent_heat) / water.heat_capacity),  # "≈ 97"
        "lava_sets_below": _n(spec["lava"].cooled.below),
        "cooling_most": _n(next(rule.le for rule in cooling.metadata if getattr(rule, "le", None) is not None)),
        "eagerness": _n(compiler.EAGERNESS), "into_air": _n(compiler.INTO_AIR[0]),
        "exchange_most": f"{compiler.SURE_ENOUGH / compiler.ALWAYS:.2f}",
        "sand_into_water": chance("sand", "water"), "water_into_oil": chance("water", "oil"),
        "blast_max_radius": modspec.MAX_BLAST_RADIUS,
        **{f"resistance_{archetype}": _n(value) for archetype, value in compiler.DEFAULT_RESISTANCE.items()},
        "resistance_titanium": _n(spec["titanium"].explosion_resistance),
    }


def _limits() -> dict[str, object]:
    """What files, worlds, renders and sweeps may hold, and what memory they are estimated to take."""
    from sandmod.formats import limits, sweepspec, userfiles, worldspec
    from sandmod.jobs import render as render_job, session
    from sandmod.jobs.batch import sheet
    from sandmod.plugins import gif
    from sandmod.registry import collect, make_plugin_manager

    recorder = collect(make_plugin_manager(entry_points=False)).recorder_for
    cell = limits.WORLD_BYTES_PER_CELL + render_job.DRAWN_BYTES_PER_PIXEL  # a render at scale 1 draws a pixel a cell (as `bench --memory`)
    estimate = lambda side: f"{(limits.BASELINE_BYTES + cell * side**2) / 2**30:.3g}"  # noqa: E731
    refusal = re.search(r"about ([\d.]+) GB of memory, ([\d.]+) GB in all: more than the limit of ([\d.]+) GB",
                        limits.MemoryBudget().take(limits.WORLD_BYTES_PER_CELL * worldspec.MAX_SIZE**2, "a world"))
    render = worldspec.RenderSettings()
    return {
        "session_events": f"{session.MAX_EVENTS:,}", "session_bytes": f"{session.MAX_RECORD_BYTES:,}",
        "session_mb": f"{session.MAX_RECORD_BYTES / 2**20:.2f}", "world_file_mb": userfiles.MAX_TEXT_BYTES // 2**20,
        "max_frames": f"{worldspec.MAX_FRAMES:,}", "max_size": worldspec.MAX_SIZE,
        "heat_event_frames": worldspec._Heating.model_fields["frames"].default,
        **{f"render_{key}": _n(getattr(render, key)) for key in ("frames", "every", "fps", "scale", "loop")},
        "max_memory": f"{limits.DEFAULT_MAX_MEMORY // 2**30}G", "baseline_gb": _n(limits.BASELINE_BYTES / 2**30),
        "estimate_8192": estimate(8192), "estimate_largest": estimate(worldspec.MAX_SIZE),
        "largest_under_default": math.isqrt((limits.DEFAULT_MAX_MEMORY - limits.BASELINE_BYTES) // cell) // 500 * 500,
        "refusal_world": refusal.group(1), "refusal_total": refusal.group(2), "refusal_limit": refusal.group(3),
        "gif_max_side": f"{gif.MAX_SIDE:,}", "webp_max_side": f"{recorder(Path('x.webp')).max_side:,}",
        "apng_declared": recorder(Path("x.apng")).kept_bytes_per_pixel, "webp_declared": recorder(Path("x.webp")).kept_bytes_per_pixel,
        "sweep_max_runs": f"{sweepspec.MAX_RUNS:,}", "sheet_tile": sheet.TILE, "sheet_max_side": f"{sheet.MAX_SIDE:,}",
    }


def _play() -> dict[str, object]:
    from sandmod.formats import behaviour
    from sandmod.jobs import undo
    from sandmod.jobs.play import menu, view, window

    return {
        "play_steps_a_second": window.TICKS, "play_display_fps": window.DISPLAY_FPS, "play_capture_seconds": window.CAPTURE_SECONDS,
        "play_min_width": view.MIN_WIDTH, "play_menu_rows": view.ROWS, "play_favourites": menu.KEYED,
        "undo_depth": undo.UNDO_DEPTH, "undo_mb": undo.UNDO_MEMORY // 2**20, "undo_block": f"{undo.BLOCK}x{undo.BLOCK}",
        "behaviour_reach": behaviour.REACH,
    }


def _tools(ruleset) -> dict[str, object]:
    """What the developers' tools (bench.py, kernels.py) do by default."""
    import bench  # tools/dev/bench.py
    import kernels
    from packs import write_packs

    from sandmod.jobs import benchmark
    from sandmod.world.loading import load_ruleset

    packs = max(1, -(-(500 - len(ruleset.elements)) // 25))  # what `bench.py loaded --elements 500` writes
    with tempfile.TemporaryDirectory() as folder:
        write_packs(Path(folder), packs, 25)
        with_packs = len(load_ruleset(None, [Path(folder)]).elements)
    size = next(option.default for option in bench.in_turns.params if option.name == "size")
    turns = inspect.signature(kernels.compare_worlds).parameters
    return {
        "bench_size": size, "bench_steps": benchmark.scene_bench(ruleset, "mix", size).steps,
        "everything_elements": len(benchmark.EVERYTHING), "loaded_500_packs": packs, "loaded_500_elements": with_packs,
        "turns_segment": turns["segment"].default, "turns_repeats": turns["repeats"].default,
    }


def _examples() -> dict[str, object]:
    """Figures of the example worlds and sweeps."""
    from PIL import Image

    from sandmod.jobs.batch.plan import read_sweep

    read = lambda name: tomllib.loads((ROOT / "examples" / name).read_text(encoding="utf-8"))  # noqa: E731
    level, timeline = read("picture_level.toml"), read("timeline.toml")["timeline"]
    with Image.open(ROOT / "examples" / "level.png") as picture:
        width, height = picture.size
    with tempfile.TemporaryDirectory() as out:
        runs = {name: len(read_sweep(ROOT / path, Path(out) / name).runs)
                for name, path in (("friction", "docs/sweeps/friction.toml"), ("seeds", "examples/seeds.toml"))}
    return {
        "friction_runs": runs["friction"], "seeds_runs": runs["seeds"], "level_png": f"{width}x{height}",
        "level_world": f"{level['world']['width']}x{level['world']['height']}",
        "level_torch": next(event["frame"] for event in level["timeline"] if "heat" in event),
        **{f"timeline_{next(key for key in event if key != 'frame')}": event["frame"] for event in timeline},
        "timeline_heat_frames": next(event["heat"]["frames"] for event in timeline if "heat" in event),
    }


def main() -> None:
    for name, value in facts().items():
        print(f"{name}: {value}")


if __name__ == "__main__":
    main()
