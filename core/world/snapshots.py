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
import zlib
from pathlib import Path

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from ..errors import Problem, ProblemsError, display_path
from ..formats.userfiles import NO_SUCH_FILE, Refused, open_regular
from ..formats.worldspec import MAX_SIZE
from ..formats.recording import atomic_path, writing
from .world import State, World

#: Bumped when the layout changes; older files are refused with a clear message.
FORMAT = 1
#: Bytes of an .npy member besides its data (its header).
_NPY_HEADER = 4096
#: State arrays that hold element numbers, remapped by id on load.
ELEMENT_ARRAYS = ("cells", "carry")


def save_snapshot(world: World, path: Path) -> None:
    """Write ``world``'s state to ``path`` (atomically)."""
    with atomic_path(path) as tmp, writing(path):
        write_snapshot(world, tmp)


def write_snapshot(world: World, path: Path) -> None:
    """Write ``world``'s state to ``path`` as it is (see :func:`save_snapshot`)."""
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
    with open(path, "wb") as out:
        np.savez_compressed(out, meta=np.array(json.dumps(meta)), awake=world.awake, **arrays)


def load_snapshot(world: World, path: Path) -> list[str]:
    """Replace ``world``'s state, frame and seed by the snapshot's; returns warnings.

    ProblemsError (naming the file) if it is not a snapshot, was made for
    another size, or holds elements that no loaded mod defines.
    """
    name = display_path(path)

    def fail(message: str) -> ProblemsError:
        return ProblemsError([Problem(name, None, "", message)])

    expected = {n: getattr(world.state, n) for n in State._fields}
    expected["awake"] = world.awake
    try:
        meta, arrays = _read(path, expected)
    except Refused as exc:
        raise fail("no such snapshot file" if str(exc) == NO_SUCH_FILE else f"cannot read snapshot: {exc}") from None
    except _NotASnapshot as exc:
        why = f": {exc}" if str(exc) else " (write one with 'sandmod render --save-snapshot FILE.npz')"
        raise fail(f"not a sandmod snapshot{why}") from None
    if meta.format != FORMAT:
        raise fail(f"snapshot format {meta.format}; this sandmod reads format {FORMAT}")
    size = (meta.height, meta.width)
    if size != (world.height, world.width):
        raise fail(f"made for a {size[1]}x{size[0]} world; this world is {world.width}x{world.height}")
    for key, like in expected.items():
        got = arrays.get(key)
        # Element numbers are remapped below, so any unsigned width will do (older files' carry was uint8, and before that uint16).
        same_kind = got is not None and (got.dtype == like.dtype or (key in ELEMENT_ARRAYS and got.dtype.kind == "u"))
        if key == "awake" and got is None:
            continue  # older files: every chunk wakes
        if not same_kind or got.shape != like.shape:
            raise fail(f"its '{key}' array is missing or not {like.dtype} of {like.shape[1]}x{like.shape[0]}")
    ids: list[str] = meta.elements
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
        more = f" and {len(unknown) - 5} more" if len(unknown) > 5 else ""
        raise fail(f"holds {', '.join(unknown[:5])}{more}, which no loaded mod defines")
    state = world.state
    for key in State._fields:
        getattr(state, key)[...] = remap[arrays[key]] if key in ELEMENT_ARRAYS else arrays[key]
    state.carry[world.tables.remembers[state.cells] == 0] = 0  # what cells held under rules in which they no longer can
    _keep_temperatures(state, arrays.get("heat_cap"), world.tables.heat_cap, remap, used)
    world.frame, world.seed = meta.frame, meta.seed
    world._walker = None  # which chunks hold behaviour cells is not in a snapshot: found again from its cells
    world.wake()  # every chunk's marks start afresh: awake, and heat not known to be even
    if "awake" in arrays:
        world.awake[...] = arrays["awake"]  # the snapshot's own, so the run goes on as it would have
    return _mod_warnings(meta.mods, world)


class _Meta(BaseModel):
    """A snapshot's description, as it must be."""

    model_config = ConfigDict(strict=True)
    format: int
    frame: int = Field(ge=0, le=2**40)
    seed: int = Field(ge=0, le=2**32 - 1)
    width: int = Field(ge=1, le=MAX_SIZE)
    height: int = Field(ge=1, le=MAX_SIZE)
    elements: list[str] = Field(max_length=65536)
    mods: dict[str, str] = Field(default_factory=dict, max_length=4096)


class _NotASnapshot(Exception):
    """The file is not a snapshot this sandmod wrote; the message says what is wrong."""


def _read(path: Path, expected: dict[str, np.ndarray]) -> tuple[_Meta, dict[str, np.ndarray]]:
    """The snapshot's description and the arrays named in ``expected`` (and ``heat_cap``), each
    member's size checked before it is decompressed; Refused or _NotASnapshot when it cannot be."""
    with open_regular(path) as file:
        try:
            data = np.load(file, allow_pickle=False)
            if not isinstance(data, np.lib.npyio.NpzFile):  # a lone .npy array
                raise _NotASnapshot()
            with data:
                sizes = {info.filename.removesuffix(".npy"): info.file_size for info in data.zip.infolist()}
                limits = {key: like.size * (8 if key in ELEMENT_ARRAYS else like.itemsize) for key, like in expected.items()}
                limits.update(meta=2**24, heat_cap=8 * 65536)
                arrays = {}
                for key, limit in limits.items():
                    if key not in sizes:
                        continue
                    if sizes[key] > limit + _NPY_HEADER or _claimed_bytes(data.zip, key) > limit:
                        raise _NotASnapshot(f"its '{key}' member is larger than a {key} can be")
                    arrays[key] = data[key]
                    if not isinstance(arrays[key], np.ndarray):  # a member that is not an .npy array
                        raise _NotASnapshot()
        except _NotASnapshot:
            raise
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error, NotImplementedError) as exc:
            raise _NotASnapshot() from None
    try:
        meta = _Meta.model_validate(json.loads(str(arrays.pop("meta"))))
    except KeyError:
        raise _NotASnapshot() from None
    except RecursionError:
        raise _NotASnapshot("its description nests too deep") from None
    except (ValueError, ValidationError) as exc:  # ValueError: bad JSON
        raise _NotASnapshot(f"its description is wrong: {_first_error(exc)}") from None
    if meta.format == FORMAT and len(meta.elements) < 1:
        raise _NotASnapshot("its description lists no elements")
    return meta, arrays


def _claimed_bytes(archive: zipfile.ZipFile, key: str) -> int:
    """The bytes the .npy header of member ``key`` says its array holds, read before the array is:
    a small member may claim a huge shape, which numpy would allocate before reading a byte of it."""
    with archive.open(f"{key}.npy") as member:
        version = np.lib.format.read_magic(member)
        read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
        shape, _, dtype = read_header(member)
    return int(np.prod(shape, dtype=object)) * dtype.itemsize


def _first_error(exc: Exception) -> str:
    if isinstance(exc, ValidationError):
        err = exc.errors()[0]
        return f"{'.'.join(str(p) for p in err['loc'])}: {err['msg']}"
    return "not JSON"


def _keep_temperatures(state: State, old_caps, new_caps: np.ndarray, remap: np.ndarray, used: np.ndarray) -> None:
    """Rescale the heat of elements whose heat capacity a mod changed since, so their temperature stays."""
    if old_caps is None or old_caps.shape != remap.shape or old_caps.dtype.kind not in "iu" or (old_caps < 0).any():
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
