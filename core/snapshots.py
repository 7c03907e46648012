"""Snapshots: a world's whole state in one ``.npz`` file, and back.

A snapshot holds every per-cell array, the frame number, the seed, which
chunks are awake, and the mods (with versions) it was made with. Cells are
stored by element id (``sand:sand``) rather than by number, so a snapshot loads
under a ruleset with other unrelated mods added or removed. Loading one and
stepping on gives exactly the frames an uninterrupted run would have given.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from .errors import Problem, ProblemsError, display_path
from .recording import atomic_path
from .world import State, World

#: Bumped when the layout changes; older files are refused with a clear message.
FORMAT = 1
#: State arrays that hold element numbers, remapped by id on load.
ELEMENT_ARRAYS = ("cells", "carry")


def save_snapshot(world: World, path: Path) -> None:
    """Write ``world``'s state to ``path`` (atomically)."""
    ruleset = world.ruleset
    meta = {
        "format": FORMAT,
        "frame": world.frame,
        "seed": world.seed,
        "width": world.width,
        "height": world.height,
        "elements": [e.id for e in ruleset.elements],
        "mods": {m.name: m.spec.mod.version for m in ruleset.mods},
    }
    arrays = {name: getattr(world.state, name) for name in State._fields}
    arrays["heat_cap"] = world.tables.heat_cap  # to keep temperatures if a mod changes an element's
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as out:
            np.savez_compressed(out, meta=np.array(json.dumps(meta)), awake=world.awake, **arrays)


def load_snapshot(world: World, path: Path) -> list[str]:
    """Replace ``world``'s state, frame and seed by the snapshot's; returns warnings.

    ProblemsError (naming the file) if it is not a snapshot, was made for
    another size, or holds elements that no loaded mod defines.
    """
    name = display_path(path)

    def fail(message: str) -> ProblemsError:
        return ProblemsError([Problem(name, None, "", message)])

    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            arrays = {key: data[key] for key in data.files if key != "meta"}
    except FileNotFoundError:
        raise fail("no such snapshot file") from None
    except (OSError, ValueError, KeyError, zipfile.BadZipFile):  # ValueError covers bad JSON
        raise fail("not a sandmod snapshot (write one with 'sandmod render --save-snapshot FILE.npz')") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise fail(f"snapshot format {meta.get('format') if isinstance(meta, dict) else '?'}; this sandmod reads format {FORMAT}")
    missing = [key for key in ("frame", "seed", "width", "height", "elements") if key not in meta]
    if missing:
        raise fail(f"its description lacks {', '.join(missing)}")
    size = (meta["height"], meta["width"])
    if size != (world.height, world.width):
        raise fail(f"made for a {size[1]}x{size[0]} world; this world is {world.width}x{world.height}")
    expected = {n: getattr(world.state, n) for n in State._fields}
    for key, like in expected.items():
        got = arrays.get(key)
        # Element numbers are remapped below, so any unsigned width will do (older files' carry was uint16).
        same_kind = got is not None and (got.dtype == like.dtype or (key in ELEMENT_ARRAYS and got.dtype.kind == "u"))
        if not same_kind or got.shape != like.shape:
            raise fail(f"its '{key}' array is missing or not {like.dtype} of {like.shape[1]}x{like.shape[0]}")
    ids: list[str] = meta["elements"]
    used = np.zeros(len(ids), bool)
    for key in ELEMENT_ARRAYS:
        if int(arrays[key].max(initial=0)) >= len(ids):
            raise fail(f"its '{key}' array holds element numbers past its list of {len(ids)} elements")
        used[np.unique(arrays[key])] = True
    remap = np.zeros(len(ids), np.int64)  # snapshot's element number -> this ruleset's
    unknown = []
    for number, element_id in enumerate(ids):
        try:
            remap[number] = world.ruleset.index(element_id)
        except KeyError:
            if used[number]:
                unknown.append(element_id)
    if unknown:
        raise fail(f"holds {', '.join(unknown)}, which no loaded mod defines")
    state = world.state
    for key in State._fields:
        getattr(state, key)[...] = remap[arrays[key]] if key in ELEMENT_ARRAYS else arrays[key]
    _keep_temperatures(state, arrays.get("heat_cap"), world.tables.heat_cap, remap, used)
    world.frame, world.seed = int(meta["frame"]), int(meta["seed"])
    world.wake()  # every chunk's marks start afresh: awake, and heat not known to be even
    awake = arrays.get("awake")
    if awake is not None and awake.shape == world.awake.shape:
        world.awake[...] = awake  # the snapshot's own, so the run goes on as it would have
    return _mod_warnings(meta.get("mods", {}), world)


def _keep_temperatures(state: State, old_caps, new_caps: np.ndarray, remap: np.ndarray, used: np.ndarray) -> None:
    """Rescale the heat of elements whose heat capacity a mod changed since, so their temperature stays."""
    if old_caps is None or len(old_caps) != len(remap):
        return
    for number in np.flatnonzero(used):
        old, new = int(old_caps[number]), int(new_caps[remap[number]])
        if old != new and old > 0:
            cells = state.cells == remap[number]
            state.heat[cells] = np.round(state.heat[cells].astype(np.int64) * new / old).astype(np.int32)


def _mod_warnings(recorded: dict[str, str], world: World) -> list[str]:
    loaded = {m.name: m.spec.mod.version for m in world.ruleset.mods}
    warnings = [f"snapshot made with mod {n} {v}; loading {n} {loaded[n]}" for n, v in recorded.items() if n in loaded and loaded[n] != v]
    warnings += [f"snapshot made with mod {n} {v}, which is not loaded now" for n, v in recorded.items() if n not in loaded]
    return warnings
