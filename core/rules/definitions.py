"""Which definition of each element is in force, from the mods in load order: whole elements
and overrides, patches of some fields of another mod's element, elements made ``like`` another,
and the molten and frozen forms an element makes of itself. Each becomes a :class:`Definition`,
which :mod:`.compiler` turns into tables; names are resolved here (:func:`resolve_name`)."""

from __future__ import annotations

import difflib
import typing
from dataclasses import dataclass, field
from typing import Sequence

from pydantic import BaseModel

from ..errors import Problem, ProblemsError
from ..formats.modspec import ELEMENT_REF, Cooled, Element, Heated, LiquidElement, PatchedElement, StaticElement
from ..formats.tomlsource import TomlSource
from ..formats.validation import validate_changed
from .glow import glowing, lean
from .modset import LoadedMod


@dataclass(frozen=True)
class Override:
    """One mod replacing an element another mod defined, or patching some of its fields: where, and the fields whose values changed."""

    mod: str
    file: str
    line: int | None
    changes: tuple[tuple[str, object, object], ...]  # (field, before, after)
    patch: bool = False  # only the fields it names changed (the rest kept), or the whole element replaced

    def describe(self) -> str:
        where = self.file if self.line is None else f"{self.file}:{self.line}"
        changed = "; ".join(f"{name} {before!r} -> {after!r}" for name, before, after in self.changes) or "no values changed"
        return f"{'patched' if self.patch else 'overridden'} by {self.mod} ({where}): {changed}"


def _differences(before: Element, after: Element) -> tuple[tuple[str, object, object], ...]:
    old, new = before.model_dump(exclude={"override"}), after.model_dump(exclude={"override"})
    return tuple((k, old.get(k), new.get(k)) for k in dict.fromkeys([*old, *new]) if old.get(k) != new.get(k))


@dataclass
class Definition:
    """An element's definition in force: its fields, where they were written, and who changed what."""

    spec: Element
    source: TomlSource
    mod: str
    loc: tuple
    replaced: list[str] = field(default_factory=list)
    history: list[Override] = field(default_factory=list)
    patched: dict[str, Override] = field(default_factory=dict)  # each field patches set: the last patch that set it


def collect_definitions(mods: Sequence[LoadedMod], problems: list[Problem], warnings: list[Problem]) -> dict[str, Definition]:
    defs: dict[str, Definition] = {}
    below, by_name = required_below(mods), {m.name: m for m in mods}
    for mod in mods:
        for key, spec in mod.spec.elements.items():
            loc = ("elements", key)
            element_id = key if ":" in key else f"{mod.name}:{key}"
            previous = defs.get(element_id)
            foreign = element_id.split(":", 1)[0] != mod.name
            if previous is None:
                if spec.override or foreign:
                    what = "nothing to override" if spec.override else "an element of another mod needs override = true"
                    problems.append(mod.source.problem(loc, f"'{element_id}' is not defined by any loaded mod ({what})"))
                    continue
                defs[element_id] = Definition(spec, mod.source, mod.name, loc)
                _make_family(defs, element_id, mod, problems)
            elif not spec.override:
                problems.append(
                    mod.source.problem(
                        loc, f"'{element_id}' is already defined by {previous.source.name}; set override = true to replace it"
                    )
                )
            else:
                change = Override(mod.name, mod.source.name, mod.source.line_of(loc), _differences(previous.spec, spec))
                defs[element_id] = Definition(
                    spec, mod.source, mod.name, loc, previous.replaced + [previous.mod], previous.history + [change]
                )
                _make_family(defs, element_id, mod, problems)
        for key, fields in mod.spec.patches.items():
            if "like" in fields:
                _derive(defs, key, fields, mod, by_name, problems)
            else:
                _patch(defs, key, fields, mod, below, problems, warnings)
    return defs


def _derive(defs: dict[str, Definition], key: str, fields: dict, mod: LoadedMod, by_name: dict[str, LoadedMod], problems: list[Problem]) -> None:
    """Define an element ``like`` another defined before it: that one's fields, those given replacing them."""
    loc = ("elements", key)
    element_id = key if ":" in key else f"{mod.name}:{key}"
    like = fields["like"]
    base_id, message = resolve_name(like, mod.name, defs, mod.requires) if isinstance(like, str) else (None, "must be an element name")
    if element_id.split(":", 1)[0] != mod.name or element_id in defs:
        problems.append(mod.source.problem(loc, f"'{element_id}' is not a new element of {mod.name}: 'like' makes a new one (a patch changes one)"))
        return
    if base_id is None:
        problems.append(mod.source.problem(loc + ("like",), f"{message} (an element defined before this one: in a mod it requires, or above it)"))
        return
    given = {name: value for name, value in fields.items() if name != "like"}
    base = defs[base_id]  # its names (glass, for sand's heated.becomes) as its own mod reads them
    taken = _qualified(base.spec.model_dump(mode="json", exclude={"override", "like"}, exclude_none=True), type(base.spec),
                       lambda ref: resolve_name(ref, base.mod, defs, by_name[base.mod].requires)[0] or ref)
    try:
        spec = validate_changed(PatchedElement, {**taken, **given, "like": base_id}, mod.source, loc, set(fields)).element
    except ProblemsError as mistakes:
        problems.extend(mistakes.problems)
        return
    defs[element_id] = Definition(spec, mod.source, mod.name, loc)
    _make_family(defs, element_id, mod, problems)


#: The forms an element may make of itself: its field, the form's name prefix and archetype, which way
#: the element changes into it (its own field, the point's name), the colour its colours lean to (none:
#: they glow as the element's would at the point), and how far from the point the form is placed.
FAMILY = (
    ("melts", "molten_", "liquid", "heated", "above", None, 100.0),
    ("freezes", "frozen_", "static", "cooled", "below", "#d8ecff", -20.0),
)
FORM_DENSITY, FORM_DISPERSION = 2500.0, 1  # a molten form's, where the element has no density of its own
_ARCHETYPE_MODELS = {"liquid": LiquidElement, "static": StaticElement}


def _make_family(defs: dict[str, Definition], element_id: str, mod: LoadedMod, problems: list[Problem]) -> None:
    """Make the forms that an element's ``melts`` and ``freezes`` ask for, and the changes between them."""
    d = defs[element_id]
    for field_name, prefix, archetype, change, point, tint, offset in FAMILY:
        family = getattr(d.spec, field_name, None)
        if family is None:
            continue
        at = getattr(family, point)
        given = dict(family.model_extra or {})
        form_id = f"{mod.name}:{prefix}{element_id.split(':', 1)[1]}"
        loc = d.loc + (field_name,)
        if form_id in defs:
            problems.append(mod.source.problem(loc, f"its form '{form_id}' is defined already"))
            continue
        own = d.spec.model_dump(mode="json", exclude={"override", "like", "melts", "freezes", "heated", "cooled"}, exclude_none=True)
        form = {name: value for name, value in own.items() if name in _ARCHETYPE_MODELS[archetype].model_fields}
        colors = [lean(c, tint) if tint else glowing(c, at) for c in d.spec.color]
        form.update(archetype=archetype, color=colors, temperature=at + offset)
        if archetype == "liquid":
            form.update(density=0.9 * own.get("density", FORM_DENSITY / 0.9), dispersion=FORM_DISPERSION)
        back, back_point = ("cooled", "below") if change == "heated" else ("heated", "above")
        form[back] = {back_point: at, "becomes": element_id}
        try:
            spec = validate_changed(PatchedElement, {**form, **given}, mod.source, loc, set(given)).element
        except ProblemsError as mistakes:
            problems.extend(mistakes.problems)
            continue
        defs[form_id] = Definition(spec, mod.source, mod.name, loc)
        into = (Heated if change == "heated" else Cooled)(**{point: at, "becomes": form_id})
        d.spec = d.spec.model_copy(update={change: into})


def required_below(mods: Sequence[LoadedMod]) -> dict[str, set[str]]:
    """Each mod's requirements, theirs and so on."""
    below: dict[str, set[str]] = {}
    for mod in mods:  # in load order: a mod's requirements come before it
        below[mod.name] = set(mod.requires).union(*(below.get(name, set()) for name in mod.requires))
    return below


def _qualified(data: dict, model: type[BaseModel], qualify) -> dict:
    """``data`` (``model`` dumped) with each element name in it, nested tables' too, as ``qualify`` gives it."""
    out = dict(data)
    for name, info in model.model_fields.items():
        value = out.get(name)
        if isinstance(value, str) and f"^{ELEMENT_REF}$" in repr(info):
            out[name] = qualify(value)
        elif isinstance(value, dict):
            nested = [a for a in (info.annotation, *typing.get_args(info.annotation)) if isinstance(a, type) and issubclass(a, BaseModel)]
            out[name] = _qualified(value, nested[0], qualify) if nested else value
    return out


def _patch(
    defs: dict[str, Definition], element_id: str, fields: dict, mod: LoadedMod, below: dict[str, set[str]], problems: list[Problem], warnings: list[Problem]
) -> None:
    """Apply a mod's patch of another mod's element (a table of the fields it changes): the
    element keeps its other fields; the result is checked as a whole element would be. A field
    that a mod it does not require (nor that requires it) patched before is a warning: its
    value wins by load order alone."""
    loc = ("elements", element_id)
    previous = defs.get(element_id)
    if previous is None:
        problems.append(mod.source.problem(loc, f"'{element_id}' is not defined by any loaded mod (nothing to change: "
                                           f"a mod that changes another's element names it in requires, to load after it)"))
        return
    given = {name: value for name, value in fields.items() if name != "override"}
    for family in ("melts", "freezes"):
        if family in given:
            problems.append(mod.source.problem(loc + (family,), f"a patch cannot make forms ('{family}'): override the element, "
                                               "or give it a 'heated' or 'cooled' into an element of your own"))
            return
    merged = {**previous.spec.model_dump(mode="json", exclude={"override"}, exclude_none=True), **given}
    try:
        spec = validate_changed(PatchedElement, merged, mod.source, loc, set(given)).element
    except ProblemsError as mistakes:
        problems.extend(mistakes.problems)
        return
    change = Override(mod.name, mod.source.name, mod.source.line_of(loc), _differences(previous.spec, spec), patch=True)
    patched = dict(previous.patched)
    for name in given:
        earlier = patched.get(name)
        if earlier is not None and earlier.mod not in below[mod.name] and mod.name not in below.get(earlier.mod, set()):
            warnings.append(mod.source.problem(loc + (name,), f"also patched by {earlier.mod} ({earlier.file}:{earlier.line}), "
                                               f"which {mod.name} does not require: {mod.name}'s value is kept, by load order alone"))
        patched[name] = change
    # still the element its mod defined (its names resolve as that mod's), changed: the change is in its history
    defs[element_id] = Definition(spec, previous.source, previous.mod, previous.loc, previous.replaced, previous.history + [change], patched)


def resolve_name(ref: str, mod: str | None, ids: typing.Collection[str], requires: Sequence[str] = ()) -> tuple[str | None, str]:
    """Resolve an element reference among the ids ``ids`` holds; returns (id, "") or (None, message).

    A bare name means the element of that name in ``mod`` itself, else in the
    mods it requires (one of them), else in any loaded mod (one of them).
    """
    if ":" in ref:
        if ref in ids:
            return ref, ""
        candidates = list(ids)
    else:
        if mod is not None and f"{mod}:{ref}" in ids:
            return f"{mod}:{ref}", ""
        required = [f"{m}:{ref}" for m in requires if f"{m}:{ref}" in ids]
        if len(required) == 1:
            return required[0], ""
        matches = [i for i in ids if i.split(":", 1)[1] == ref]
        if len(matches) == 1:
            return matches[0], ""
        if matches:
            return None, f"'{ref}' is ambiguous; write one of: {', '.join(sorted(matches))}"
        candidates = sorted({i.split(":", 1)[1] for i in ids})
    close = difflib.get_close_matches(ref, candidates, n=1)
    return None, f"unknown element '{ref}'" + (f" (did you mean '{close[0]}'?)" if close else "")
