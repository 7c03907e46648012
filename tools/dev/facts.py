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


def facts() -> dict[str, object]:
    """Each figure's name and value, read from the code at the time of asking."""
    import bench  # tools/dev/bench.py
    import kernels  # tools/dev/kernels.py
    import numpy as np
    from packs import write_packs  # tools/dev/packs.py
    from PIL import Image

    from sandmod.engine import layout, threads
    from sandmod.formats import behaviour, limits, modspec, sweepspec, userfiles, worldspec
    from sandmod.jobs import benchmark, session, undo
    from sandmod.jobs.batch import sheet
    from sandmod.jobs.batch.plan import read_sweep
    from sandmod.jobs.play import menu, view, window
    from sandmod.plugins import gif
    from sandmod.registry import collect, make_plugin_manager
    from sandmod.engine import kernel as kernel_constants
    from sandmod.rules import compiler
    from sandmod.rules.compiler import DEFAULT_RESISTANCE
    from sandmod.rules.colours import GLOW_COLOURS, SCORCHED_SHADES, SHADES
    from sandmod.rules.glow import GLOW_FROM
    from sandmod.world.loading import load_ruleset
    from sandmod.world.world import World

    ruleset = load_ruleset()  # every bundled mod
    recorder_for = collect(make_plugin_manager(entry_points=False)).recorder_for
    spec = {e.id.split(":")[1]: e.spec for e in ruleset.elements}
    water, steam = spec["water"], spec["steam"]
    steam_holds = (water.heated.above * water.heat_capacity - water.heated.latent_heat) / steam.heat_capacity
    water_holds = (steam.cooled.below * steam.heat_capacity + steam.cooled.latent_heat) / water.heat_capacity
    packs = max(1, -(-(500 - len(ruleset.elements)) // 25))  # what `bench.py loaded --elements 500` writes
    with tempfile.TemporaryDirectory() as folder:
        write_packs(Path(folder), packs, 25)
        with_packs = len(load_ruleset(None, [Path(folder)]).elements)
    colours = SHADES + SCORCHED_SHADES + len(GLOW_COLOURS)
    world = World(ruleset, 1024, 1024)
    chunks, tiles = (1024 // layout.CHUNK) ** 2, (1024 // layout.TILE) ** 2
    whole = lambda a: a if a.base is None else a.base  # noqa: E731 (as benchmark.state_bytes counts them)
    per_chunk = sum(whole(a).nbytes for a in (world.awake, world._woken, world._even, world._stirred)) // chunks
    per_tile = sum(a.nbytes for a in (world._detonations, world._fast_gain, world._seen)) // tiles
    render = worldspec.RenderSettings()
    tables, n = ruleset.tables, len(ruleset.elements)
    pair_tables = [a for a in tables._asdict().values() if isinstance(a, np.ndarray) and a.shape[:2] == (n, n)]
    density = {name: getattr(s, "density", None) for name, s in spec.items()}
    bench_size = next(option.default for option in bench.in_turns.params if option.name == "size")
    segment = inspect.signature(kernels.compare_worlds).parameters
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    with tempfile.TemporaryDirectory() as out:
        sweep_runs = {name: len(read_sweep(ROOT / path, Path(out) / name).runs)
                      for name, path in (("friction", "docs/sweeps/friction.toml"), ("seeds", "examples/seeds.toml"))}
    picture_level = tomllib.loads((ROOT / "examples" / "picture_level.toml").read_text(encoding="utf-8"))
    level = picture_level["world"]
    with Image.open(ROOT / "examples" / "level.png") as picture:
        level_png = picture.size
    timeline = tomllib.loads((ROOT / "examples" / "timeline.toml").read_text(encoding="utf-8"))["timeline"]
    cell_bytes = limits.WORLD_BYTES_PER_CELL + 4  # a render at scale 1 draws a 4-byte pixel a cell (`bench --memory`)
    refusal = re.search(r"about ([\d.]+) GB of memory, ([\d.]+) GB in all: more than the limit of ([\d.]+) GB",
                        limits.MemoryBudget().take(limits.WORLD_BYTES_PER_CELL * worldspec.MAX_SIZE**2, "a world"))
    return {
        "python_min": pyproject["requires-python"].removeprefix(">="),
        "numba_min": next(d for d in pyproject["dependencies"] if d.startswith("numba")).split(">=")[1],
        "max_elements": f"{layout.MAX_ELEMENTS:,}",
        "colours_per_element": colours,
        "colours_max": f"{colours * layout.MAX_ELEMENTS:,}",
        "bench_size": bench_size,
        "bench_steps": benchmark.scene_bench(ruleset, "mix", bench_size).steps,
        "everything_elements": len(benchmark.EVERYTHING),
        "loaded_500_packs": packs,
        "loaded_500_elements": with_packs,
        "cell_bytes": sum(a.nbytes for a in world.state) // (1024 * 1024),
        "chunk_bytes": per_chunk,
        "tile_words": per_tile // 8,
        "pair_bytes": sum(a.nbytes for a in pair_tables) // n**2,
        "bytes_per_cell": f"{benchmark.state_bytes(world) / (1024 * 1024):.2f}",
        "chunk": layout.CHUNK,
        "tile": layout.TILE,
        "wake_margin": layout.WAKE_MARGIN,
        "reach": layout.REACH,
        "max_speed": layout.MAX_SPEED,
        "cached_cells": f"{layout.CACHED_CELLS:,}",
        "plume_columns": layout.PLUME,
        "plume_rows": layout.PLUME_RUN,
        "mask_bits": tables.reactive.dtype.itemsize * 8,
        "own_mask_bits": layout.UNIQUE_BITS,
        "last_own_bit": layout.UNIQUE_BITS - 1,
        "eagerness": f"{compiler.EAGERNESS:.15g}",
        "into_air": f"{compiler.INTO_AIR[0]:.15g}",
        "exchange_most": f"{compiler.SURE_ENOUGH / compiler.ALWAYS:.2f}",
        "sand_into_water": f"{compiler.exchange_chance(density['sand'], density['water'], 1) / compiler.ALWAYS:.2f}",
        "water_into_oil": f"{compiler.exchange_chance(density['water'], density['oil'], 1) / compiler.ALWAYS:.2f}",
        "handed_on_cost": kernel_constants.HANDED_ON_COST,
        "fast_trial": kernel_constants.FAST_TRIAL,
        "turns_segment": segment["segment"].default,
        "turns_repeats": segment["repeats"].default,
        "apng_declared": recorder_for(Path("x.apng")).kept_bytes_per_pixel,
        "webp_declared": recorder_for(Path("x.webp")).kept_bytes_per_pixel,
        "behaviour_reach": behaviour.REACH,
        "glow_from": f"{GLOW_FROM:.0f}",
        "water_heat_capacity": f"{water.heat_capacity:.15g}",
        "water_boils_at": f"{water.heated.above:.15g}",
        "boiling_latent_heat": f"{water.heated.latent_heat:.15g}",
        "steam_heat_capacity": f"{steam.heat_capacity:.15g}",
        "steam_condenses_below": f"{steam.cooled.below:.15g}",
        "water_boiling_holds": f"{water.heated.above * water.heat_capacity:.15g}",
        "steam_condensing_holds": f"{steam.cooled.below * steam.heat_capacity:.15g}",
        "steam_born_at": f"{steam_holds:.15g}",
        "water_born_at": f"{math.floor(water_holds):.15g}",  # the page says "≈ 97"
        "lava_sets_below": f"{spec['lava'].cooled.below:.15g}",
        "undo_depth": undo.UNDO_DEPTH,
        "undo_mb": undo.UNDO_MEMORY // 2**20,
        "undo_million_cells": round(undo.UNDO_MEMORY / (sum(a.nbytes for a in world.state) / world.width / world.height) / 1e6),
        "undo_block": f"{undo.BLOCK}x{undo.BLOCK}",
        "session_events": f"{session.MAX_EVENTS:,}",
        "session_bytes": f"{session.MAX_RECORD_BYTES:,}",
        "session_mb": f"{session.MAX_RECORD_BYTES / 2**20:.2f}",
        "world_file_mb": userfiles.MAX_TEXT_BYTES // 2**20,
        "max_frames": f"{worldspec.MAX_FRAMES:,}",
        "play_steps_a_second": window.TICKS,
        "play_display_fps": window.DISPLAY_FPS,
        "play_capture_seconds": window.CAPTURE_SECONDS,
        "play_min_width": view.MIN_WIDTH,
        "play_menu_rows": view.ROWS,
        "play_favourites": menu.KEYED,
        "blast_max_radius": modspec.MAX_BLAST_RADIUS,
        **{f"resistance_{archetype}": f"{value:.15g}" for archetype, value in DEFAULT_RESISTANCE.items()},
        "resistance_titanium": f"{spec['titanium'].explosion_resistance:.15g}",
        "max_size": worldspec.MAX_SIZE,
        "estimate_8192": f"{(limits.BASELINE_BYTES + cell_bytes * 8192**2) / 2**30:.3g}",
        "estimate_largest": f"{(limits.BASELINE_BYTES + cell_bytes * worldspec.MAX_SIZE**2) / 2**30:.3g}",
        "largest_under_default": math.isqrt((limits.DEFAULT_MAX_MEMORY - limits.BASELINE_BYTES) // cell_bytes) // 500 * 500,
        "refusal_world": refusal.group(1),
        "refusal_total": refusal.group(2),
        "refusal_limit": refusal.group(3),
        **{f"render_{key}": f"{getattr(render, key):.15g}" for key in ("frames", "every", "fps", "scale", "loop")},
        "baseline_gb": f"{limits.BASELINE_BYTES / 2**30:.15g}",
        "heat_event_frames": worldspec._Heating.model_fields["frames"].default,
        "cooling_most": f"{_most(modspec._ElementBase.model_fields['cooling']):.15g}",
        "max_memory": f"{limits.DEFAULT_MAX_MEMORY // 2**30}G",
        "gif_max_side": f"{gif.MAX_SIDE:,}",
        "webp_max_side": f"{recorder_for(Path('x.webp')).max_side:,}",
        "one_thread_below": layout.TILE * 2 * math.isqrt(threads.MIN_TILES_A_PASS),  # a pass's tiles, 2 apart
        "sweep_max_runs": f"{sweepspec.MAX_RUNS:,}",
        "sheet_tile": sheet.TILE,
        "sheet_max_side": f"{sheet.MAX_SIDE:,}",
        "friction_runs": sweep_runs["friction"],
        "seeds_runs": sweep_runs["seeds"],
        "level_png": f"{level_png[0]}x{level_png[1]}",
        "level_world": f"{level['width']}x{level['height']}",
        "level_torch": next(event["frame"] for event in picture_level["timeline"] if "heat" in event),
        **{f"timeline_{next(k for k in event if k != 'frame')}": event["frame"] for event in timeline},
        "timeline_heat_frames": next(event["heat"]["frames"] for event in timeline if "heat" in event),
    }


def _most(field) -> float:
    """A pydantic field's upper bound."""
    return next(rule.le for rule in field.metadata if getattr(rule, "le", None) is not None)


def main() -> None:
    for name, value in facts().items():
        print(f"{name}: {value}")


if __name__ == "__main__":
    main()
