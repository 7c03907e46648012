"""The generated reference pages: up to date with the code, and covering all of it."""

from __future__ import annotations

import html
import inspect
import re
from pathlib import Path
from typing import Annotated

import pytest
import reference
from pydantic import BaseModel, TypeAdapter

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
        if f"></a>`{field.alias or name}` |" not in text and not (name in ("archetype", "shape") and f'{name} = "' in text)  # a kind's heading
    ]
    assert len(_models(module)) >= 5 and not missing


def test_the_world_reference_lists_each_shape_once():
    text = reference.file_reference("world")
    for shape in ("rect", "circle", "line", "stroke", "fill", "image"):
        assert text.count(f'### shape = "{shape}"') == 1 and f"(#shape-{shape})" in text


def test_the_file_reference_says_types_ranges_and_defaults():
    text = reference.file_reference("mod")
    assert '<a id="elements-name-powder-density"></a>`density` | number, > 0, ≤ 100000<br>required |' in text
    assert "`friction` | number, ≥ 0.0, ≤ 4.0<br>default `0.6` |" in text
    assert '#### archetype = "powder"' in text and "### `[[reactions]]`" in text and "### `[elements.NAME.flammable]`" in text
    assert '`from` | list of integer, 2 long<br>required |' in reference.file_reference("world")  # the key as written, not the field's name


@pytest.mark.parametrize("kind", ["mod", "world", "sweep"])
def test_every_field_of_the_file_references_has_an_anchor_of_its_own(kind):
    rows = [line for line in reference.file_reference(kind).splitlines() if line.startswith("| ") and "`" in line.split("|")[1]]
    anchors = [re.match(r'\| <a id="([a-z0-9-]+)"></a>`', row) for row in rows]
    assert all(anchors) and len({a.group(1) for a in anchors}) == len(anchors)


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


def _entries(text: str) -> dict[str, str]:
    """Each heading's name and the text under it, to the next heading."""
    parts = re.split(r"^#{3,4} `([^`]+)`(?: \{#[a-z0-9-]+\})?\n", text, flags=re.M)
    return dict(zip(parts[1::2], parts[2::2]))


def test_the_api_reference_has_an_entry_with_text_for_every_public_name_method_and_hook():
    entries = _entries(reference.api_reference())
    wanted = [f"sandmod.{name}" for name in sandmod.__all__ if name != "__version__"] + [f"sandmod.api.{name}" for name in api.__all__]
    wanted += reference.hook_names() + [f"sandmod.World.{m}" for m in ("step", "run", "paint_shape", "counts", "temperature", "image", "save_snapshot", "load_snapshot")]
    assert len(reference.hook_names()) == 6
    assert [name for name in wanted if name not in entries] == []
    assert [name for name, body in entries.items() if not re.sub(r'<pre class="signature"><code>.*?</code></pre>', "", body, flags=re.S).strip()] == []


def test_the_api_reference_shows_nothing_private_or_internal():
    text = reference.api_reference()
    assert [name for name in _entries(text) if "._" in name or name.startswith("_")] == []
    for internal in ("salt", "sandmod.engine", "sandmod.formats", "sandmod.world.", "sandmod.errors", "tests/", "<factory>", "_F"):
        assert internal not in text, internal


def test_the_gallery_has_a_page_for_every_example_world_and_the_site_lists_them():
    nav = (reference.ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    names = reference.example_worlds()
    assert len(names) >= 10 and "seeds" not in names  # a sweep is not a world
    for name in names:
        assert f"docs/gallery/{name}.md" in reference.PAGES and f"gallery/{name}.md" in nav
        assert reference._render_command(name), f"no page says how docs/images/{name}.webp is made"


def test_the_file_references_show_real_examples_that_read_as_toml():
    import tomllib

    examples = re.findall(r"<br>Example: `([a-z_]+ = [^`]+)` \|$", reference.file_reference("mod") + "\n" + reference.file_reference("world"), re.M)
    assert len(examples) >= 100
    for example in examples:
        tomllib.loads(example.replace("\\|", "|"))
    assert "`density = 1600`" in reference.file_reference("mod") or "`density = 1400`" in reference.file_reference("mod") or "`density = 2400`" in reference.file_reference("mod")


@pytest.mark.parametrize("kind", ["mod", "world", "sweep"])
def test_every_field_of_the_file_references_has_an_example(kind):
    rows = [line for line in reference.file_reference(kind).splitlines() if line.startswith("| <a id=")]
    assert rows and [row.split("`")[1] for row in rows if not re.search(r"<br>(Example: `|Its table: \[)", row)] == []


def test_every_example_a_model_gives_is_a_value_its_field_takes():
    checked = 0
    for module in (modspec, sweepspec, worldspec):
        for model in vars(module).values():
            if isinstance(model, type) and issubclass(model, BaseModel) and model.__module__ == module.__name__:
                for name, field in model.model_fields.items():
                    for example in field.examples or []:
                        kind = Annotated[field.annotation, *field.metadata] if field.metadata else field.annotation
                        TypeAdapter(kind).validate_python(example)
                        checked += 1
    assert checked >= 60


@pytest.mark.parametrize("kind", ["mod", "world", "sweep"])
def test_every_link_within_a_file_reference_lands_on_an_anchor_of_it(kind):
    text = reference.file_reference(kind)
    anchors = set(re.findall(r'id="([^"]+)"', text)) | set(re.findall(r"\{#([^}]+)\}", text))
    links = re.findall(r"\]\(#([^)]+)\)", text)
    assert links and sorted(set(links) - anchors) == []


#: Names a signature may use that are Python's, typing's or pathlib's, not sandmod's (numpy's come as np.NAME).
_NOT_SANDMODS = {"Any", "Callable", "False", "Iterable", "Literal", "Mapping", "None", "Path", "Sequence", "True"}


def _codes(text: str) -> list[str]:
    """The signatures and definitions the reference shows as code, as HTML."""
    return re.findall(r'<pre class="signature"><code>(.*?)</code></pre>', text, flags=re.S)


def test_every_type_a_signature_or_hook_names_is_importable_from_sandmod_or_sandmod_api_and_linked():
    codes = _codes(reference.api_reference())
    assert len(codes) >= 40 and any("register_metrics(" in code for code in codes)
    for code in codes:
        plain = html.unescape(re.sub(r"<[^>]+>", "", code))
        for name in set(re.findall(r"(?<![\w.'])[A-Z]\w*", plain)) - _NOT_SANDMODS:
            assert hasattr(sandmod, name) or hasattr(api, name), f"{name}, in {plain}"
            assert re.search(rf'<a href="#sandmod-[a-z-]+">{name}</a>', code), f"{name} is not linked in {plain}"


def test_every_link_within_the_api_reference_lands_on_an_anchor_of_it():
    text = reference.api_reference()
    anchors = set(re.findall(r'id="([^"]+)"', text)) | set(re.findall(r"\{#([^}]+)\}", text))
    links = re.findall(r'href="#([^"]+)"', text)
    assert links and sorted(set(links) - anchors) == []


def _public_attributes(cls: type, *instances) -> set[str]:
    """What a reader can get from a class or its objects: its fields, annotated names, properties
    and instance attributes, none private."""
    names = set(getattr(cls, "model_fields", {}))
    for klass in cls.__mro__:
        if klass.__module__.startswith("sandmod"):
            names |= set(vars(klass).get("__annotations__", {}))
            names |= {n for n, v in vars(klass).items() if isinstance(v, property)}
    for instance in instances:
        names |= set(vars(instance))
    return {name for name in names if not name.startswith("_")}


def test_every_public_attribute_of_every_public_class_has_a_row_with_its_type_and_a_line():
    from sandmod.api import ProblemsError, SavedAtClose, VideoSettings

    loaded = sandmod.load_world(reference.ROOT / "examples" / "hourglass.toml")  # paints its scene; steps nothing
    made = {
        sandmod.LoadedWorld: [loaded], sandmod.World: [loaded.world], sandmod.Ruleset: [loaded.ruleset],
        ProblemsError: [ProblemsError([])], SavedAtClose: [SavedAtClose(Path("x.webp"), VideoSettings(1, 1, bytes(768), 10.0))],
    }
    text = reference.api_reference()
    rows = dict(re.findall(r'^\| <a id="([a-z0-9-]+)"></a>`\w+` \| (.*) \|$', text, flags=re.M))
    checked, seen = 0, set()
    for name, thing in reference._public_names():
        if inspect.isclass(thing) and thing not in seen:  # a second name's entry points to the first
            seen.add(thing)
            for attribute in _public_attributes(thing, *made.get(thing, [])):
                row = rows.get(reference._slug(f"{name}.{attribute}"), "")
                kind, _, what = row.partition(" | ")
                assert re.fullmatch(r"<code>.+</code>", kind) and what.strip(), f"{name}.{attribute}: {row!r}"
                checked += 1
    assert checked >= 60 and {"sandmod-world-width", "sandmod-world-state", "sandmod-loadedworld-world", "sandmod-api-explosion-radius"} <= set(rows)


def test_an_alias_of_a_type_shows_its_definition():
    entries = _entries(reference.api_reference())
    assert '<a href="#sandmod-api-modloader">ModLoader</a> = Callable[[Path], <a href="#sandmod-api-tomlsource">TomlSource</a>]' in entries["sandmod.api.ModLoader"]
    assert "Metric</a> = Callable[[<a href=\"#sandmod-world\">World</a>], float | Mapping[str, float]]" in entries["sandmod.api.Metric"]


@pytest.mark.parametrize("page", sorted(page for page in reference.PAGES if page.startswith("docs/reference/")))
def test_no_generated_reference_has_an_empty_table(page):
    lines = reference.PAGES[page]().splitlines() + [""]
    headers = [number for number, line in enumerate(lines) if re.fullmatch(r"\|(---\|)+", lines[number + 1] if number + 1 < len(lines) else "")]
    assert headers and [lines[n] for n in headers if not lines[n + 2].startswith("|")] == []


def test_the_gallery_index_shows_each_example_world_as_a_picture_with_its_name_and_a_line_linking_to_its_page():
    text = reference.gallery_index()
    cards = re.findall(r"^-   \[!\[[^\]]+\]\(\.\./images/(\w+)\.webp\)\{ loading=lazy \}\]\((\w+)\.md \"made by sandmod render [^\"]+\"\)\n\n"
                       r"    \*\*\[[^\]]+\]\((\w+)\.md\)\*\*: \S.*[.!?]$", text, flags=re.M)
    assert [(name, name, name) for name in reference.example_worlds()] == cards
    for name in reference.example_worlds():
        assert (reference.ROOT / "docs" / "images" / f"{name}.webp").is_file()
