"""Validate parsed TOML with a pydantic model and turn its errors into problems.

Pydantic's messages are written for programmers; a mod author gets a short
one (``must be > 0 (got -5)``), the field path as written in the file (the
union's tag, like ``liquid``, is left out), and for unknown keys the list of
keys that are allowed there.
"""

from __future__ import annotations

import copy
import re
import types
import typing
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from .tomlsource import Loc, TomlSource

M = TypeVar("M", bound=BaseModel)

#: Friendly words for the regular expressions the models use.
PATTERN_HINTS: dict[str, str] = {}


def validate(model: type[M], source: TomlSource) -> M:
    """Validate ``source.data`` as ``model``; raise ProblemsError naming every mistake."""
    from ..errors import ProblemsError

    try:
        return model.model_validate(source.data)
    except ValidationError as exc:
        errors = exc.errors()
        problems = [_to_problem(model, source, err) for err in errors + _behind_field_mistakes(model, source.data, errors)]
        raise ProblemsError(sorted(set(problems), key=lambda p: (p.line or 0, p.path, p.message))) from None


def validate_changed(model: type[M], data: dict, source: TomlSource, at: Loc, written: set[str]) -> M:
    """Validate ``data`` as ``model``'s one field: a table that ``source`` does not state whole but
    changes at ``at`` (it wrote the fields ``written``; the rest come from elsewhere). Raise
    ProblemsError naming each mistake at ``at`` and the field's path where the file wrote that
    field, else at ``at`` itself, saying the field is not the file's."""
    from ..errors import ProblemsError

    (name,) = model.model_fields
    try:
        return model.model_validate({name: data})
    except ValidationError as exc:
        problems = []
        for err in exc.errors():
            loc = _written_loc({name: data}, tuple(err["loc"]), err["type"] == "missing")[1:]
            message = _message(model, {name: data}, (name, *loc), err)
            if not loc or loc[0] in written:  # a field written here, or the table's own check across its fields
                problems.append(source.problem((*at, *loc), message))
            else:
                problems.append(source.problem(at, f"{'.'.join(map(str, loc))} (not changed here): {message}"))
        raise ProblemsError(sorted(set(problems), key=lambda p: (p.line or 0, p.path, p.message))) from None


def _behind_field_mistakes(model: type[BaseModel], data: Any, errors: list) -> list:
    """The mistakes a table's own checks across its fields find (``burn_temperature must be at least
    ignites_at``), which pydantic makes only once every field of the table is right: found by
    validating again with each mistaken field left out. A check that names a field left out of its
    table is not reported, since it saw that field's default rather than what the file says."""
    data, left_out = copy.deepcopy(data), set()
    for err in errors:
        loc = tuple(err["loc"])
        if err["type"] == "missing" or "[key]" in loc:
            continue
        written = _written_loc(data, loc)
        parent = _at(data, written[:-1])
        if written and isinstance(parent, dict) and written[-1] in parent:  # not where a mistake left out a table
            del parent[written[-1]]
            left_out.add((written[:-1], str(written[-1])))
    if not left_out:
        return []
    try:
        model.model_validate(data)
        return []
    except ValidationError as again:
        return [err for err in again.errors() if err["type"] == "value_error" and not _names_one_left_out(err, data, left_out)]


def _names_one_left_out(err: Any, data: Any, left_out: set[tuple[Loc, str]]) -> bool:
    table = _written_loc(data, tuple(err["loc"]))
    return any(where == table and re.search(rf"\b{re.escape(name)}\b", err["msg"]) for where, name in left_out)


def _at(data: Any, loc: Loc) -> Any:
    """What ``data`` holds at ``loc``, or None where nothing is."""
    for part in loc:
        try:
            data = data[part]
        except (KeyError, IndexError, TypeError):
            return None
    return data


def _to_problem(model: type[BaseModel], source: TomlSource, err: Any):
    raw = tuple(err["loc"])
    is_key = "[key]" in raw  # the error is in a table's key, not its value
    loc = _written_loc(source.data, raw[: raw.index("[key]")] if is_key else raw, err["type"] == "missing")
    if err["type"] == "union_tag_invalid":
        loc += (err["ctx"]["discriminator"].strip("'"),)
    message = _message(model, source.data, loc, err)
    if err["type"] == "grid":  # a row of a test's drawn scene: point at that row's line
        return source.problem(loc + (err["ctx"]["field"],), message, row=err["ctx"].get("row"))
    return source.problem(loc, f"invalid name: {message}" if is_key else message)


def _written_loc(data: Any, loc: tuple, missing: bool = False) -> Loc:
    """Drop the parts of pydantic's location that are not in the file: union tags and the labels
    of union members (``constrained-str``); a last part not in the file stays when ``missing``."""
    kept: list[str | int] = []
    current = data
    for number, part in enumerate(loc):
        if isinstance(current, dict):
            if part not in current and not (missing and number == len(loc) - 1):
                continue  # a discriminated union's tag ("liquid") or a member's label
            current = current.get(part)
        elif isinstance(current, list) and isinstance(part, int) and 0 <= part < len(current):
            current = current[part]
        elif current is not None:
            break  # past a plain value only union member labels remain
        kept.append(part)
    return tuple(kept)


def _message(model: type[BaseModel], data: Any, loc: Loc, err: Any) -> str:
    kind, ctx, value = err["type"], err.get("ctx", {}), err.get("input")
    got = f" (got {_show(value)})"
    if kind == "missing":
        return "required field is missing"
    if kind == "extra_forbidden":
        allowed = _allowed_fields(model, data, loc[:-1])
        return "unknown field" + (f"; allowed here: {', '.join(allowed)}" if allowed else "")
    comparisons = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}
    if kind in comparisons:
        bound = next(iter(ctx.values()))
        shown = str(bound) if isinstance(bound, int) else f"{bound:g}"  # 1000000, not 1e+06
        return f"must be {comparisons[kind]} {shown}{got}"
    if kind == "string_pattern_mismatch":
        return PATTERN_HINTS.get(ctx.get("pattern", ""), f"must match {ctx.get('pattern')}") + got
    if kind == "union_tag_invalid":
        return f"must be one of {ctx.get('expected_tags')} (got {_show(ctx.get('tag'))})"
    if kind == "union_tag_not_found":
        return f"required field '{ctx.get('discriminator', '').strip(chr(39))}' is missing"
    if kind in ("value_error", "assertion_error"):
        return str(ctx.get("error", err["msg"]))
    msg = err["msg"]
    if msg.startswith("Input should be "):
        return "must be " + msg[len("Input should be "):] + got
    return msg[0].lower() + msg[1:]


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _allowed_fields(model: type[BaseModel], data: Any, loc: Loc) -> list[str]:
    """The field names of the model that validates the table at ``loc``."""
    target: Any = model
    current = data
    for part in loc:
        target = _inner(target, current)
        if isinstance(target, type) and issubclass(target, BaseModel):
            field = target.model_fields.get(str(part))
            if field is None:
                return []
            target = field.annotation
        else:
            origin = typing.get_origin(target)
            args = typing.get_args(target)
            if origin in (dict, list) and args:
                target = args[-1]
            else:
                return []
        current = current.get(part) if isinstance(current, dict) else (
            current[part] if isinstance(current, list) and isinstance(part, int) and part < len(current) else None
        )
    target = _inner(target, current)
    if isinstance(target, type) and issubclass(target, BaseModel):
        return list(target.model_fields)
    return []


def _inner(target: Any, value: Any) -> Any:
    """Unwrap Annotated/Optional/Union down to the model that fits ``value``."""
    while True:
        origin = typing.get_origin(target)
        if origin is typing.Annotated:
            target = typing.get_args(target)[0]
        elif origin in (typing.Union, types.UnionType):
            models = [a for a in typing.get_args(target) if isinstance(a, type) and issubclass(a, BaseModel)]
            if not models:
                return target
            target = _pick_union_member(models, value)
        else:
            return target


def _pick_union_member(models: list[type[BaseModel]], value: Any) -> type[BaseModel]:
    if isinstance(value, dict):
        for candidate in models:
            for name, field in candidate.model_fields.items():
                literal = field.annotation
                if typing.get_origin(literal) is typing.Literal and value.get(name) in typing.get_args(literal):
                    return candidate
    return models[0]
