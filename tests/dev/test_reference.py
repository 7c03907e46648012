"""The generated reference pages: up to date with the code, and covering all of it."""

from __future__ import annotations

import inspect

import pytest
import reference
from pydantic import BaseModel

import sandmod
from sandmod import api
from sandmod.formats import modspec, sweepspec, worldspec
from sandmod.tools.cli import cli


@pytest.mark.parametrize("page", sorted(reference.PAGES))
def test_each_generated_page_is_up_to_date(page):
    written = (reference.ROOT / page).read_text(encoding="utf-8")
    assert written == reference.page_text(page), f"{page} is out of date: run python tools/dev/reference.py"


def _models(module) -> list[type[BaseModel]]:
    """The models a module defines that a file's table is validated by (not the private bases)."""
    return [
        thing
        for name, thing in vars(module).items()
        if inspect.isclass(thing) and issubclass(thing, BaseModel) and thing.__module__ == module.__name__ and not name.startswith("_")
    ]


@pytest.mark.parametrize("module, kind", [(modspec, "mod"), (worldspec, "world"), (sweepspec, "sweep")])
def test_the_file_reference_has_a_row_for_every_field_of_every_model(module, kind):
    text = reference.file_reference(kind)
    missing = [
        f"{model.__name__}.{name}"
        for model in _models(module)
        for name, field in model.model_fields.items()
        if f"| `{field.alias or name}` |" not in text
    ]
    assert len(_models(module)) >= 5 and not missing


def test_the_file_reference_says_types_ranges_and_defaults():
    text = reference.file_reference("mod")
    assert "| `density` | number | required | > 0, ≤ 100000 |" in text
    assert "| `friction` | number | `0.6` | ≥ 0.0, ≤ 4.0 |" in text
    assert '#### archetype = "powder"' in text and "### `[[reactions]]`" in text and "### `[elements.NAME.flammable]`" in text
    assert '| `from` | list of integer | required |' in reference.file_reference("world")  # the key as written, not the field's name


def _commands(group, prefix="sandmod"):
    for name, command in group.commands.items():
        yield f"{prefix} {name}", command
        if hasattr(command, "commands"):
            yield from _commands(command, f"{prefix} {name}")


def test_the_cli_reference_has_every_command_and_option():
    text = reference.cli_reference()
    for name, command in _commands(cli):
        assert f"### `{name}`" in text
        for param in command.params:
            if not getattr(param, "hidden", False) and param.name != "help":
                shown = f"`{param.opts[0]}`" if param.param_type_name == "option" else f"`{param.human_readable_name}`"
                assert shown in text, f"{name} {shown}"


def test_the_api_reference_has_every_public_name_and_worlds_methods():
    text = reference.api_reference()
    for name in sandmod.__all__[1:]:
        assert f"sandmod.{name}" in text
    for name in api.__all__:
        assert f"sandmod.api.{name}" in text
    for method in ("step", "run", "paint_shape", "counts", "temperature", "image", "save_snapshot", "load_snapshot"):
        assert f"`sandmod.World.{method}(" in text
