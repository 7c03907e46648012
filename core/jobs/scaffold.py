"""``sandmod new``: write commented, valid mod files to start from.

Values are written with tomli-w; every parameter gets its description from
the pydantic models as a comment, so the file documents itself.
"""

from __future__ import annotations

import textwrap
import typing
from typing import Any

import tomli_w
from pydantic import BaseModel

from ..formats.modspec import ARCHETYPES, Element, ModFile
from ..formats.tomlsource import TomlSource
from ..formats.validation import validate

#: The parameters written for a new element, in this order, where its archetype has them.
WRITTEN = (
    "description", "color", "shade", "density", "dispersion", "viscosity", "gravity", "max_speed", "friction",
    "impact_spread", "inertial_resistance", "drag", "carries", "temperature", "heat_capacity", "conductivity",
)  # fmt: skip
#: What --like copies: parameters, not references to other elements (which the new mod may not load).
COPIED = tuple(k for k in WRITTEN if k not in ("description", "carries"))
COPIED_IF_SET = ("tags", "ignites", "extinguishes", "cooling", "explosion_resistance")
#: Values for the parameters an archetype requires, when no --like element gives them.
STARTING_VALUES: dict[str, dict[str, Any]] = {
    "static": {"color": ["#8a8f98", "#7d828b"]},
    "powder": {"color": ["#c9a66b", "#bf9a5e"], "density": 1500},
    "liquid": {"color": ["#3f7fd6", "#4a8ae0"], "density": 1000, "dispersion": 3},
    "gas": {"color": ["#d8dde3", "#c8cfd6"], "density": 0.8, "dispersion": 2},
    "particle": {"color": "#f0e6c8"},
}
#: Optional features, written commented out as examples to switch on.
EXAMPLES = (
    ('tags = ["wet"]', "tags"),
    ('lifetime = { frames = 600, jitter = 200, becomes = "empty" }', "lifetime"),
    ('heated = { above = 100, becomes = "steam" }', "heated"),
    ('cooled = { below = 0, becomes = "ice" }', "cooled"),
    ('flammable = { ignites_at = 300, burn_time = 120, flame = "fire" }', "flammable"),
)
CREATABLE = tuple(a for a in ARCHETYPES if a != "empty")


def _model(archetype: str) -> type[BaseModel]:
    """The element model of an archetype (a member of the ``Element`` union)."""
    union = typing.get_args(Element)[0]  # Element is Annotated[Union[...], Field(discriminator=...)]
    return next(m for m in typing.get_args(union) if typing.get_args(m.model_fields["archetype"].annotation) == (archetype,))


def _comment(text: str) -> str:
    return "\n".join(textwrap.wrap(text, 96, initial_indent="# ", subsequent_indent="# "))


def _line(key: str, value: Any) -> str:
    """``key = value`` written by tomli-w; a table becomes an inline table."""
    return f"{tomli_w.dumps({key: 0}).split('=')[0].strip()} = {_value(value)}"


def _value(value: Any) -> str:
    """A value in TOML, on one line: tables inline, arrays on one line."""
    if isinstance(value, dict):
        return "{ " + ", ".join(_line(k, v) for k, v in value.items() if v is not None) + " }"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return tomli_w.dumps({"v": value}).split("=", 1)[1].strip()


def mod_header(name: str, description: str, requires: list[str]) -> str:
    info = {"name": name, "version": "0.1.0", "description": description, "requires": requires}
    fields = ModFile.model_fields["mod"].annotation.model_fields
    lines = ["[mod]"]
    for key, value in info.items():
        lines += [_comment(fields[key].description), _line(key, value)]
    return "\n".join(lines) + "\n"


def element_block(name: str, archetype: str, like: BaseModel | None = None) -> str:
    """``[elements.NAME]`` with every usual parameter of ``archetype``, commented."""
    model = _model(archetype)
    values: dict[str, Any] = {"archetype": archetype, **STARTING_VALUES[archetype]}
    if like is not None:
        wanted = (set(COPIED) | (like.model_fields_set & set(COPIED_IF_SET))) & set(model.model_fields)
        values.update(like.model_dump(include=wanted, exclude_none=True))
    values.setdefault("description", f"{name.replace('_', ' ').capitalize()}: say what it is and what it does.")
    lines = [f"[elements.{name}]", _comment("How it moves: " + ", ".join(CREATABLE) + "."), _line("archetype", archetype)]
    for key in [*WRITTEN, *(k for k in values if k not in WRITTEN)]:
        if key == "archetype" or key not in model.model_fields:
            continue
        field = model.model_fields[key]
        value = values.get(key, field.default)
        if value is None or (key not in values and field.is_required()):
            continue
        lines += ["", _comment(field.description or key), _line(key, value)]
    examples = [text for text, key in EXAMPLES if key not in values]
    if examples:
        lines += ["", "# More it can do (remove the # to switch one on; 'sandmod schema' documents them all):"]
        lines += [f"# {text}" for text in examples]
    return "\n".join(lines) + "\n"


def test_block(element: str, archetype: str = "powder") -> str:
    """A first ``[[tests]]`` entry for ``element``: it is still there after a few frames
    (a particle carrying nothing is gone once it lands)."""
    if archetype == "particle":
        name, said, check = "vanishes", "falls and is gone once it lands (it carries nothing)", f'absent = ["{element}"]'
    else:
        name, said, check = "exists", "is still there a few frames later", f'present = ["{element}"]'
    return textwrap.dedent(
        f'''\
        # A test of the element: the scene, drawn with the legend's characters, runs for
        # `frames` frames; then every expectation must hold. Run it with `sandmod test` or pytest.
        [[tests]]
        name = "{element}_{name}"
        description = "A cell of {element} in a stone box {said}."
        frames = 10
        legend = {{ X = "{element}", "#" = "stone" }}
        scene = """
        #######
        #.....#
        #..X..#
        #.....#
        #######
        """
        {check}
        # expect = """...""" (the exact cells at the end, '?' matches any), count = {{ {element} = 1 }},
        # absent = ["..."], temperature = {{ {element} = {{ min = 0, max = 100 }} }}
        '''
    )


def new_mod(name: str, archetype: str = "powder", like: BaseModel | None = None) -> str:
    """A new mod file: the [mod] table, one element named after the mod ('my-mod' makes 'my_mod'), and a test."""
    element = name.replace("-", "_")
    header = mod_header(name, f"{element.replace('_', ' ').capitalize()}: what this mod adds.", [])
    return f"{header}\n{element_block(element, archetype, like)}\n{test_block(element, archetype)}"


def add_element(text: str, origin: str, name: str, archetype: str, like: BaseModel | None = None) -> str:
    """``text`` (a mod file) with a new element and its test appended; ProblemsError if the result is not valid."""
    combined = text.rstrip("\n") + f"\n\n{element_block(name, archetype, like)}\n{test_block(name, archetype)}"
    check(combined, origin)
    return combined


def check(text: str, origin: str) -> ModFile:
    """Parse and validate a mod file's text."""
    return validate(ModFile, TomlSource.parse(text, origin))


def new_world(size: tuple[int, int], mods: list[str] | None, made_with: dict[str, str], pour: str) -> str:
    """A world file: a stone floor, an emitter pouring ``pour``, and the mods it is made with."""
    width, height = size
    world: dict[str, Any] = {"width": width, "height": height, "seed": 0}
    if mods is not None:
        world["mods"] = mods
    lines = ["# A world for 'sandmod render'. (0, 0) is the top-left cell; y grows downwards.", "[world]"]
    lines += [_line(k, v) for k, v in world.items()]
    lines += [
        "",
        "# The mods and versions this world was made with: loading it with others prints a warning.",
        "[world.made_with]",
        *(_line(k, v) for k, v in made_with.items()),
        "",
        "# Shapes painted before the first frame, in order: rect, circle, line, fill.",
        "[[scene]]",
        *(_line(k, v) for k, v in {"shape": "rect", "element": "stone", "x": 0, "y": height - 8, "width": width, "height": 8}.items()),
        "",
        "# Shapes that pour an element while start <= frame < stop.",
        "[[emitters]]",
        *(
            _line(k, v)
            for k, v in {"shape": "circle", "element": pour, "x": width // 2, "y": 8, "radius": 3, "start": 0, "stop": 200, "chance": 0.5}.items()
        ),
        "",
        "[render]",
        _line("frames", 300),
        _line("every", 2),
        _line("scale", 3),
    ]
    return "\n".join(lines) + "\n"


def check_world(text: str, origin: str):
    """Parse and validate a world file's text."""
    from ..formats.worldspec import WorldFile

    return validate(WorldFile, TomlSource.parse(text, origin))


SWEEP = """\
# A sweep for 'sandmod batch': every world x seed x combination of parameters is a run.
# Run it with: sandmod batch {name}.toml -j 2

[sweep]
# World files, or globs of them, relative to this file.
worlds = [{world}]
# Seeds: a list, or a range: {{ from = 0, to = 99 }}.
seeds = {{ from = 0, to = 3 }}
# Frames each run simulates (default: each world's own).
frames = 300

# A grid of values by dotted path: 'elements.NAME.FIELD' changes a mod's element,
# 'world.FIELD' or 'render.FIELD' each world. Every combination is a run.
[parameters]
"elements.sand.friction" = [0.3, 0.6, 1.2]

[record]
# An animation of each run (gif, webp, apng, png-frames, a plugin's), or "none".
format = "none"
# Frames at which to save the whole state as a snapshot.
snapshots = []

[metrics]
# Frames at which to measure (default: the last). Each metric is a column NAME@FRAME of
# results.csv: count.ELEMENT, centre_x/y.ELEMENT, height/width.ELEMENT, awake, heat, plugins'.
frames = [100, 300]
"""


def new_sweep(name: str, world: str) -> str:
    """A commented sweep file over ``world``, valid as written."""
    return SWEEP.format(name=name, world=tomli_w.dumps({"w": world}).split(" = ", 1)[1].strip())
