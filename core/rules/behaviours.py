"""Elements' plugin behaviours, compiled into a numbering and a table of arguments.

Each behaviour that some element names gets a number (1, 2, ... in the order of
their full names); ``codes[e]`` is element e's (0: none) and ``args[e]`` its
arguments as the behaviour declares them, float64, element names resolved to ids.
A ruleset in which no element names a behaviour has none of this: its worlds never
run the behaviours' pass.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from ..formats.behaviour import Behaviour
from ..registry import Registered


@dataclass(frozen=True)
class Behaviours:
    """The behaviours a ruleset's elements name, numbered from 1."""

    #: Full names (``garden:grow``), by number - 1.
    names: tuple[str, ...]
    #: What the plugins registered under them.
    given: tuple[Registered[Behaviour], ...]
    #: int32[n]: each element's behaviour's number, 0 for none.
    codes: np.ndarray
    #: float64[n, k]: each element's arguments.
    args: np.ndarray


#: Reports a problem at an element's field (a path below the element) with a message.
Report = Callable[[tuple, str], None]
#: Resolves an element's name to its id at an element's field (None: unknown, reported).
Resolve = Callable[..., "int | None"]


def compile_behaviours(
    elements: Sequence, catalog: Mapping[str, Registered[Behaviour]], report_for: Callable[[int], Report], resolve_for: Callable[[int], Resolve]
) -> Behaviours | None:
    """The behaviours ``elements`` name (None when none does); each unknown name, unknown,
    missing or wrong argument is reported at its field."""
    named = {e.index: e.spec.behaviour for e in elements if e.spec.behaviour is not None}
    for e in elements:
        if e.spec.behaviour is None and e.spec.behaviour_args:
            report_for(e.index)(("behaviour_args",), "arguments without a 'behaviour' to take them")
    if not named:
        return None
    used = sorted({name for name in named.values() if name in catalog})
    width = max([len(catalog[name].value.args) for name in used] + [1])
    codes = np.zeros(len(elements), np.int32)
    args = np.zeros((len(elements), width), np.float64)
    for index, name in named.items():
        report = report_for(index)
        if name not in catalog:
            known = ", ".join(sorted(catalog)) or "none is installed"
            report(("behaviour",), f"no plugin gives a behaviour '{name}' (known: {known})")
            continue
        codes[index] = used.index(name) + 1
        _fill_args(args[index], catalog[name].value, elements[index].spec.behaviour_args, report, resolve_for(index))
    return Behaviours(tuple(used), tuple(catalog[name] for name in used), codes, args)


def _fill_args(row: np.ndarray, behaviour: Behaviour, given: Mapping[str, object], report: Report, resolve: Resolve) -> None:
    """One element's arguments into ``row``, in the behaviour's order."""
    for name in given:
        if name not in behaviour.args:
            takes = ", ".join(behaviour.args) or "none"
            report(("behaviour_args", name), f"the behaviour takes no argument '{name}' (it takes: {takes})")
    for k, name in enumerate(behaviour.args):
        value = given.get(name, behaviour.defaults.get(name))
        if value is None:
            report(("behaviour_args",), f"the behaviour needs argument '{name}'")
        elif isinstance(value, str):
            found = resolve(value, "behaviour_args", name)
            row[k] = -1 if found is None else found
        else:
            row[k] = float(value)
