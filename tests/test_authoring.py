"""Tools for mod authors: new, schema, validate in one pass, version ranges, provenance, made_with."""

from __future__ import annotations

import json
import tomllib

import pytest
from click.testing import CliRunner

from sandmod.errors import ProblemsError
from sandmod.rules.modset import find_mods
from sandmod.jobs.modtests import TestRunner
from sandmod.tools.cli import cli

from conftest import write_mods


def invoke(*args: str):
    return CliRunner().invoke(cli, list(args))


def test_new_mod_and_elements_are_valid_commented_and_pass_their_tests(registry, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert invoke("new", "mod", "goo").stdout == "wrote mods/goo.toml\n"
    for args in (["slime", "--like", "water", "--mod", "mods/goo.toml"], ["spark", "--archetype", "particle"], ["wall", "--archetype", "static"]):
        assert invoke("new", "element", *args).exit_code == 0
    text = (tmp_path / "mods" / "goo.toml").read_text()
    assert "# Mass per volume in kg/m3" in text and "# lifetime = {" in text
    data = tomllib.loads(text)
    assert data["elements"]["goo"]["archetype"] == "powder"
    slime = data["elements"]["slime"]
    assert slime["archetype"] == "liquid" and slime["dispersion"] == 4 and slime["heat_capacity"] == 4.0
    assert "heated" not in slime  # references to water's elements are not copied
    assert [t["name"] for t in data["tests"]] == ["goo_exists", "slime_exists"]
    runner = TestRunner(find_mods(registry, [tmp_path / "mods"]))
    outcomes = [runner.run(case) for case in runner.cases(["goo", "spark", "wall"])]
    assert [o.case.id for o in outcomes if o.passed] == ["goo:goo_exists", "goo:slime_exists", "spark:spark_vanishes", "wall:wall_exists"]


def test_new_never_overwrites_and_checks_names(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    invoke("new", "mod", "goo")
    before = (tmp_path / "mods" / "goo.toml").read_text()
    again = invoke("new", "mod", "goo")
    assert again.exit_code == 2 and again.stderr == "mods/goo.toml: already exists; not overwriting it\n"
    twice = invoke("new", "element", "goo", "--mod", "mods/goo.toml")
    assert twice.exit_code == 2 and "'goo' is already in this mod" in twice.stderr
    assert (tmp_path / "mods" / "goo.toml").read_text() == before
    assert invoke("new", "element", "Bad").exit_code == 2
    assert "unknown element 'watr'" in invoke("new", "element", "x", "--like", "watr").stderr


def test_schema_describes_the_mod_format(tmp_path):
    out = tmp_path / "mod.schema.json"
    assert invoke("schema", "-o", str(out)).exit_code == 0
    schema = json.loads(out.read_text())
    assert schema["title"] == "sandmod mod file" and schema["additionalProperties"] is False
    assert set(schema["properties"]) == {"mod", "elements", "reactions", "neighbours", "tests"}
    liquid = schema["$defs"]["LiquidElement"]["properties"]
    assert liquid["viscosity"]["maximum"] if "maximum" in liquid["viscosity"] else liquid["viscosity"]["exclusiveMaximum"] == 1
    assert "dispersion" in schema["$defs"]["LiquidElement"]["required"]
    (entry,) = schema["properties"]["elements"]["patternProperties"].values()  # an element, or a table checked when loaded
    assert entry["anyOf"][1]["not"] == {"required": ["archetype"]} and entry["anyOf"][0]["discriminator"]["propertyName"] == "archetype"
    world = json.loads(invoke("schema", "--world").stdout)
    assert "made_with" in world["$defs"]["WorldInfo"]["properties"]


BROKEN = {
    "a.toml": '[mod]\nname = "a"\n[elements.x]\narchetype = "static"\ncolor = "#12345"\n',
    "b.toml": '[mod]\nname = "b"\nrequires = ["a"]\n[elements.y]\narchetype = "static"\ncolor = "#123456"\n',
    "c.toml": '[mod]\nname = "c"\n[elements.z]\narchetype = "static"\ncolor = "#123456"\nlifetime = { frames = 3, becomes = "snad" }\n',
    "d.toml": (
        '[mod]\nname = "d"\n[elements.tic]\narchetype = "static"\ncolor = "#ff0000"\n'
        '[elements.tac]\narchetype = "static"\ncolor = "#00ff00"\n'
        '[elements.yin]\narchetype = "static"\ncolor = "#000000"\nheated = { above = 50, becomes = "yang" }\n'
        '[elements.yang]\narchetype = "static"\ncolor = "#ffffff"\ncooled = { below = 60, becomes = "yin" }\n'
        '[[reactions]]\na = "tic"\nb = "tac"\na_becomes = "tac"\nb_becomes = "tic"\nchance = 0.5\n'
    ),
}


def test_validate_reports_every_file_in_one_pass(tmp_path, monkeypatch):
    write_mods(tmp_path / "mods", BROKEN)
    monkeypatch.chdir(tmp_path)
    result = invoke("validate")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "mods/a.toml:5:1: elements.x.color: must be a colour like '#c2b280' (got '#12345')",
        "mods/b.toml:3:1: mod.requires.0: requires mod 'a', which has mistakes",
        "mods/c.toml:6:26: elements.z.lifetime.becomes: unknown element 'snad' (did you mean 'sand'?)",
        "mods/d.toml:17:1: reactions.0: these reactions never settle: tac + tic -> tic + tac; touching cells that cannot move would "
        "change forever (give one of them a temperature range, a lifetime to an element in it, or end the chain)",
        "mods/d.toml:12:12: elements.yin.heated.above: yin turns into yang above 50 degrees, but yang turns back below 60: "
        "between the two it would change every frame; make yang's cooled.below at most 50",
    ]


def test_requires_with_version_ranges(registry, tmp_path):
    def problems(requires: str) -> list[str]:
        mod = f'[mod]\nname = "m"\nrequires = [{requires}]\n'
        try:
            find_mods(registry, [write_mods(tmp_path / "mods", {"m.toml": mod})]).select(["m"])
        except ProblemsError as exc:
            return [str(p).split("/mods/", 1)[-1] for p in exc.problems]
        return []

    assert problems('"water>=2.0,<3", "sand >= 1.1"') == []
    assert problems('"water<2"') == ["m.toml:3:1: mod.requires.0: requires mod 'water<2', but mods/water.toml is version 2.2.0"]
    assert problems('"sand", "water==1.0"') == ["m.toml:3:1: mod.requires.1: requires mod 'water==1.0', but mods/water.toml is version 2.2.0"]
    with pytest.raises(ProblemsError) as caught:
        find_mods(registry, [write_mods(tmp_path / "bad", {"m.toml": '[mod]\nname = "m"\nrequires = ["water>>2"]\n'})])
    assert str(caught.value).endswith("mod.requires.0: '>>2' is not a version range like '>=2.0,<3', '~=2.1' or '==2.*'")


def test_requires_follows_the_version_standard():
    from packaging.specifiers import SpecifierSet

    from sandmod.formats.modspec import ModInfo, version_matches

    def meets(version: str, wanted: str) -> bool:
        return version_matches(version, SpecifierSet(wanted))

    assert not meets("2.0.0rc1", ">=2.0") and meets("2.0.0rc1", ">=2.0rc1")  # a pre-release only where one is named
    assert meets("2.1.5", "~=2.1") and not meets("3.0", "~=2.1")
    assert meets("2.7", "==2.*") and not meets("3.0", "==2.*")
    assert meets("1.2.0-beta", "==1.2.0b0") and ModInfo(name="m", version="2.0.0-rc1").version == "2.0.0-rc1"
    assert ModInfo(name="m", requires=[" water ~= 2.1 "]).requirements()[0][0] == "water"


def test_list_provenance_shows_overrides(tmp_path, monkeypatch):
    write_mods(tmp_path / "mods", {"red.toml": '[mod]\nname = "red"\nrequires = ["sand"]\n[elements."sand:sand"]\noverride = true\narchetype = "powder"\ncolor = "#cc3322"\ndensity = 1600\n'})
    monkeypatch.chdir(tmp_path)
    lines = invoke("list", "--provenance").stdout.splitlines()
    at = lines.index(next(line for line in lines if line.startswith("sand:sand: ")))
    assert lines[at].startswith("sand:sand: defined by sand (")
    assert lines[at + 1].startswith("  overridden by red (mods/red.toml:4): ")
    assert "color ['#dcc38a', '#d2b478', '#e4cf9c'] -> ['#cc3322']" in lines[at + 1]


def test_a_patch_changes_the_fields_it_names_and_keeps_the_rest(tmp_path, monkeypatch):
    from sandmod.world.loading import load_ruleset

    write_mods(tmp_path / "mods", {"heavy.toml": '[mod]\nname = "heavy"\nrequires = ["sand"]\n[elements."sand:sand"]\ndensity = 1800\n'})
    bundled = {e.id: e.spec for e in load_ruleset().elements}["sand:sand"]
    patched = {e.id: e for e in load_ruleset(mod_dirs=[tmp_path / "mods"]).elements}["sand:sand"]
    assert patched.spec.density == 1800 and bundled.density != 1800
    assert patched.spec.model_dump(exclude={"density"}) == bundled.model_dump(exclude={"density"})  # its melting point too
    assert patched.defined_by == "sand" and patched.history[0].describe().endswith(f"heavy.toml:4): density {bundled.density!r} -> 1800.0")
    monkeypatch.chdir(tmp_path)
    lines = invoke("list", "--provenance").stdout.splitlines()
    assert lines[lines.index(next(line for line in lines if line.startswith("sand:sand: "))) + 1].startswith("  patched by heavy (mods/heavy.toml:4): density")


def test_a_patch_files_an_element_in_another_menu_section_or_hides_it(tmp_path, monkeypatch):
    from sandmod.world.loading import load_ruleset

    menu = '[mod]\nname = "menu"\nrequires = ["sand", "explosives"]\n[elements."sand:sand"]\ncategory = "land"\n[elements."explosives:tnt"]\nhidden = true\n'
    write_mods(tmp_path / "mods", {"menu.toml": menu})
    bundled = {e.id: e.spec for e in load_ruleset().elements}
    patched = {e.id: e.spec for e in load_ruleset(mod_dirs=[tmp_path / "mods"]).elements}
    assert (bundled["sand:sand"].menu_category, bundled["explosives:tnt"].menu_category, bundled["explosives:tnt"].hidden) == ("powders", "explosives", False)
    assert (patched["sand:sand"].menu_category, patched["explosives:tnt"].hidden) == ("land", True)
    assert patched["sand:sand"].model_dump(exclude={"category"}) == bundled["sand:sand"].model_dump(exclude={"category"})
    write_mods(tmp_path / "mods", {"menu.toml": menu.replace('"land"', '"Land!"')})
    monkeypatch.chdir(tmp_path)
    result = invoke("validate", "mods")
    assert result.exit_code == 2 and result.stderr == "mods/menu.toml:5:1: elements.sand:sand.category: must be a lower-case name like 'acid_proof' (got 'Land!')\n"


def test_one_field_patched_by_two_mods_that_do_not_require_each_other_is_a_warning(tmp_path, monkeypatch):
    def patch(name: str, requires: str, density: int) -> str:
        return f'[mod]\nname = "{name}"\nrequires = [{requires}]\n[elements."sand:sand"]\ndensity = {density}\nfriction = 0.5\n'

    monkeypatch.chdir(tmp_path)
    write_mods(tmp_path / "mods", {"light.toml": patch("light", '"sand"', 900), "heavy.toml": patch("heavy", '"sand"', 1800)})
    result = invoke("validate", "mods")
    assert result.exit_code == 0
    warned = [line for line in result.stderr.splitlines() if line.startswith("warning: ")]
    assert len(warned) == 2 and all("also patched by heavy (" in line and "light does not require" in line for line in warned)
    assert warned[0].startswith("warning: mods/light.toml:5:1: elements.sand:sand.density: ")
    assert warned == [line for line in invoke("list").stderr.splitlines() if line.startswith("warning: ")]
    write_mods(tmp_path / "mods", {"light.toml": patch("light", '"sand", "heavy"', 900)})  # light builds on heavy: its value is meant
    assert "warning" not in invoke("validate", "mods").stderr


def test_an_element_like_another_takes_its_fields_and_replaces_those_it_gives(tmp_path, monkeypatch):
    from sandmod.world.loading import load_ruleset

    red = '[mod]\nname = "red"\nrequires = ["sand"]\n[elements.red_sand]\nlike = "sand"\ncolor = "#c04020"\n[elements.red_dust]\nlike = "red_sand"\ndensity = 900\n'
    write_mods(tmp_path / "mods", {"red.toml": red})
    specs = {e.id: e.spec for e in load_ruleset(mod_dirs=[tmp_path / "mods"]).elements}
    sand, red_sand, red_dust = specs["sand:sand"], specs["red:red_sand"], specs["red:red_dust"]
    assert red_sand.color == ["#c04020"] and red_sand.like == "sand:sand" and red_dust.like == "red:red_sand"
    assert red_sand.model_dump(exclude={"color", "like", "heated"}) == sand.model_dump(exclude={"color", "like", "heated"})
    assert red_dust.density == 900 and red_dust.color == ["#c04020"] and red_dust.heated.becomes == "glass:glass"  # sand's glass, named whole
    monkeypatch.chdir(tmp_path)
    assert "red:red_dust: defined by red (mods/red.toml, plugin user), like red:red_sand" in invoke("list", "--provenance").stdout
    write_mods(tmp_path / "mods", {"red.toml": red.replace('like = "red_sand"', 'like = "red_sandd"').replace("density = 900", "density = -1")})
    result = invoke("validate", "mods")
    assert result.exit_code == 2 and result.stderr.splitlines() == [
        "mods/red.toml:8:1: elements.red_dust.like: unknown element 'red_sandd' (did you mean 'red_sand'?) "
        "(an element defined before this one: in a mod it requires, or above it)"
    ]


METAL = """
[mod]
name = "metal"

[elements.iron]
archetype = "static"
color = "#8a8a8a"
melts = { above = 1538, viscosity = 0.3 }

[elements.brine]
archetype = "liquid"
color = "#3060c0"
density = 1100
dispersion = 3
freezes = { below = -10 }

[[tests]]
name = "hot_iron_melts_flows_and_sets_on_cold_stone"
frames = 40
legend = { I = { element = "iron", temperature = 1800 }, "#" = "stone" }
scene = \"\"\"
#.....#
#.III.#
#.....#
#.....#
#######
\"\"\"
count = { iron = 3 }
expect = \"\"\"
#.....#
#.....#
#.....#
#?????#
#######
\"\"\"

[[tests]]
name = "cold_brine_freezes"
frames = 5
legend = { C = { element = "brine", temperature = -40 }, "#" = "stone" }
scene = \"\"\"
#CC#
####
\"\"\"
absent = ["brine"]
present = ["frozen_brine"]
"""


def test_an_element_that_melts_or_freezes_makes_its_form_and_the_changes_between(tmp_path, monkeypatch):
    from sandmod.world.loading import load_ruleset

    write_mods(tmp_path / "mods", {"metal.toml": METAL})
    specs = {e.id: e.spec for e in load_ruleset(mod_dirs=[tmp_path / "mods"]).elements}
    iron, molten = specs["metal:iron"], specs["metal:molten_iron"]
    assert (iron.heated.above, iron.heated.becomes) == (1538, "metal:molten_iron")
    assert molten.archetype == "liquid" and (molten.cooled.below, molten.cooled.becomes) == (1538, "metal:iron")
    assert molten.viscosity == 0.3 and molten.temperature == 1638 and molten.color != iron.color  # given, placed hot, glowing
    brine, frozen = specs["metal:brine"], specs["metal:frozen_brine"]
    assert (brine.cooled.becomes, frozen.archetype, frozen.heated.above, frozen.heated.becomes) == ("metal:frozen_brine", "static", -10, "metal:brine")
    monkeypatch.chdir(tmp_path)
    result = invoke("test", "metal")
    assert result.exit_code == 0, result.output
    assert "metal:molten_iron" in invoke("list").stdout
    write_mods(tmp_path / "mods", {"metal.toml": METAL.replace("viscosity = 0.3", "viscosity = 3")})  # checked as the form's own
    bad = invoke("validate", "mods")
    assert bad.exit_code == 2 and bad.stderr == "mods/metal.toml:7:25: elements.iron.melts.viscosity: must be < 1 (got 3)\n"
    write_mods(tmp_path / "mods", {"metal.toml": METAL, "hot.toml": '[mod]\nname = "hot"\nrequires = ["metal"]\n[elements."metal:brine"]\nmelts = { above = 90 }\n'})
    assert invoke("validate", "mods").stderr.startswith("mods/hot.toml:5:1: elements.metal:brine.melts: a patch cannot make forms ('melts')")


def test_a_patch_is_checked_as_the_element_it_makes(tmp_path, monkeypatch):
    patch = '[mod]\nname = "heavy"\nrequires = REQUIRES\n[elements."sand:sand"]\ndensity = -5\ndensty = 3\n[elements."water:waterr"]\ndensity = 900\n[elements."water:water"]\nheated = { above = 90 }\n'
    write_mods(tmp_path / "mods", {"heavy.toml": patch.replace("REQUIRES", '["sand", "water"]')})
    monkeypatch.chdir(tmp_path)
    result = invoke("validate", "mods")
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [
        "mods/heavy.toml:5:1: elements.sand:sand.density: must be > 0 (got -5)",
        "mods/heavy.toml:6:1: elements.sand:sand.densty: unknown field; allowed here: " + result.stderr.split("allowed here: ")[1].splitlines()[0],
        "mods/heavy.toml:7:1: elements.water:waterr: 'water:waterr' is not defined by any loaded mod (nothing to change: a mod that "
        "changes another's element names it in requires, to load after it)",
        "mods/heavy.toml:10:1: elements.water:water.heated.becomes: required field is missing",  # a table is replaced whole
    ]
    assert "density" in result.stderr.split("allowed here: ")[1]
    write_mods(tmp_path / "mods", {"heavy.toml": patch.replace("REQUIRES", "[]")})  # loaded before sand: nothing to patch yet
    assert "'sand:sand' is not defined by any loaded mod" in invoke("validate", "mods").stderr


def test_a_new_world_pours_the_users_own_element_else_sand(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    poured = lambda: tomllib.loads((tmp_path / "w.toml").read_text())["emitters"][0]["element"]
    assert invoke("new", "world", "w").exit_code == 0
    assert poured() == "sand:sand"  # of all the bundled mods, not the first one loaded
    assert invoke("new", "mod", "mud").exit_code == 0
    (tmp_path / "w.toml").unlink()
    assert invoke("new", "world", "w").exit_code == 0
    assert poured() == "mud:mud"
    (tmp_path / "w.toml").unlink()
    assert invoke("new", "world", "w", "--mod", "water").exit_code == 0
    assert poured() == "water:water"


def test_worlds_record_their_mods_and_warn_when_they_differ(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert invoke("new", "world", "w", "--mod", "sand", "--size", "32", "32").exit_code == 0
    data = tomllib.loads((tmp_path / "w.toml").read_text())
    assert data["world"]["made_with"] == {"base": "1.2.0", "glass": "1.2.0", "sand": "1.1.0"}
    assert data["emitters"][0]["element"] == "sand:sand"
    clean = invoke("validate", "w.toml")
    assert clean.exit_code == 0 and clean.stderr == ""
    text = (tmp_path / "w.toml").read_text().replace('sand = "1.1.0"', 'sand = "1.0.0"').replace('glass = "1.2.0"\n', "")
    (tmp_path / "w.toml").write_text(text)
    result = invoke("validate", "w.toml")
    assert result.exit_code == 0
    assert result.stderr.splitlines() == [
        "warning: w.toml:11:1: world.made_with.sand: made with mod sand 1.0.0; loading sand 1.1.0",
        "warning: w.toml:9:1: world.made_with: mod glass 1.2.0 is loaded but the world was not made with it",
    ]


GOO = """[mod]
name = "goo"
version = "1.0.0"

[elements.goo]
archetype = "liquid"
density = -1
dispersion = 99
color = "red"

[[reactions]]
a = "goo"
b = "goo"
a_becomes = "empty"
chance = 5

[[reactions]]
a = "goo"
b = "water"
a_becomes = "goo"
chance = 0.5
"""


def test_validate_reports_what_field_mistakes_would_hide_in_the_same_pass(tmp_path, monkeypatch):
    write_mods(tmp_path / "mods", {"goo.toml": GOO})
    monkeypatch.chdir(tmp_path)
    first = invoke("validate").stderr.splitlines()
    assert first == [
        "mods/goo.toml:7:1: elements.goo.density: must be > 0 (got -1)",
        "mods/goo.toml:8:1: elements.goo.dispersion: must be <= 16 (got 99)",
        "mods/goo.toml:9:1: elements.goo.color: must be a colour like '#c2b280' (got 'red')",
        "mods/goo.toml:15:1: reactions.0.chance: must be <= 1 (got 5)",
        "mods/goo.toml:19:1: reactions.1.b: 'water:water' is from mod 'water'; add 'water' to mod.requires",
    ]
    fixed = GOO.replace("-1", "900").replace("99", "3").replace('"red"', '"#44aa33"').replace("chance = 5", "chance = 0.5")
    write_mods(tmp_path / "mods", {"goo.toml": fixed})
    assert invoke("validate").stderr.splitlines() == first[-1:]  # nothing new once the fields are right


def test_validate_reports_a_tables_own_checks_beside_its_field_mistakes(tmp_path, monkeypatch):
    """A check across a table's fields (burn_temperature against ignites_at) is made in the same pass
    as the table's field mistakes, unless it names a field that is wrong (it would see its default)."""
    log = """
        [mod]
        name = "logs"

        [elements.log]
        archetype = "static"
        color = "#884400"
        flammable = { ignites_at = 500, burn_temperature = 300, flame_chance = 2 }

        [elements.twig]
        archetype = "static"
        color = "#884400"
        flammable = { ignites_at = 900, burn_temperature = -900 }  # left out, it would be 700: below 900
    """
    write_mods(tmp_path / "mods", {"logs.toml": log})
    monkeypatch.chdir(tmp_path)
    assert invoke("validate").stderr.splitlines() == [
        "mods/logs.toml:7:1: elements.log.flammable: burn_temperature must be at least ignites_at, or the fire would go out at once",
        "mods/logs.toml:7:57: elements.log.flammable.flame_chance: must be <= 1 (got 2)",
        "mods/logs.toml:12:33: elements.twig.flammable.burn_temperature: must be >= -273 (got -900)",
    ]
