"""The state of a world: a few numpy arrays, painted by shapes and stepped by the kernel.

Per cell (16 bytes): the element (uint16: a ruleset has at most 4,096), a
shade (uint8, picked at birth, travels with the cell), a timer (uint16:
lifetime left, or burning time left), flags (uint8: moved this frame, reacted,
loose, burning, scorched), a velocity (two int16, in 1/256ths of a cell per
frame), for flying particles the element carried (uint16), and its heat
(int32: heat capacity x temperature, so that conduction conserves it exactly). Building
and painting a world needs no numba; stepping it does.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path
from time import perf_counter
from typing import Any, Callable, Mapping, NamedTuple

import numpy as np

from ..rules.compiler import (
    ARCHETYPE_CODES,
    GLOW_STEP,
    SUBCELL,
    TEMP_ONE,
    Ruleset,
    Tables,
    blast_row,
    temperature_units,
)
from ..engine.layout import CACHE_LINE, CHUNK, CHUNK_SHIFT, LOOSE, MAX_SPEED, TILE, WAKE_MARGIN, WHOLE
from ..formats.modspec import Explosion
from ..engine.threads import Chooser
from ..engine.threads import available as threads_available
from ..engine.hashing import (
    ROLL_BITS,
    SALT_MOVE,
    SALT_PAINT,
    SALT_REACT,
    SALT_SPAWN,
    SALT_SPRAY,
    SALT_BLAST,
    SALT_LAUNCH,
    SALT_TIMELINE,
    cell_hash,
    chance_threshold,
    frame_key,
    mix32,
    spawn_state,
)

Switches = tuple[tuple[int, bool], ...]  # (frame, on) pairs from a timeline's start and stop events


def _on(start: int, stop: int | None, frame: int, switches: Switches = ()) -> bool:
    """Is a source on at ``frame``? It runs from ``start`` until before ``stop`` (never ending if
    None), and each (frame, on) switch turns it on or off from that frame; a switch on the
    same frame as ``start`` or ``stop`` comes after them."""
    own = [(start, True)] + ([] if stop is None else [(stop, False)])
    on = False
    for at, turn_on in sorted(own + list(switches), key=lambda switch: switch[0]):  # stable: own first
        if at <= frame:
            on = turn_on
    return on


class State(NamedTuple):
    """The per-cell arrays the kernel updates, each (height, width)."""

    cells: np.ndarray  # uint16: element id
    shade: np.ndarray  # uint8: colour variation, travels with the cell
    timer: np.ndarray  # uint16: frames of lifetime left, or of burning while BURNING
    flags: np.ndarray  # uint8: kernel flags
    vx: np.ndarray  # int16: velocity, 1/256ths of a cell per frame, right positive
    vy: np.ndarray  # int16: velocity, down positive
    carry: np.ndarray  # uint16: what a flying particle carries, or a cell holds (0: nothing)
    heat: np.ndarray  # int32: heat energy, heat_cap x temperature (fixed point, see compiler)


@dataclass(frozen=True)
class Emitter:
    """Pours ``element`` into the empty ones of its cells while start <= frame < stop."""

    ys: np.ndarray  # the rows and columns of the emitter's cells
    xs: np.ndarray
    element: int
    start: int
    stop: int | None
    chance: float
    switches: Switches = ()

    def active(self, frame: int) -> bool:
        return _on(self.start, self.stop, frame, self.switches)


@dataclass(frozen=True)
class Spray:
    """Shoots ``rate`` particles a frame from empty cells among its own, while start <= frame < stop.

    Each particle leaves at an angle within ``spread`` degrees around
    ``direction`` (0 = right, 90 = up) and a speed between ``speeds``.
    """

    ys: np.ndarray
    xs: np.ndarray
    element: int  # what is sprayed (a particle element, or any element to fly as a particle)
    direction: float
    spread: float
    speeds: tuple[float, float]
    rate: float
    start: int
    stop: int | None
    number: int  # which spray of the world, for independent randomness
    switches: Switches = ()

    def active(self, frame: int) -> bool:
        return _on(self.start, self.stop, frame, self.switches)

    def shots(self, seed: int, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The cells and velocities (cells/frame) of this frame's particles, each from a different cell."""
        key = frame_key(seed, frame, SALT_SPRAY + self.number)
        whole = int(self.rate)
        count = whole + (int(mix32(key) >> (32 - ROLL_BITS)) < chance_threshold(self.rate - whole))
        order = cell_hash(key, self.xs.astype(np.uint64), self.ys.astype(np.uint64))
        picks = np.argsort(order, kind="stable")[:count]  # distinct cells, in a hashed order
        parts = np.arange(1, 3 * len(picks) + 1, dtype=np.uint64)  # particle j's three rolls: hashes of 3j+1 to 3j+3
        rolls = (mix32(key ^ mix32(parts)) / 2**32).reshape(-1, 3).tolist()
        angles = [math.radians(self.direction + (r[1] - 0.5) * self.spread) for r in rolls]
        speeds = [self.speeds[0] + r[2] * (self.speeds[1] - self.speeds[0]) for r in rolls]
        vx = np.array([s * math.cos(a) for a, s in zip(angles, speeds)])
        vy = np.array([-s * math.sin(a) for a, s in zip(angles, speeds)])
        return self.ys[picks], self.xs[picks], vx, vy


@dataclass(frozen=True)
class Painting:
    """A timeline event that paints (or erases) on its frame, before the step.

    ``layer`` gives, for the world's cells at that moment, the element each
    cell becomes (-1: left alone); a fill needs to see the world as it is then.
    """

    frame: int
    layer: Callable[[np.ndarray], np.ndarray]
    celsius: float | None  # painted cells' temperature (None: each element's own)
    number: int  # which event of the timeline, for independent randomness


@dataclass(frozen=True)
class Launcher:
    """Sends the cells ``area`` gives flying on ``frame``, before the step: each non-empty cell becomes a
    particle carrying its element, at an angle within ``spread`` degrees around ``direction`` (0 = right,
    90 = up) and a speed between ``speeds``, rolled per cell."""

    frame: int
    area: Callable[[np.ndarray], np.ndarray]  # the world's cells -> a boolean mask
    direction: float
    spread: float
    speeds: tuple[float, float]
    number: int  # which event of the timeline, for independent randomness

    def velocities(self, seed: int, ys: np.ndarray, xs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each cell's velocity, in cells per frame."""
        key = frame_key(seed, self.frame, SALT_LAUNCH + self.number)
        xs, ys = xs.astype(np.uint64), ys.astype(np.uint64)
        angle = np.radians(self.direction + (cell_hash(key, xs, ys) / 2**32 - 0.5) * self.spread)
        speed = self.speeds[0] + cell_hash(mix32(key), xs, ys) / 2**32 * (self.speeds[1] - self.speeds[0])
        return speed * np.cos(angle), -speed * np.sin(angle)


@dataclass(frozen=True)
class Heater:
    """Sets the cells ``area`` gives to ``celsius`` degrees before each step from ``start`` until before ``stop``."""

    area: Callable[[np.ndarray], np.ndarray]  # the world's cells -> a boolean mask
    celsius: float
    start: int
    stop: int

    def active(self, frame: int) -> bool:
        return self.start <= frame < self.stop


#: Cells painted at once from a mask (the rest band by band), so painting a whole world takes little memory.
PAINT_BAND = 1 << 18

_AT_REST = np.zeros(0, np.int64)  # no velocities: what World._pour paints is at rest


def _kernel():
    """The engine's kernel, imported on first use: importing it starts numba."""
    from ..engine import kernel

    return kernel


_STEP_COMPILED = False  # the best step is in the cache: once so, always so


def _serial_step(kernel):
    """The step on one thread: :func:`~sandmod.engine.kernel.step` once it is in the cache
    (:func:`sandmod.engine.kernelcache.best_step_cached`), else ``step_soon``, the same frames compiled in
    seconds (a first run steps with it while the other compiles, and switches when it is done:
    :mod:`sandmod.jobs.warmup`)."""
    global _STEP_COMPILED
    if not _STEP_COMPILED:
        from ..engine import kernelcache

        _STEP_COMPILED = kernelcache.best_step_cached()
    return kernel.step if _STEP_COMPILED else kernel.step_soon


def _speed_units(cells_a_frame) -> np.ndarray:
    """Speeds in cells a frame as the state holds them, 1/256ths of a cell, within MAX_SPEED
    (the kernel then holds each particle to its own max_speed)."""
    limit = MAX_SPEED * SUBCELL
    return np.clip(np.round(np.asarray(cells_a_frame, float) * SUBCELL), -limit, limit).astype(np.int64)


def _on_own_lines(shape: tuple[int, int], dtype) -> np.ndarray:
    """A zeroed per-chunk array whose every entry, ``[cy, cx, 0]``, lies on a cache line of its own.

    Threads updating tiles side by side write these marks many times a frame;
    sharing lines, the cores would pass each line back and forth at every write.
    The array is whole (C-contiguous) whatever the world's size, so that numba
    compiles the kernel once for worlds of one chunk and of many.
    """
    return np.zeros((*shape, CACHE_LINE // np.dtype(dtype).itemsize), dtype)


class World:
    """A grid of cells under one ruleset and seed; ``gravity`` scales every element's."""

    #: The compiled elements the world runs under.
    ruleset: Ruleset
    #: Columns of cells.
    width: int
    #: Rows of cells.
    height: int
    #: The seed of every random roll: the same seed and world file, the same frames.
    seed: int
    #: Frames stepped so far (a loaded snapshot's own frame).
    frame: int
    #: The per-cell arrays the kernel updates; code that writes them directly calls :meth:`wake`.
    state: State
    #: The ruleset's tables, each element's acceleration scaled by ``gravity``.
    tables: Tables
    #: Wake marks per chunk: which chunks (and rows of them) the next step updates.
    awake: np.ndarray
    #: Threads to step on; None: as many as pay.
    threads: int | None
    #: The world file's ``[[emitters]]``, pouring while they are on.
    emitters: list[Emitter]
    #: The world file's ``[[sprays]]`` and its timeline's ``spawn`` bursts.
    sprays: list[Spray]
    #: Explosions the world file sets off: (frame, blast), in the order they go off.
    scheduled: list[tuple[int, np.ndarray]]
    #: The timeline's ``paint`` and ``erase`` events.
    paintings: list[Painting]
    #: The timeline's ``heat`` events.
    heaters: list[Heater]
    #: The timeline's ``launch`` events.
    launchers: list[Launcher]

    def __init__(self, ruleset: Ruleset, width: int, height: int, seed: int = 0, gravity: float = 1.0):
        self.ruleset = ruleset
        self.width, self.height, self.seed = width, height, seed
        self.frame = 0
        t = ruleset.tables
        self.tables = t if gravity == 1.0 else t._replace(accel=np.round(t.accel * gravity).astype(np.int32))
        shape = (height, width)
        self.state = State(
            cells=np.zeros(shape, np.uint16),
            shade=np.zeros(shape, np.uint8),
            timer=np.zeros(shape, np.uint16),
            flags=np.zeros(shape, np.uint8),
            vx=np.zeros(shape, np.int16),
            vy=np.zeros(shape, np.int16),
            carry=np.zeros(shape, np.uint16),
            heat=np.zeros(shape, np.int32),
        )
        chunks = (-(-height // CHUNK), -(-width // CHUNK))
        self.awake = np.ones(chunks, np.uint16)  # wake marks: which chunks (and rows of them) to update on the next step
        self._changed = np.ones(chunks, np.uint16)  # chunks that may look different since image(changed_only=True) drew them
        self._woken = _on_own_lines(chunks, np.uint16)  # the kernel's scratch: wake marks made during a step
        self._even = np.zeros(chunks, np.uint8)  # chunks whose heat is even: the kernel's conduction skips them
        self._stirred = _on_own_lines(chunks, np.uint8)  # the kernel's scratch: chunks whose heat or elements changed
        self._detonations = np.zeros(-(-height // TILE) * -(-width // TILE), np.int64)  # per tile, during a step
        self._fast_gain = np.zeros(-(-height // TILE) * -(-width // TILE), np.int64)  # per tile: did the kernel's fast loop pay?
        self._seen = np.zeros_like(self._fast_gain)  # per tile: the mask of the elements in the rows the last step updated
        self._also_present = 0  # -1: the kernel looks for partners next to every cell, none skipped (for tests)
        self._fast_route = 0  # 1: every tile through the kernel's fast loop, -1: none (for tests); 0: as it pays
        self.threads = None  # threads to step on; None: as many as pay (see sandmod.engine.threads)
        self._chooser: Chooser | None = None  # picks them then
        self.emitters: list[Emitter] = []
        self.sprays: list[Spray] = []
        self.scheduled: list[tuple[int, np.ndarray]] = []  # (frame, blast row) from the world file
        self.paintings: list[Painting] = []
        self.heaters: list[Heater] = []
        self.launchers: list[Launcher] = []
        self._walker = None  # the plugin behaviours' pass (sandmod.passes.behaviours.Walker), made on the first step that needs it
        self.paint(np.broadcast_to(True, shape), 0)  # empty, with its own shades

    @property
    def cells(self) -> np.ndarray:
        """The element id of every cell, (height, width)."""
        return self.state.cells

    def paint(self, mask: np.ndarray, element: int, *, chance: float = 1.0, only_empty: bool = False, salt: int = SALT_PAINT) -> int:
        """Set the cells of ``mask`` to ``element`` as newly born cells; returns how many changed."""
        rows = max(1, PAINT_BAND // self.width)  # a band of rows at a time: the temporaries stay small
        painted = 0
        for top in range(0, self.height, rows):
            ys, xs = np.nonzero(mask[top : top + rows])
            painted += self.paint_cells(ys + top, xs, element, chance=chance, only_empty=only_empty, salt=salt)
        return painted

    def paint_layer(self, layer: np.ndarray, *, salt: int = SALT_PAINT) -> np.ndarray:
        """Paint each cell with the element ``layer`` gives (-1: left alone); returns the painted mask."""
        mask = layer >= 0
        for element in np.unique(layer[mask]):
            self.paint(layer == element, int(element), salt=salt)
        return mask

    def paint_cells(
        self, ys: np.ndarray, xs: np.ndarray, element: int, *, chance: float = 1.0, only_empty: bool = False, salt: int = SALT_PAINT
    ) -> int:
        """:meth:`paint` for the cells at rows ``ys`` and columns ``xs``."""
        # In numpy, so that a world file's scene is built without numba (validate builds it): the cells
        # become the new element as engine.cells.become makes them in the kernel (tests/test_painting.py).
        if only_empty:
            keep = self.cells[ys, xs] == 0
            ys, xs = ys[keep], xs[keep]
        ys, xs = ys.astype(np.uint64), xs.astype(np.uint64)
        if chance < 1.0:
            roll = cell_hash(frame_key(self.seed, self.frame, salt), xs, ys)
            keep = (roll >> (32 - ROLL_BITS)) < chance_threshold(chance)
            ys, xs = ys[keep], xs[keep]
        t = self.ruleset.tables
        h = cell_hash(frame_key(self.seed, self.frame, SALT_SPAWN ^ salt), xs, ys)
        shade, timer = spawn_state(h, int(t.life_frames[element]), int(t.life_jitter[element]))
        s = self.state
        s.cells[ys, xs] = element
        s.shade[ys, xs] = shade
        s.timer[ys, xs] = timer
        s.flags[ys, xs] = LOOSE
        s.vx[ys, xs] = s.vy[ys, xs] = s.carry[ys, xs] = 0
        s.heat[ys, xs] = t.heat_cap[element] * t.temp_start[element]
        self.wake(ys, xs)
        return len(xs)

    def _pour(
        self, ys, xs, element: int, *, cargo: int = 0, velocity=None, chance: float = 1.0, only_empty: bool = False, salt: int = SALT_PAINT
    ) -> int:
        """:meth:`paint_cells` in the kernel, for what is painted every frame; ``velocity``: the
        painted cells' (vx, vy) arrays in 1/256ths of a cell a frame, or None for at rest."""
        from ..engine import kernel  # this version's, even while tools/dev steps with another

        t = self.ruleset.tables
        vx, vy = (_AT_REST, _AT_REST) if velocity is None else velocity
        return kernel.paint_cells(
            self.state, t, np.ascontiguousarray(ys, np.int64), np.ascontiguousarray(xs, np.int64), element, cargo, vx, vy, only_empty,
            chance_threshold(chance), frame_key(self.seed, self.frame, salt), frame_key(self.seed, self.frame, SALT_SPAWN ^ salt),
            self.awake, self._even,
        )  # fmt: skip

    def launch(self, ys: np.ndarray, xs: np.ndarray, vx: np.ndarray, vy: np.ndarray) -> int:
        """Send cells flying: each becomes a particle carrying it, at (vx, vy) cells per frame.

        Empty cells and particles already in flight are left alone; returns how many flew.
        """
        s = self.state
        ys, xs = np.asarray(ys, np.int64), np.asarray(xs, np.int64)
        vx, vy = np.broadcast_to(vx, ys.shape), np.broadcast_to(vy, ys.shape)
        keep = (s.cells[ys, xs] != 0) & (self.tables.archetype[s.cells[ys, xs]] != ARCHETYPE_CODES["particle"])
        ys, xs, vx, vy = ys[keep], xs[keep], vx[keep], vy[keep]
        celsius = self._temperature_units(ys, xs) / TEMP_ONE
        s.carry[ys, xs] = s.cells[ys, xs]
        s.cells[ys, xs] = self.ruleset.particle
        self._set_velocity(ys, xs, vx, vy)
        self._set_temperature(ys, xs, celsius)
        self.wake(ys, xs)
        return len(xs)

    def spawn_particles(self, ys: np.ndarray, xs: np.ndarray, element: int, vx: np.ndarray, vy: np.ndarray) -> int:
        """Put particles into the empty ones of the given cells, flying at (vx, vy) cells per frame.

        A particle element flies as itself, carrying what its ``carries`` says;
        any other element flies as ``base:particle`` carrying it. Returns how many were placed.
        """
        t = self.tables
        ys = np.asarray(ys, np.int64)
        velocity = (_speed_units(np.broadcast_to(vx, ys.shape)), _speed_units(np.broadcast_to(vy, ys.shape)))
        if t.archetype[element] == ARCHETYPE_CODES["particle"]:
            particle, cargo = element, int(t.carries[element])
        else:
            particle, cargo = self.ruleset.particle, element
        return self._pour(ys, xs, particle, cargo=cargo, velocity=velocity, only_empty=True, salt=SALT_SPRAY)

    def _set_velocity(self, ys, xs, vx, vy) -> None:
        s = self.state
        s.vx[ys, xs] = _speed_units(vx)
        s.vy[ys, xs] = _speed_units(vy)
        s.flags[ys, xs] = 0

    def temperature(self) -> np.ndarray:
        """Every cell's temperature in degrees Celsius (float), (height, width)."""
        return self._temperature_units() / TEMP_ONE

    def _temperature_units(self, ys=slice(None), xs=slice(None)) -> np.ndarray:
        """Temperatures in the kernel's fixed point, of every cell or of the cells given."""
        s, t = self.state, self.tables
        energy = s.heat[ys, xs].astype(np.int64)
        scaled = (np.abs(energy) * t.heat_recip[s.cells[ys, xs]]) >> 32  # as the kernel does: exact on both sides of 0
        return np.where(energy < 0, -scaled, scaled)

    def temperature_at(self, x: int, y: int) -> float:
        """One cell's temperature, in degrees Celsius."""
        return float(self._temperature_units(slice(y, y + 1), slice(x, x + 1))[0, 0]) / TEMP_ONE

    def set_temperature(self, mask: np.ndarray, celsius: float) -> None:
        """Heat or cool the cells of ``mask`` to ``celsius`` degrees."""
        ys, xs = np.nonzero(mask)
        self._set_temperature(ys, xs, celsius)

    def _set_temperature(self, ys, xs, celsius) -> None:
        s = self.state
        units = np.round(np.asarray(celsius, float) * TEMP_ONE).astype(np.int64)
        s.heat[ys, xs] = self.tables.heat_cap[s.cells[ys, xs]] * units
        self.wake(ys, xs)

    def wake(self, ys: np.ndarray | None = None, xs: np.ndarray | None = None) -> None:
        """Update the chunks around the given cells (all chunks, without cells) on the next step,
        heat conduction included (their heat is no longer known to be even).

        The world's own methods call this; code that writes ``state`` arrays
        directly must call it too, or chunks at rest will not notice the change.
        """
        if ys is None or xs is None:
            self.awake[:] = WHOLE
            self._even[:] = 0
            self._changed[:] = 1
            return
        ys, xs = np.asarray(ys, np.int64), np.asarray(xs, np.int64)
        if ys.size == 0:
            return
        for dy in (-WAKE_MARGIN, WAKE_MARGIN):
            for dx in (-WAKE_MARGIN, WAKE_MARGIN):
                cy = np.clip(ys + dy, 0, self.height - 1) >> CHUNK_SHIFT
                cx = np.clip(xs + dx, 0, self.width - 1) >> CHUNK_SHIFT
                self.awake[cy, cx] = WHOLE
                self._even[cy, cx] = 0
                self._changed[cy, cx] = 1

    @property
    def awake_fraction(self) -> float:
        """The share of chunks the next step will update (woken ones not counted)."""
        return np.count_nonzero(self.awake) / self.awake.size

    def heat_total(self) -> int:
        """The sum of every cell's heat energy (conduction keeps it; sources and cooling change it)."""
        return int(self.state.heat.sum(dtype=np.int64))

    def _blast_row(self, x: int, y: int, explosion: Explosion) -> np.ndarray:
        """An explosion centred on cell (x, y), as the kernel takes it (KeyError: unknown 'leaves')."""
        return blast_row(explosion, self.ruleset.index(explosion.leaves), x, y)

    def explode(self, x: int, y: int, explosion: Explosion) -> None:
        """Set off an explosion centred on cell (x, y) now."""
        self._explode(self._blast_row(x, y, explosion)[None, :], 1)

    def _explode(self, rows: np.ndarray, salt: int) -> None:
        key = frame_key(self.seed, self.frame, SALT_BLAST + salt)
        _kernel().explode(self.state, self.tables, rows, len(rows), key, self.ruleset.particle, self.awake, self._even)
        self._changed |= self.awake  # what it woke is what it changed

    def mark_changed(self) -> None:
        """Have the next :meth:`image` with ``changed_only`` draw every chunk (after writing ``state``
        arrays directly; the world's own methods keep track themselves)."""
        self._changed[:] = 1

    def _step_arguments(self, hands: int) -> tuple:
        """What the kernel's step is handed, this frame, on ``hands`` threads."""
        return (
            self.state,
            self.tables,
            frame_key(self.seed, self.frame, SALT_MOVE),
            frame_key(self.seed, self.frame, SALT_REACT),
            frame_key(self.seed, self.frame, SALT_SPAWN),
            self.frame,
            self.awake,
            self._woken,
            self._even,
            self._stirred,
            self._detonations,
            hands,
            self._also_present,
            self._fast_gain,
            self._fast_route,
            self._seen,
        )

    def step(self) -> None:
        """Advance one frame: emitters pour, sprays shoot, the timeline paints and heats,
        the kernel updates every cell, neighbour rules change cells, explosions go off."""
        kernel = _kernel()
        for number, emitter in enumerate(self.emitters):
            if emitter.active(self.frame):
                self._pour(emitter.ys, emitter.xs, emitter.element, chance=emitter.chance, only_empty=True, salt=SALT_PAINT + 1 + number)
        for spray in self.sprays:
            if spray.active(self.frame):
                ys, xs, vx, vy = spray.shots(self.seed, self.frame)
                self.spawn_particles(ys, xs, spray.element, vx, vy)
        for painting in self.paintings:
            if painting.frame == self.frame:
                painted = self.paint_layer(painting.layer(self.cells), salt=SALT_TIMELINE + painting.number)
                if painting.celsius is not None:
                    self.set_temperature(painted, painting.celsius)
        for launcher in self.launchers:
            if launcher.frame == self.frame:
                ys, xs = np.nonzero(launcher.area(self.cells))
                self.launch(ys, xs, *launcher.velocities(self.seed, ys, xs))
        for heater in self.heaters:
            if heater.active(self.frame):
                self.set_temperature(heater.area(self.cells), heater.celsius)
        self._changed |= self.awake  # the kernel changes only chunks awake before it runs, or woken by it
        before = self.awake.copy() if self.ruleset.behaviours is not None else None
        hands = self._thread_count()
        started = perf_counter()
        stepper = kernel.step_at_once if hands > 1 else _serial_step(kernel)
        went_off = stepper(*self._step_arguments(hands))
        if self.threads is None:
            self._chooser.timed(perf_counter() - started)
        if self.ruleset.neighbours is not None:
            from ..passes.counts import apply_neighbour_rules

            apply_neighbour_rules(self)
        if went_off:  # top to bottom, left to right, whichever thread found them
            self._explode(kernel.take_detonations(self.state, self.tables, self._detonations), 0)
        due = [row for frame, row in self.scheduled if frame == self.frame]
        if due:  # the world file's, in its order
            self._explode(np.array(due), 1)
        if before is not None:
            self._behave(before)
        self._changed |= self.awake
        self.frame += 1

    def _behave(self, before: np.ndarray) -> None:
        """Run the plugin behaviours the ruleset's elements name (``before``: the wake marks before the step)."""
        from ..passes.behaviours import SALT_BEHAVIOUR, Walker

        if self._walker is None or self._walker.table is not self.ruleset.behaviours:
            self._walker = Walker(self.ruleset.behaviours, (self.height, self.width), self.awake.shape)
            self._walker.hold(self.cells)
        self._walker.run(self, before, frame_key(self.seed, self.frame, SALT_BEHAVIOUR))

    def _thread_count(self) -> int:
        """This frame's thread count: :attr:`threads`, or as many as pay (see :mod:`sandmod.engine.threads`);
        numba's threads set to it when more than one."""
        if self.threads is not None:
            hands = max(1, min(self.threads, threads_available()))
        else:
            if self._chooser is None:
                self._chooser = Chooser(len(self._detonations) // 4)
            hands = self._chooser.count()
        if hands > 1:
            import numba

            numba.set_num_threads(hands)
        return hands

    def counts(self, *, carried: bool = False) -> dict[str, int]:
        """How many cells of each element there are, by element id.

        With ``carried``, a flying particle counts as what it carries, so the
        totals show what motion alone can neither create nor lose.
        """
        s = self.state
        flying = self.tables.archetype[s.cells] == ARCHETYPE_CODES["particle"]
        cells = np.where(flying & (s.carry != 0), s.carry, s.cells) if carried else s.cells
        numbers = np.bincount(cells.ravel(), minlength=len(self.ruleset.elements))
        return {e.id: int(numbers[e.index]) for e in self.ruleset.by_id if numbers[e.index]}

    def shown(self) -> np.ndarray:
        """The element each cell shows: its own, or what it carries (a particle) or holds (an element
        that ``shows_held``)."""
        s = self.state
        return np.where((s.carry != 0) & (self.tables.shows_held[s.cells] != 0), s.carry, s.cells)

    def image(self, out: np.ndarray | None = None, changed_only: bool = False, rgb: np.ndarray | None = None,
              colours: np.ndarray | None = None) -> np.ndarray:
        """Colour indices of every cell (rows of ``ruleset.colours``), uint16 (height, width), into
        ``out`` when given.

        A cell shows its element's colour in its own shade; scorched cells are
        darker, and cells hotter than the glow point glow red, orange, then
        yellow. With ``changed_only``, only the chunks that may have changed
        since the last such call are drawn (``out`` holds the rest from then).
        With ``rgb`` (uint8 (height, width, 3), or 4 with the last left
        alone), the cells drawn are written there in colour too: rows of
        ``colours``, the ruleset's unless given (in another channel order, say).
        """
        from ..engine import pixels

        looks, s = self.ruleset.looks, self.state
        out = np.empty((self.height, self.width), np.uint16) if out is None else out
        chunks = self._take_changed() if changed_only else _ALL_CHUNKS
        pixels.colour_indices(
            s.cells, s.carry, s.shade, s.flags, s.heat, self.tables.heat_recip, self.tables.shows_held,
            looks.normal, looks.scorched, looks.glow, looks.glow_from, _GLOW_STEP, looks.glow_energy, chunks, out,
        )
        if rgb is not None:
            pixels.rgb(out, self.ruleset.colours if colours is None else colours, chunks, rgb)
        return out

    def heat_image(self, out: np.ndarray | None = None, changed_only: bool = False) -> np.ndarray:
        """Every cell's temperature as a colour, RGB (height, width, 3): blue cold, dark at 20 degrees,
        then purple, red, orange, yellow and white, the scale of ``sandmod play``'s heat view.
        ``changed_only`` as for :meth:`image`, whose record of changes it shares."""
        from ..engine import pixels

        out = np.empty((self.height, self.width, 3), np.uint8) if out is None else out
        pixels.heat_rgb(self.cells, self.state.heat, self.tables.heat_recip, _heat_colours(), self._take_changed() if changed_only else _ALL_CHUNKS, out)
        return out

    def _take_changed(self) -> np.ndarray:
        """The chunks changed since the last call (a copy), forgotten here."""
        changed = self._changed.copy()
        self._changed[:] = 0
        return changed

    def rgb(self) -> np.ndarray:
        """The frame in colour, RGB (height, width, 3): :meth:`image` through ``ruleset.colours``."""
        return self.ruleset.colours[self.image()]

    def run(self, frames: int) -> None:
        """:meth:`step` ``frames`` times."""
        for _ in range(frames):
            self.step()

    def paint_shape(self, table: Mapping[str, Any] | None = None, /, **fields: Any) -> int:
        """Paint a shape written as in a world file's ``[[scene]]``, as a table or as keywords:
        ``world.paint_shape(shape="circle", element="sand", x=40, y=10, radius=5)``. A picture's
        ``file`` is taken from the working folder. Returns how many cells were painted;
        ProblemsError names each mistake in the shape."""
        from .scene import paint_shape

        return paint_shape(self, {**(table or {}), **fields})

    def save_snapshot(self, path: str | Path) -> None:
        """Write the whole state to an ``.npz`` file (atomically): :meth:`load_snapshot` goes on from it bit for bit."""
        from .snapshots import save_snapshot

        save_snapshot(self, Path(path))

    def load_snapshot(self, path: str | Path) -> list[str]:
        """Take the state, frame and seed from a snapshot this world's size; returns warnings (other mod
        versions than it was made with); ProblemsError if it does not fit or is not a snapshot."""
        from .snapshots import load_snapshot

        return load_snapshot(self, Path(path))

    def _repr_png_(self) -> bytes:
        """The frame as a PNG, each cell a block of pixels: how a notebook shows a world."""
        import io

        from ..formats.recording import write_png

        scale = max(1, min(8, 512 // max(self.width, self.height)))
        out = io.BytesIO()
        write_png(out, enlarge(self.image(), scale), self.ruleset.colours)
        return out.getvalue()


def enlarge(frame: np.ndarray, scale: int) -> np.ndarray:
    """Each pixel as a ``scale`` x ``scale`` block (nearest neighbour)."""
    if scale == 1:
        return frame
    height, width = frame.shape
    big = np.empty((height, scale, width, scale), frame.dtype)
    big[...] = frame[:, None, :, None]
    return big.reshape(height * scale, width * scale)


_ALL_CHUNKS = np.zeros((0, 0), np.uint16)  # pixels' chunk mask for "every chunk"
_GLOW_STEP = temperature_units(GLOW_STEP)


@functools.cache
def _heat_colours() -> np.ndarray:
    from ..engine.pixels import heat_colours

    return heat_colours()

