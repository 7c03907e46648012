"""The mod format: bundled mods are valid; each mistake is one line naming file, line and field."""

from __future__ import annotations

import pytest

from sandmod.errors import ProblemsError
from sandmod.formats.modspec import LiquidElement, ModFile
from sandmod.plugins.toml_mods import bundled_mods_dir
from sandmod.formats.tomlsource import TomlSource
from sandmod.formats.validation import validate


def check(text: str) -> list[str]:
    """Validate mod text; the problems as printed (empty when valid)."""
    try:
        validate(ModFile, TomlSource.parse(text, "m.toml"))
    except ProblemsError as exc:
        return [str(p) for p in exc.problems]
    return []


HEAD = '[mod]\nname = "m"\n\n'


def test_every_bundled_mod_is_valid():
    files = sorted(bundled_mods_dir().glob("*.toml"))
    assert {f.stem for f in files} >= {"base", "sand", "water", "lava", "acid", "titanium", "fire", "wood", "explosives"}
    for path in files:
        validate(ModFile, TomlSource.read(path))


def test_a_valid_mod_parses_into_its_archetype():
    spec = validate(
        ModFile,
        TomlSource.parse(HEAD + '[elements.goo]\narchetype = "liquid"\ncolor = "#00ff00"\ndensity = 900\ndispersion = 2\n', "m"),
    )
    goo = spec.elements["goo"]
    assert isinstance(goo, LiquidElement)
    assert goo.color == ["#00ff00"] and goo.dispersion == 2 and goo.viscosity == 0.0


@pytest.mark.parametrize(
    "body, expected",
    [
        (
            '[elements.lava]\narchetype = "liquid"\ncolor = "#ff0000"\ndensity = -5\ndispersion = 1\n',
            "m.toml:7:1: elements.lava.density: must be > 0 (got -5)",
        ),
        (
            '[elements.lava]\narchetype = "liquid"\ncolor = "#ff0000"\ndensity = 5\ndispersion = 1\nglow = true\n',
            "m.toml:9:1: elements.lava.glow: unknown field; allowed here: description, color, shade, tags, "
            "category, hidden, lifetime, shows_held, override, like, temperature, heat_capacity, conductivity, cooling, heated, cooled, melts, freezes, flammable, "
            "explosion, explosion_resistance, breaks_into, breaks_on_impact, ignites, extinguishes, behaviour, behaviour_args, archetype, density, dispersion, viscosity, "
            "gravity, max_speed",
        ),
        (
            '[elements.rock]\narchetype = "stony"\ncolor = "#333333"\n',
            "m.toml:5:1: elements.rock.archetype: must be one of 'empty', 'static', 'powder', 'liquid', 'gas', 'particle' (got 'stony')",
        ),
        ('[elements.dust]\narchetype = "powder"\ncolor = "#111111"\n', "m.toml:4:1: elements.dust.density: required field is missing"),
        ('[elements.dust]\ncolor = "#111111"\n', "m.toml:4:1: elements.dust: required field 'archetype' is missing"),
        (
            '[elements.wall]\narchetype = "static"\ncolor = "#12345"\n',
            "m.toml:6:1: elements.wall.color: must be a colour like '#c2b280' (got '#12345')",
        ),
        (
            '[elements.wall]\narchetype = "static"\ncolor = "#123456"\ndispersion = 3\n',
            "m.toml:7:1: elements.wall.dispersion: unknown field; allowed here: description, color, shade, tags, "
            "category, hidden, lifetime, shows_held, override, like, temperature, heat_capacity, conductivity, cooling, heated, cooled, melts, freezes, flammable, "
            "explosion, explosion_resistance, breaks_into, breaks_on_impact, ignites, extinguishes, behaviour, behaviour_args, archetype",
        ),
        (
            '[elements.x]\narchetype = "static"\ncolor = "#123456"\nheated = { above = 100 }\n',
            "m.toml:7:1: elements.x.heated.becomes: required field is missing",
        ),
        (
            '[elements.x]\narchetype = "static"\ncolor = "#123456"\ncategory = "Fire Stuff"\n',
            "m.toml:7:1: elements.x.category: must be a lower-case name like 'acid_proof' (got 'Fire Stuff')",
        ),
        (
            '[elements.x]\narchetype = "static"\ncolor = "#123456"\ntemperature = -300\n',
            "m.toml:7:1: elements.x.temperature: must be >= -273 (got -300)",
        ),
        (
            '[elements.x]\narchetype = "static"\ncolor = "#123456"\n[elements.x.flammable]\nignites_at = 500\nburn_temperature = 300\n',
            "m.toml:7:1: elements.x.flammable: burn_temperature must be at least ignites_at, or the fire would go out at once",
        ),
        (
            '[elements.x]\narchetype = "static"\ncolor = "#123456"\n[elements.x.explosion]\nradius = 40\nstrength = 2\n',
            "m.toml:8:1: elements.x.explosion.radius: must be <= 32 (got 40)",
        ),
        (
            '[elements.x]\narchetype = "static"\ncolor = "#1234ff"\n[elements.x.explosion]\nradius = 4\nstrength = 2\n',
            "m.toml:4:1: elements.x: an explosive element needs 'flammable' (ignites_at, catch_chance) to say when it goes off",
        ),
        (
            '[[reactions]]\na = "x"\nb = "y"\na_becomes = "z"\nchance = 1\nmin_temperature = 50\nmax_temperature = 10\n',
            "m.toml:4:1: reactions.0: min_temperature must not be above max_temperature",
        ),
        (
            '[elements.Wall]\narchetype = "static"\ncolor = "#123456"\n',
            "m.toml:4:1: elements.Wall: invalid name: must be an element name like 'sand' or 'base:stone' "
            "(lower case, digits, _) (got 'Wall')",
        ),
        (
            '[[reactions]]\na = "x"\nb = "#wet stuff"\na_becomes = "y"\nchance = 2\n',
            "m.toml:6:1: reactions.0.b: must be an element ('water'), a tag ('#metal'), '*', or one of those after '!' "
            "(got '#wet stuff')",
        ),
        ('[[reactions]]\na = "x"\nb = "y"\nchance = 0.5\n', "m.toml:4:1: reactions.0: a reaction needs a_becomes, b_becomes, a_holds, b_holds or push"),
        (
            '[elements.fog]\narchetype = "gas"\ncolor = "#eeeeee"\ndensity = 1\ndispersion = 2\n'
            'lifetime = { frames = 0, becomes = "empty" }\n',
            "m.toml:9:14: elements.fog.lifetime.frames: must be >= 1 (got 0)",
        ),
    ],
)
def test_each_mistake_is_one_line_with_file_line_and_field(body, expected):
    assert expected in check(HEAD + body)


def test_every_problem_in_a_file_is_reported_at_once():
    problems = check(
        HEAD
        + '[elements.a]\narchetype = "powder"\ncolor = "#111111"\ndensity = 0\n\n'
        + '[elements.b]\narchetype = "liquid"\ncolor = "#111111"\ndensity = 10\ndispersion = 99\n'
    )
    assert problems == [
        "m.toml:7:1: elements.a.density: must be > 0 (got 0)",
        "m.toml:13:1: elements.b.dispersion: must be <= 16 (got 99)",
    ]


def test_missing_mod_table_and_bad_mod_name():
    assert check('[elements]\n') == ["m.toml: mod: required field is missing"]
    assert check('[mod]\nname = "My Mod"\n') == [
        "m.toml:2:1: mod.name: must be a mod name like 'sand' or 'my-mod' (lower case, digits, _ and -) (got 'My Mod')"
    ]


def test_invalid_toml_names_its_line():
    assert check('[mod]\nname = "m"\ncolor = #fff\n') == ["m.toml:3:9: invalid TOML: Invalid value"]


def test_the_archetypes_are_one_list():
    import typing

    from sandmod.formats import modspec
    from sandmod.engine.layout import ARCHETYPES

    members = typing.get_args(typing.get_args(modspec.Element)[0])
    assert tuple(typing.get_args(m.model_fields["archetype"].annotation)[0] for m in members) == ARCHETYPES
