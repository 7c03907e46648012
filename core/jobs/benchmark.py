"""The scenes and the timing loop behind ``sandmod bench``.

Speed is million cell-updates a second: width x height x steps / seconds,
every cell counted whether its chunk is awake or asleep, so the figures
compare with other engines' and show what sleeping saves.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..rules.compiler import Ruleset
from ..world.world import World

#: Elements of the ``everything`` scene and their shares of the cells (the rest is empty).
EVERYTHING = {
    "sand": 12,
    "water": 12,
    "stone": 8,
    "lava": 5,
    "acid": 4,
    "oil": 4,
    "wood": 4,
    "coal": 3,
    "steam": 3,
    "ice": 3,
    "fire": 2,
    "gunpowder": 1,
}


def scene_hash(width: int, height: int) -> np.ndarray:
    """The mix scene's per-cell number 0..99 (the formula other engines' figures were measured with)."""
    y, x = np.mgrid[:height, :width].astype(np.uint64)
    h = (x * np.uint64(374761393) + y * np.uint64(668265263)) % np.uint64(2**32)
    h = ((h ^ (h >> np.uint64(13))) * np.uint64(1274126177)) % np.uint64(2**32)
    return (h % np.uint64(100)).astype(np.int64)


def _mix(world: World, ruleset: Ruleset, where: np.ndarray | None = None) -> None:
    r = scene_hash(world.width, world.height)
    inside = np.ones(r.shape, bool) if where is None else where
    world.paint(inside & (r < 25), ruleset.index("sand"))
    world.paint(inside & (r >= 25) & (r < 50), ruleset.index("water"))


def mix(world: World, ruleset: Ruleset) -> None:
    """A quarter sand, a quarter water, half empty, scattered by a fixed hash."""
    _mix(world, ruleset)


def halves(world: World, ruleset: Ruleset) -> None:
    """The top half sand, the bottom half water: every cell full, the sand sinks through."""
    top = np.arange(world.height)[:, None] < world.height // 2
    world.paint(np.broadcast_to(top, (world.height, world.width)), ruleset.index("sand"))
    world.paint(np.broadcast_to(~top, (world.height, world.width)), ruleset.index("water"))


PATCH = 512  # the side of the patch scene's busy square


def patch(world: World, ruleset: Ruleset) -> None:
    """The mix scene in a 512 x 512 box of stone in the middle, the rest empty: the same work at any size.

    In a 512 x 512 world the world's edges are the box.
    """
    y, x = np.mgrid[: world.height, : world.width]
    y0, x0 = (world.height - PATCH) // 2, (world.width - PATCH) // 2
    inside = (y >= y0) & (y < y0 + PATCH) & (x >= x0) & (x < x0 + PATCH)
    _mix(world, ruleset, inside)
    frame = (y >= y0 - 1) & (y <= y0 + PATCH) & (x >= x0 - 1) & (x <= x0 + PATCH) & ~inside
    world.paint(frame, ruleset.index("stone"))


def settled(world: World, ruleset: Ruleset) -> None:
    """A world at rest: full rows of sand under full rows of water under air. Stepped until all sleeps."""
    rows = np.broadcast_to(np.arange(world.height)[:, None], (world.height, world.width))
    world.paint(rows >= world.height * 3 // 4, ruleset.index("sand"))
    world.paint((rows >= world.height // 2) & (rows < world.height * 3 // 4), ruleset.index("water"))
    for _ in range(100):
        world.step()
        if world.awake_fraction == 0:
            break


def everything(world: World, ruleset: Ruleset) -> None:
    """Twelve elements scattered by the mix hash: reactions, lifetimes, heat, fire, steam, blasts."""
    r = scene_hash(world.width, world.height)
    start = 0
    for name, share in EVERYTHING.items():
        world.paint((r >= start) & (r < start + share), ruleset.index(name))
        start += share


SCENES: dict[str, Callable[[World, Ruleset], None]] = {
    "mix": mix,
    "halves": halves,
    "everything": everything,
    "settled": settled,
    "patch": patch,
}


class _Result:
    """A measurement that ``--json`` prints as one object."""

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Bench:
    """What a bench run steps: a built-in scene at a size, or a world file; ``make`` builds it afresh."""

    name: str  # the scene's name, or the world file as given
    width: int
    height: int
    steps: int  # how many to time unless told: 1000 for a scene, a world's own frames
    make: Callable[[], World]


def scene_bench(ruleset: Ruleset, scene: str, size: int, seed: int = 0) -> Bench:
    """The built-in ``scene`` in a size x size world of ``ruleset``."""

    def make() -> World:
        world = World(ruleset, size, size, seed)
        SCENES[scene](world, ruleset)
        return world

    return Bench(scene, size, size, 1000, make)


def world_bench(path: Path, *, mod_dirs: Sequence[Path] = (), seed: int | None = None) -> tuple[Bench, list[str]]:
    """A world file, as ``sandmod render`` would start it (its mods, scene, emitters and
    timeline), and the warnings about its mods. Raises ProblemsError for a bad file."""
    from ..errors import display_path
    from ..world.loading import load_world
    from ..world.scene import build_world

    loaded = load_world(path, mod_dirs=mod_dirs, seed=seed)

    def make() -> World:
        return build_world(loaded.spec, loaded.ruleset, loaded.source, seed)

    info = loaded.spec.world
    return Bench(display_path(path), info.width, info.height, loaded.spec.render.frames, make), [str(w) for w in loaded.warnings]


@dataclass(frozen=True)
class BenchResult(_Result):
    """One timed run; the JSON that ``sandmod bench --json`` prints."""

    scene: str
    width: int
    height: int
    steps: int
    threads: int | str  # a count, or "auto"
    sleep: bool  # chunks at rest skipped (False: every chunk updated every step)
    seconds: float
    steps_per_second: float
    mcell_updates_per_second: float
    awake_fraction: float  # the mean share of chunks updated a step
    compile_seconds: float  # the first step of a tiny world: compiling, or loading the cached kernels
    peak_memory_mb: float  # the process's peak resident memory
    state_bytes_per_cell: float  # the world's arrays, per-cell and per-chunk, over its cells


def peak_memory_mb() -> float:
    """The process's peak resident set size (on Windows, its peak working set) in MiB.

    On Linux, ``VmHWM`` of /proc/self/status: ``ru_maxrss`` keeps the peak of the process that
    started this one across the exec (a render started from a 500 MB test run read 525 MB)."""
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError), open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 2**10  # kB
    try:
        import resource
    except ImportError:  # Windows
        return _peak_working_set() / 2**20
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 2**10  # bytes on macOS, KiB elsewhere


def _peak_working_set() -> int:
    """Windows: the process's peak working set in bytes (GetProcessMemoryInfo)."""
    import ctypes
    from ctypes import wintypes

    class Counters(ctypes.Structure):  # PROCESS_MEMORY_COUNTERS
        _fields_ = [("cb", wintypes.DWORD), ("PageFaultCount", wintypes.DWORD)] + [
            (name, ctypes.c_size_t)
            for name in (
                "PeakWorkingSetSize", "WorkingSetSize", "QuotaPeakPagedPoolUsage", "QuotaPagedPoolUsage",
                "QuotaPeakNonPagedPoolUsage", "QuotaNonPagedPoolUsage", "PagefileUsage", "PeakPagefileUsage",
            )
        ]  # fmt: skip

    counters = Counters(cb=ctypes.sizeof(Counters))
    process = ctypes.windll.kernel32.GetCurrentProcess()
    if not ctypes.windll.psapi.GetProcessMemoryInfo(process, ctypes.byref(counters), counters.cb):
        return 0
    return counters.PeakWorkingSetSize


#: The world ``render_peak_memory`` renders: a disc of sand above a pool of water on a stone floor.
MEMORY_WORLD = """
[world]
width = {size}
height = {size}
mods = ["sand", "water"]

[[scene]]
shape = "rect"
element = "stone"
x = 0
y = {floor}
width = {size}
height = 4

[[scene]]
shape = "rect"
element = "water"
x = 0
y = {water}
width = {size}
height = {quarter}

[[scene]]
shape = "circle"
element = "sand"
x = {half}
y = {quarter}
radius = {radius}
"""


@dataclass(frozen=True)
class MemoryResult(_Result):
    """The peak memory of a render, measured in a process of its own, and what sandmod estimates first."""

    width: int
    height: int
    frames: int
    format: str
    peak_mb: float
    estimate_mb: float


def render_peak_memory(size: int, frames: int = 4, output_format: str = "gif") -> MemoryResult:
    """Render a ``size`` x ``size`` world for ``frames`` frames (an image each, one pixel a cell) in a
    fresh process and return its peak resident memory beside the estimate the memory limit checks."""
    import subprocess
    import tempfile

    from ..formats.limits import MemoryBudget
    from ..world.loading import read_world_spec

    with tempfile.TemporaryDirectory() as folder:
        world = Path(folder) / "w.toml"
        quarter = size // 4
        world.write_text(
            MEMORY_WORLD.format(size=size, floor=size - 4, water=size - 4 - quarter, quarter=quarter, half=size // 2, radius=size // 8)
        )
        output = Path(folder) / f"out.{output_format}"
        args = ["render", str(world), "-o", str(output), "--frames", str(frames), "--every", "1", "--scale", "1", "-q", "--max-memory", "none"]
        code = (
            "import sys; from sandmod.jobs import benchmark; from sandmod.tools.cli import cli\n"
            f"try:\n    cli({args!r}, prog_name='sandmod')\nexcept SystemExit as end:\n    assert not end.code, end.code\n"
            "print(benchmark.peak_memory_mb())"
        )
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        spec, _ = read_world_spec(world)
    from ..formats.limits import WORLD_BYTES_PER_CELL
    from .render import DRAWN_BYTES_PER_PIXEL

    budget = MemoryBudget(None)
    budget.take(spec.world.width * spec.world.height * WORLD_BYTES_PER_CELL, "the world")
    budget.take(DRAWN_BYTES_PER_PIXEL * size * size, "the frame")  # as a render's check takes it (render.kept_bytes; a GIF keeps none)
    return MemoryResult(size, size, frames, output_format, round(float(done.stdout.split()[-1]), 1), round(budget.used / 2**20, 1))


def state_bytes(world: World) -> int:
    """Bytes of everything a world keeps between steps: its cells and its chunks' bookkeeping."""
    chunks = (world.awake, world._woken, world._even, world._stirred, world._detonations, world._fast_gain, world._seen)
    return sum(a.nbytes for a in world.state) + sum((a if a.base is None else a.base).nbytes for a in chunks)


def run(bench: Bench, steps: int, threads: int | None, *, sleep: bool = True, compile_seconds: float = 0.0) -> BenchResult:
    """Build ``bench``'s world and time ``steps`` steps on ``threads`` threads (None: as many as pay)."""
    world = bench.make()
    world.threads = threads
    awake = 0.0
    started = time.perf_counter()
    for _ in range(steps):
        if not sleep:
            world.wake()
        awake += world.awake_fraction
        world.step()
    seconds = time.perf_counter() - started
    return BenchResult(
        scene=bench.name,
        width=world.width,
        height=world.height,
        steps=steps,
        threads=AUTO if threads is None else threads,
        sleep=sleep,
        seconds=round(seconds, 4),
        steps_per_second=round(steps / seconds, 2),
        mcell_updates_per_second=round(world.width * world.height * steps / seconds / 1e6, 1),
        awake_fraction=round(awake / steps, 4),
        compile_seconds=round(compile_seconds, 3),
        peak_memory_mb=round(peak_memory_mb(), 1),
        state_bytes_per_cell=round(state_bytes(world) / (world.width * world.height), 4),
    )


def state_digest(world: World) -> str:
    """A digest of every cell's state (not the chunks' marks, which one kernel may set wider than another):
    two runs that end with the same one reached the same frames."""
    return hashlib.sha1(b"".join(a.tobytes() for a in world.state)).hexdigest()


def numpy_image(world: World) -> np.ndarray:
    """:meth:`World.image` in numpy, as it was before the compiled one: the slow, obvious reference
    that tests hold the compiled pixels to, and that ``sandmod bench --pixels`` times them against."""
    from ..rules.compiler import GLOW_COLOURS, GLOW_FROM, GLOW_STEP, temperature_units
    from ..engine.layout import SCORCHED

    looks, s = world.ruleset.looks, world.state
    shown = world.shown()
    shade = s.shade.astype(np.uint16)
    frame = looks.normal[shown, (shade * looks.shades) >> 8]
    scorched = (s.flags & SCORCHED) != 0
    if scorched.any():
        frame[scorched] = looks.scorched[shown[scorched], (shade[scorched] * looks.scorched.shape[1]) >> 8]
    if int(s.heat.max()) >= temperature_units(GLOW_FROM):  # cheap test first: heat >= temperature
        units = world._temperature_units()
        start = looks.glow_from[shown]
        hot = (units > start) & (shown != 0)
        if hot.any():
            level = np.minimum((units[hot] - start[hot]) // temperature_units(GLOW_STEP), len(GLOW_COLOURS) - 1)
            frame[hot] = looks.glow[shown[hot], level]
    return frame


@dataclass(frozen=True)
class PixelsResult(_Result):
    """A frame to colour indices, compiled and in numpy (``sandmod bench --pixels``)."""

    scene: str
    width: int
    height: int
    compiled_ms: float
    numpy_ms: float


def time_pixels(bench: Bench, steps: int, repeats: int = 5) -> tuple[float, float]:
    """Milliseconds a frame of ``bench``'s world takes to become colour indices: compiled
    (:meth:`World.image`) and in numpy (:func:`numpy_image`), each the best of ``repeats``
    timings taken in turns, after ``steps`` steps (so that there is heat and motion)."""
    world = bench.make()
    world.threads = 1
    for _ in range(steps):
        world.step()
    out = np.empty((world.height, world.width), np.uint16)
    world.image(out)  # compile, or load from the cache
    best = [float("inf"), float("inf")]
    for _ in range(repeats):
        for k, draw in enumerate((lambda: world.image(out), lambda: numpy_image(world))):
            began = time.perf_counter()
            draw()
            best[k] = min(best[k], time.perf_counter() - began)
    return best[0] * 1000, best[1] * 1000


@contextlib.contextmanager
def busy_processes(count: int):
    """Keep ``count`` other processes busy (each spinning on a core) while the block runs."""
    spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]
    try:
        yield
    finally:
        for spinner in spinners:
            spinner.kill()
            spinner.wait()


#: How results name the thread count a world chooses as it steps (``--threads auto``).
AUTO = "auto"


def max_threads() -> int:
    """How many threads the kernel may use in this process (``NUMBA_NUM_THREADS``, else the CPUs)."""
    return int(os.environ.get("NUMBA_NUM_THREADS") or os.cpu_count() or 1)


@dataclass(frozen=True)
class RecordResult(_Result):
    """One timed render: how the time splits between the kernel, building images and encoding them."""

    format: str
    scene: str
    width: int
    height: int
    images: int  # one image a step, at one pixel a cell
    threads: int | str  # a count, or "auto"
    step_seconds: float
    image_seconds: float  # colour index frames from the world's state (colours, shades, scorch, glow)
    encode_seconds: float  # the recorder: add_frame for each, then close (compressing, writing)
    images_per_second: float  # encoding alone
    encode_share: float  # of the whole render's time
    file_mb: float


def record(bench: Bench, recorder, images: int, threads: int, folder) -> RecordResult:
    """Render ``images`` steps of ``bench``'s world with ``recorder`` into ``folder``, timing each part."""
    from ..formats.recording import VideoSettings, output_bytes

    world = bench.make()
    world.threads = threads
    output = Path(folder) / f"bench-{recorder.name}{recorder.extensions[0] if recorder.extensions else ''}"
    if recorder.folder:
        output.mkdir()
    out = recorder.open(output, VideoSettings(world.width, world.height, world.ruleset.colours, 25))
    step = image = encode = 0.0
    for _ in range(images):
        t0 = time.perf_counter()
        world.step()
        t1 = time.perf_counter()
        frame = world.image()
        t2 = time.perf_counter()
        out.add_frame(frame)
        step, image, encode = step + t1 - t0, image + t2 - t1, encode + time.perf_counter() - t2
    t3 = time.perf_counter()
    out.close()
    encode += time.perf_counter() - t3
    written = output_bytes(output)
    return RecordResult(
        format=recorder.name,
        scene=bench.name,
        width=world.width,
        height=world.height,
        images=images,
        threads=threads,
        step_seconds=round(step, 4),
        image_seconds=round(image, 4),
        encode_seconds=round(encode, 4),
        images_per_second=round(images / encode, 1),
        encode_share=round(encode / (step + image + encode), 3),
        file_mb=round(written / 1e6, 2),
    )
