"""The behaviour interface: what a plugin's per-cell behaviour is, and the view it gets of its cell.

A behaviour is a plain Python function of one argument, a :class:`View` of one
cell, made into a :class:`Behaviour` by :func:`behaviour`, registered with the
``register_behaviours`` hook and named by elements (``behaviour = "garden:grow"``).
sandmod compiles it with numba, alone (never the kernel), and calls it once a
frame for each cell of an element that names it, after the kernel's step.

Inside it, the cell and its neighbours are read and changed only through the
helpers below (:func:`here`, :func:`look`, :func:`put`, :func:`swap`,
:func:`temperature`, :func:`random`, :func:`chance`, :func:`arg`), within
:data:`REACH` cells. Here they are plain Python stand-ins, so that importing
them costs nothing; :mod:`sandmod.passes.helpers` gives numba their compiled
forms. Nothing here imports numba.
"""

from __future__ import annotations

import hashlib
import inspect
import re
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, NamedTuple

#: How far a behaviour reaches, in cells either way: farther offsets read as outside the world.
REACH = 2
#: A behaviour's own name (the part after the plugin's, ``garden:grow``) and an argument's name.
NAME = re.compile(r"^[a-z][a-z0-9_]*$")
#: A behaviour's full name, as elements write it: ``PLUGIN:name``.
FULL_NAME = r"^[a-z][a-z0-9_.-]*:[a-z][a-z0-9_]*$"
#: Most arguments one behaviour takes.
MAX_ARGS = 16


class View(NamedTuple):
    """One cell as a behaviour sees it. Its fields are sandmod's to change: use the helpers."""

    cells: Any  # the world's arrays (sandmod.api.State's), (height, width)
    shade: Any  # each cell's shade
    timer: Any  # each cell's lifetime or burning time left
    flags: Any  # each cell's kernel flags
    vx: Any  # each cell's velocity, right
    vy: Any  # each cell's velocity, down
    carry: Any  # what each flying particle carries
    heat: Any  # each cell's heat energy
    life_frames: Any  # per element: its lifetime (the tables a new cell is made from)
    life_jitter: Any  # per element: its lifetime's jitter
    heat_cap: Any  # per element: its heat capacity
    heat_recip: Any  # per element: 2**32 / its heat capacity
    temp_start: Any  # per element: a new cell's temperature
    remembers: Any  # per element: whether its cells keep the element they hold
    codes: Any  # per element: its behaviour's number (0: none)
    args: Any  # per element: its behaviour's arguments, float64
    stamp: Any  # per cell: frame + 1 where a behaviour changed it this frame
    awake: Any  # per chunk: the world's wake marks
    even: Any  # per chunk: the world's even-heat marks
    held: Any  # per chunk: whether it holds behaviour cells
    draws: Any  # the random draws this cell has taken this frame, one uint32
    key: Any  # the frame's key for behaviours' randomness
    frame: Any  # the frame number
    x: Any  # the cell's column
    y: Any  # the cell's row
    element: Any  # the cell's element


@dataclass(frozen=True)
class Behaviour:
    """A per-cell behaviour: the function, and the names of the arguments elements give it."""

    #: The function of one :class:`View`, compiled by numba.
    function: Callable[[View], None]
    #: Argument names, in the order :func:`arg` numbers them.
    args: tuple[str, ...] = ()
    #: Values of the arguments an element may leave out (a number, or an element's name).
    defaults: Mapping[str, float | str] = field(default_factory=dict)

    @property
    def name(self) -> str:
        """The function's name, for messages."""
        return getattr(self.function, "__qualname__", repr(self.function))

    def source_hash(self) -> str:
        """A hash of the code it is compiled from: its module's whole file, and those of the
        functions its package marks with :func:`helper`."""
        h = hashlib.sha256(f"{self.function.__module__}.{self.name} {self.args}".encode())
        package = self.function.__module__.split(".")[0]
        for function in [self.function] + [f for f in MARKED if f.__module__.split(".")[0] == package]:
            try:
                h.update(open(inspect.getsourcefile(function) or "", "rb").read())
                h.update(inspect.getsource(function).encode())
            except (OSError, TypeError):
                h.update(function.__code__.co_code + repr(function.__code__.co_consts).encode())
        return h.hexdigest()


def behaviour(args: tuple[str, ...] | Mapping[str, float | str | None] = ()) -> Callable[[Callable], Behaviour]:
    """Make a function of one :class:`View` into a behaviour taking ``args``: names, or a mapping
    of names to defaults (None: required). ``arg(v, k)`` reads the k-th, as a number (an element
    given by name reads as its id)."""
    names = tuple(args)
    defaults = {k: v for k, v in args.items() if v is not None} if isinstance(args, Mapping) else {}
    bad = [n for n in names if not (isinstance(n, str) and NAME.match(n))]
    if bad or len(names) > MAX_ARGS or len(set(names)) != len(names):
        raise ValueError(f"behaviour args must be up to {MAX_ARGS} distinct lower-case names, got {names!r}")

    def make(function: Callable) -> Behaviour:
        return Behaviour(function, names, defaults)

    return make


#: Functions of plugins marked with :func:`helper`, in the order marked.
MARKED: list[Callable] = []


def helper(function: Callable) -> Callable:
    """Mark a plugin's own function, which its behaviours call, to be compiled with them
    (numba compiles only what it is told to; this tells it without importing numba now)."""
    MARKED.append(function)
    return function


# The helpers. Plain Python here; compiled into each behaviour (see sandmod.passes.helpers).


def here(v: View) -> int:
    """The element id of the cell itself."""
    return int(v.element)


def look(v: View, dx: int, dy: int) -> int:
    """The element id of the cell ``dx`` to the right and ``dy`` down (up to :data:`REACH`
    cells either way); -1 outside the world or out of reach."""
    raise _python_only()


def put(v: View, dx: int, dy: int, element: int) -> bool:
    """Make the cell at (dx, dy) a new cell of ``element``, as a reaction would: its own shade and
    lifetime, at rest, at the temperature the cell had, holding what it held if ``element`` can
    hold, done for the frame (no behaviour runs on
    it until the next), its chunk woken. False (and nothing changed) outside the world or reach."""
    raise _python_only()


def swap(v: View, dx: int, dy: int) -> bool:
    """Trade places with the cell at (dx, dy), everything the cells hold going with them (a walk);
    both are done for the frame. The view still names the old place. False outside or out of reach."""
    raise _python_only()


def temperature(v: View, dx: int, dy: int) -> float:
    """The temperature of the cell at (dx, dy) in degrees Celsius; NaN outside or out of reach."""
    raise _python_only()


def random(v: View) -> float:
    """A number in [0, 1), a hash of the seed, frame, cell and how many the cell has drawn:
    the same on every run and any number of threads; each call draws the next."""
    raise _python_only()


def chance(v: View, p: float) -> bool:
    """True with probability ``p``: ``random(v) < p``."""
    raise _python_only()


def arg(v: View, k: int) -> float:
    """The element's k-th argument (in the order the behaviour declares them), as a float."""
    raise _python_only()


def frame(v: View) -> int:
    """The frame number (the one the kernel has just stepped)."""
    return int(v.frame)


#: The helpers, by name (the compiled forms are registered for each).
HELPERS = (here, look, put, swap, temperature, random, chance, arg, frame)


def _python_only() -> RuntimeError:
    return RuntimeError("sandmod's behaviour helpers run only inside a compiled behaviour")
