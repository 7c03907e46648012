"""Mods to tables: ids, displacement, reactions, names, overrides, dependencies."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import SEED_ROOTS, write_mods
from sandmod.rules.compiler import (
    ARCHETYPE_CODES,
    BLAST_RADIUS,
    CAP_ONE,
    COOLED,
    EXPLOSIVE,
    FLAMMABLE,
    HEATED,
    IGNITES,
    SUBCELL,
    TEMP_ONE,
    pair_reaction,
)
from sandmod.engine.layout import SIDES, UNIQUE_BITS, mask_bit
from sandmod.errors import ProblemsError
from sandmod.engine.hashing import ROLL_ONE
from sandmod.world.loading import load_ruleset


@pytest.fixture(autouse=True)
def _relative_paths(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # problems name files relative to the working directory


def problems_of(registry, tmp_path, files: dict[str, str], mods=None) -> list[str]:
    with pytest.raises(ProblemsError) as caught:
        load_ruleset(mods, [write_mods(tmp_path / "mods", files)], registry)
    return [str(p) for p in caught.value.problems]




def test_tables_hold_each_elements_parameters(ruleset):
    t, i = ruleset.tables, ruleset.index
    assert t.archetype[i("sand")] == ARCHETYPE_CODES["powder"]
    assert t.archetype[i("stone")] == ARCHETYPE_CODES["static"]
    assert (t.fall_dir[i("sand")], t.fall_dir[i("water")], t.fall_dir[i("steam")], t.fall_dir[i("stone")]) == (1, 1, -1, 0)
    assert t.accel[i("sand")] == round(0.2 * SUBCELL) and t.max_speed[i("sand")] == 8 * SUBCELL
    assert t.friction[i("coal")] == round(1.6 * 256) and t.knock_chance[i("coal")] == round((1 - 0.9) * ROLL_ONE)
    assert t.archetype[i("particle")] == ARCHETYPE_CODES["particle"] and t.carries[i("particle")] == 0
    assert ruleset.particle == i("base:particle")
    assert t.dispersion[i("water")] == 4 and t.dispersion[i("lava")] == 2
    assert t.rest_chance[i("lava")] == round(0.6 * ROLL_ONE)
    assert t.life_frames[i("fire")] == 18 and t.life_into[i("fire")] == i("smoke")


def test_heat_tables_are_fixed_point_and_precomputed(ruleset):
    t, i = ruleset.tables, ruleset.index
    water = i("water")
    assert t.heat_cap[water] == 4 * CAP_ONE and t.temp_start[water] == 20 * TEMP_ONE
    assert (t.heat_recip[water] * t.heat_cap[water]) >> 32 == 1  # temperature = (energy * recip) >> 32
    assert t.hot_limit[water] == t.heat_cap[water] * 100 * TEMP_ONE and t.heated_into[water] == i("steam")
    assert t.cold_limit[water] == 0 and t.cooled_into[water] == i("ice")
    assert t.thermal[water] == HEATED | COOLED and t.extinguishes[water] == 1
    assert t.thermal[i("lava")] == COOLED | IGNITES
    assert t.thermal[i("wood")] == FLAMMABLE and t.ash[i("wood")] == i("ash") and t.flame[i("wood")] == i("fire")
    assert t.thermal[i("gunpowder")] == FLAMMABLE | EXPLOSIVE and t.blast[i("gunpowder"), BLAST_RADIUS] == 5
    assert t.blast[i("wood"), BLAST_RADIUS] == 0
    # Conductance is conductivity x capacity / 4, in 1/256ths: each side moves at most 1/4 of a gap.
    assert t.conductance[water] == round(0.1 * 4 * CAP_ONE * 64)
    assert t.resistance[i("titanium")] == 1_000_000 * 256 and t.resistance[i("stone")] == 2 * 256
    assert t.resistance[i("sand")] == 128 and t.resistance[i("empty")] == 0


def test_density_decides_who_displaces_whom(ruleset):
    d, i = ruleset.tables.displace, ruleset.index
    assert d[i("sand"), i("water")] and not d[i("water"), i("sand")]
    assert d[i("lava"), i("water")] and d[i("water"), i("empty")]
    assert d[i("steam"), i("water")] and d[i("steam"), i("empty")] and not d[i("water"), i("water")]
    assert not d[i("sand"), i("stone")] and not d[i("sand"), i("sand")]
    assert not d[i("stone")].any()


@pytest.mark.parametrize("matrix, masks", [("displace", "displaces"), ("react_pair", "reactive")])
def test_neighbour_masks_never_miss_a_partner(ruleset, matrix, masks):
    pairs, bits = getattr(ruleset.tables, matrix), getattr(ruleset.tables, masks).view(np.uint64)
    assert pairs.any()
    for a, b in zip(*np.nonzero(pairs)):
        assert bits[a] >> np.uint64(mask_bit(int(b))) & np.uint64(1), (ruleset.elements[a].id, ruleset.elements[b].id)
    partnerless = ~(pairs > 0).any(axis=1)
    assert (bits[partnerless] == 0).all()  # no partners: the kernel's first test ends it at once


def test_the_kernel_and_the_compiler_give_an_element_the_same_mask_bit():
    from sandmod.engine.cells import _bit

    for e in (0, 1, UNIQUE_BITS - 1, UNIQUE_BITS, UNIQUE_BITS + 5, 3 * UNIQUE_BITS + 7, 4095):
        assert np.uint64(_bit.py_func(np.uint16(e)).view(np.uint64)) == 1 << mask_bit(e)
    assert {mask_bit(e) for e in range(UNIQUE_BITS)} == set(range(UNIQUE_BITS))  # the first ones, a bit each
    assert {mask_bit(e) for e in range(UNIQUE_BITS, 4096)} == set(range(UNIQUE_BITS, 64))  # the others share the rest


def test_the_elements_most_react_with_are_numbered_first_and_listed_by_id(ruleset):
    """Acid eats nearly everything and a fan blows everything, so they are partners of the most elements:
    they get mask bits of their own."""
    assert ruleset.elements[0].id == "base:empty"
    assert [e.index for e in ruleset.elements] == list(range(len(ruleset.elements)))
    partners = (ruleset.tables.react_pair > 0).sum(axis=0)
    assert list(partners[1:]) == sorted(partners[1:], reverse=True)
    assert {e.id for e in ruleset.elements[1:3]} == {"acid:acid", "machines:fan"}
    assert [e.id for e in ruleset.by_id[1:]] == sorted(e.id for e in ruleset.elements[1:])


def test_reactions_fill_the_matrix_both_ways(ruleset):
    t, i = ruleset.tables, ruleset.index
    fire, water = i("fire"), i("water")
    forward, backward = pair_reaction(t, fire, water), pair_reaction(t, water, fire)
    assert forward.chance == backward.chance == round(0.8 * ROLL_ONE)
    assert (forward.into_a, forward.into_b) == (i("steam"), water)
    assert (backward.into_a, backward.into_b) == (water, i("steam"))
    assert t.react_pair[fire, water] != t.react_pair[water, fire]  # a row for each side: it reads a then b


def test_where_limits_a_reaction_to_sides_seen_from_each_cell(ruleset):
    """The tap pours only below itself: seen from the empty cell, the tap is above it."""
    t, i = ruleset.tables, ruleset.index
    tap = i("tap")
    assert pair_reaction(t, tap, 0, "below").into_b == i("water")
    assert [pair_reaction(t, tap, 0, side) for side in ("right", "left", "above")] == [None] * 3
    assert pair_reaction(t, 0, tap, "above").into_a == i("water")
    assert [pair_reaction(t, 0, tap, side) for side in ("right", "left", "below")] == [None] * 3
    assert [pair_reaction(t, i("fire"), i("water"), side) for side in SIDES] == [pair_reaction(t, i("fire"), i("water"))] * 4


def test_two_reactions_of_one_pair_on_different_sides_both_apply(registry, tmp_path):
    mods = write_mods(tmp_path / "mods", {"g.toml": SEED_ROOTS})
    rs = load_ruleset(["g"], [mods], registry=registry)
    seed = rs.index("seed")
    assert pair_reaction(rs.tables, seed, 0, "above").into_b == seed
    assert {pair_reaction(rs.tables, seed, 0, side).into_b for side in ("below", "left", "right")} == {rs.index("root")}


def test_a_push_flies_the_cell_pushed_whichever_cell_looks(ruleset):
    """Seen from the fan, the sand above it flies (push_b); seen from the sand, the sand itself (push_a)."""
    t, i = ruleset.tables, ruleset.index
    fan, sand = i("fan"), i("sand")
    assert pair_reaction(t, fan, sand, "above")[6:8] == (0, round(2.5 * SUBCELL))
    assert pair_reaction(t, sand, fan, "below")[6:8] == (round(2.5 * SUBCELL), 0)
    assert pair_reaction(t, fan, sand, "below") is None and t.particle[0] == ruleset.particle


def test_a_reaction_is_one_row_whatever_its_selectors_match(ruleset):
    """A broad selector makes one row a side (products that stay are STAYS), not a row a pair: the
    row tables are sized by the reactions, the pair table by the elements."""
    t, i = ruleset.tables, ruleset.index
    acid = i("acid")
    victims = [b for b in range(len(ruleset.elements)) if pair_reaction(t, acid, b) and pair_reaction(t, acid, b).into_a == 0]
    assert len(victims) > 5 and len({int(t.react_pair[acid, b]) for b in victims}) == 1
    assert len(t.react_chance) <= 1 + 2 * sum(len(m.spec.reactions) for m in ruleset.mods)
    assert t.react_chance[0] == 0 and t.react_pair.dtype == np.uint16


def test_reaction_temperatures_and_heat_fill_the_matrix(registry, tmp_path):
    mods = write_mods(
        tmp_path / "mods",
        {
            "r.toml": """
            [mod]
            name = "r"
            [elements.a]
            archetype = "static"
            color = "#ffffff"
            [[reactions]]
            a = "a"
            b = "stone"
            a_becomes = "empty"
            chance = 1
            min_temperature = 100
            max_temperature = 200.5
            heat = -30
            """
        },
    )
    rs = load_ruleset(["r"], [mods], registry=registry)
    t, a, stone = rs.tables, rs.index("a"), rs.index("stone")
    for pair in ((a, stone), (stone, a)):
        reaction = pair_reaction(t, *pair)
        assert (reaction.tsum_min, reaction.tsum_max) == (200 * TEMP_ONE, 401 * TEMP_ONE)  # of T_a + T_b
        assert reaction.heat == -30 * TEMP_ONE


def test_tag_selectors_spare_acid_proof_elements(ruleset):
    t, i = ruleset.tables, ruleset.index
    acid = i("acid")
    assert pair_reaction(t, acid, i("titanium")) is pair_reaction(t, acid, acid) is pair_reaction(t, acid, 0) is None
    for victim in ("stone", "sand", "lava", "steam"):
        assert pair_reaction(t, acid, i(victim))[:3] == (round(0.2 * ROLL_ONE), 0, 0)


def test_a_more_specific_reaction_wins(ruleset):
    t, i = ruleset.tables, ruleset.index
    assert pair_reaction(t, i("acid"), i("water"))[:3] == (round(0.003 * ROLL_ONE), i("water"), i("water"))


def test_reactions_of_equal_rank_that_disagree_are_an_error(registry, tmp_path):
    problems = problems_of(
        registry,
        tmp_path,
        {
            "fizz.toml": """
                [mod]
                name = "fizz"
                requires = ["sand"]

                [[reactions]]
                a = "#x"
                b = "sand"
                a_becomes = "empty"
                chance = 0.5

                [[reactions]]
                a = "#x"
                b = "sand"
                b_becomes = "empty"
                chance = 0.5

                [elements.foam]
                archetype = "static"
                color = "#ffffff"
                tags = ["x"]
            """
        },
    )
    assert problems == [
        "mods/fizz.toml:11:1: reactions.1: fizz:foam + sand:sand also reacts differently at mods/fizz.toml:5 "
        "(reactions.0); make one selector more specific, or give one a higher priority",
    ]


VOIDS = """
[mod]
name = "voids"
requires = [REQUIRES]

[elements.void]
archetype = "static"
color = "#101010"
tags = ["device"]

[[reactions]]
a = "void"
b = "!#device"
b_becomes = "empty"
chance = 0.5
PRIORITY
"""

VIRUSES = """
[mod]
name = "viruses"

[elements.virus]
archetype = "powder"
color = "#80ff40"
density = 1000
tags = ["immune"]

[[reactions]]
a = "virus"
b = "!#immune"
b_becomes = "virus"
chance = 0.2
"""


def _void_and_virus(registry, tmp_path, requires="", priority=""):
    """The ruleset of the voids and viruses mods (two folders: their authors never met), and what void + virus does."""
    voids = write_mods(tmp_path / "voids", {"voids.toml": VOIDS.replace("REQUIRES", requires).replace("PRIORITY", priority)})
    viruses = write_mods(tmp_path / "viruses", {"viruses.toml": VIRUSES})
    ruleset = load_ruleset(None, [voids, viruses], registry)
    void, virus = ruleset.index("voids:void"), ruleset.index("viruses:virus")
    reaction = pair_reaction(ruleset.tables, void, virus)
    outcome = (ruleset.elements[reaction.into_a].id, ruleset.elements[reaction.into_b].id)
    return ruleset, outcome


def test_two_mods_whose_reactions_tie_load_together_the_later_applies_with_a_warning(registry, tmp_path):
    ruleset, outcome = _void_and_virus(registry, tmp_path)
    assert [m.name for m in ruleset.mods].index("voids") > [m.name for m in ruleset.mods].index("viruses")
    assert outcome == ("voids:void", "base:empty")  # the void, loaded later, eats the virus
    tie = [str(w) for w in ruleset.warnings if "voids:void + viruses:virus" in str(w)]
    assert tie == [
        "voids/voids.toml:10:1: reactions.0: voids:void + viruses:virus also reacts differently at "
        "viruses/viruses.toml:10 (reactions.0), as specific and of the same priority: this one applies, "
        "voids being loaded after viruses (a higher priority on one would say which)"
    ]


def test_a_higher_priority_or_a_requirement_decides_a_tie_without_a_warning(registry, tmp_path):
    ruleset, outcome = _void_and_virus(registry, tmp_path, priority="priority = -1")
    assert outcome == ("viruses:virus", "viruses:virus")  # the virus infects the void
    assert not [w for w in ruleset.warnings if "voids:void + viruses:virus" in str(w)]
    ruleset, outcome = _void_and_virus(registry, tmp_path, requires='"viruses"')  # voids builds on viruses: its rule is meant
    assert outcome == ("voids:void", "base:empty")
    assert not [w for w in ruleset.warnings if "voids:void + viruses:virus" in str(w)]


SWAPS = """
[mod]
name = "swaps"
requires = ["water"]

[elements.tic]
archetype = "static"
color = "#ff0000"
TIC

[elements.tac]
archetype = "static"
color = "#00ff00"

[elements.sponge]
archetype = "static"
color = "#e0d060"

[elements.wet_sponge]
archetype = "static"
color = "#a09040"

[[reactions]]
a = "tic"
b = "tac"
a_becomes = "tac"
b_becomes = "tic"
chance = 0.5
RANGE

[[reactions]]
a = "sponge"
b = "water"
a_becomes = "wet_sponge"
b_becomes = "empty"
chance = 0.5

[[reactions]]
a = "wet_sponge"
b = "empty"
a_becomes = "sponge"
b_becomes = "water"
chance = 0.1
"""


@pytest.mark.parametrize(
    "tic, range_, settles",
    [
        ("", "", False),  # two static cells swapping forever
        ("", "min_temperature = -273", False),  # a range that holds every temperature is none
        ("", "min_temperature = 50", True),  # a real range: it ends below 50 degrees
        ('lifetime = { frames = 30, becomes = "tac" }', "", True),  # tic changes by itself
    ],
)
def test_only_chains_of_cells_that_can_never_part_are_endless(registry, tmp_path, tic, range_, settles):
    """The sponge's wet/dry chain passes in every case: water moves away."""
    files = {"swaps.toml": SWAPS.replace("TIC", tic).replace("RANGE", range_)}
    if settles:
        load_ruleset(None, [write_mods(tmp_path / "mods", files)], registry)
    else:
        assert [p.split(": ", 2)[2][:40] for p in problems_of(registry, tmp_path, files)] == ["these reactions never settle: tac + tic "]


def test_unknown_element_suggests_a_name(registry, tmp_path):
    problems = problems_of(
        registry,
        tmp_path,
        {
            "mud.toml": """
                [mod]
                name = "mud"
                requires = ["sand"]

                [elements.mud]
                archetype = "powder"
                color = "#553311"
                density = 1800
                lifetime = { frames = 10, becomes = "snad" }
            """
        },
    )
    assert problems == ["mods/mud.toml:9:27: elements.mud.lifetime.becomes: unknown element 'snad' (did you mean 'sand'?)"]


def test_naming_another_mods_element_needs_requires(registry, tmp_path):
    problems = problems_of(
        registry,
        tmp_path,
        {
            "wet.toml": """
                [mod]
                name = "wet"

                [[reactions]]
                a = "sand"
                b = "water"
                a_becomes = "stone"
                chance = 0.1
            """
        },
    )
    assert problems == [
        "mods/wet.toml:5:1: reactions.0.a: 'sand:sand' is from mod 'sand'; add 'sand' to mod.requires",
        "mods/wet.toml:6:1: reactions.0.b: 'water:water' is from mod 'water'; add 'water' to mod.requires",
    ]


def test_ambiguous_bare_names_are_errors(registry, tmp_path):
    problems = problems_of(
        registry,
        tmp_path,
        {
            "beach.toml": """
                [mod]
                name = "beach"

                [elements.sand]
                archetype = "powder"
                color = "#ffffff"
                density = 1500
            """,
            "user.toml": """
                [mod]
                name = "user"
                requires = ["beach", "sand"]

                [elements.glass]
                archetype = "static"
                color = "#aaddff"
                lifetime = { frames = 5, becomes = "sand" }
            """,
        },
    )
    assert problems == [
        "mods/user.toml:8:26: elements.glass.lifetime.becomes: 'sand' is ambiguous; write one of: beach:sand, sand:sand"
    ]


def test_redefining_an_element_needs_override(registry, tmp_path):
    files = {
        "redsand.toml": """
            [mod]
            name = "redsand"
            requires = ["sand"]

            [elements."sand:sand"]
            archetype = "powder"
            color = "#cc3322"
            density = 1600
        """
    }
    problems = problems_of(registry, tmp_path, files)
    assert problems == [
        f"mods/redsand.toml:5:1: elements.sand:sand: 'sand:sand' is already defined by "
        f"{_bundled('sand.toml')}; set override = true to replace it"
    ]
    files["redsand.toml"] = files["redsand.toml"].replace("density = 1600", "density = 1600\n            override = true")
    ruleset = load_ruleset(None, [write_mods(tmp_path / "ok", files)], registry)
    sand = ruleset.elements[ruleset.index("sand:sand")]
    assert sand.spec.color == ["#cc3322"] and sand.defined_by == "redsand" and sand.overrides == ("sand",)


def _bundled(name: str) -> str:
    from sandmod.errors import display_path
    from sandmod.plugins.toml_mods import bundled_mods_dir

    return display_path(bundled_mods_dir() / name)


def test_override_of_nothing_is_an_error(registry, tmp_path):
    problems = problems_of(
        registry,
        tmp_path,
        {
            "ghost.toml": """
                [mod]
                name = "ghost"

                [elements.wisp]
                archetype = "static"
                color = "#ffffff"
                override = true
            """
        },
    )
    assert problems == ["mods/ghost.toml:4:1: elements.wisp: 'ghost:wisp' is not defined by any loaded mod (nothing to override)"]


def test_missing_required_mod_cycles_and_duplicate_names(registry, tmp_path):
    assert problems_of(registry, tmp_path / "a", {"x.toml": '[mod]\nname = "x"\nrequires = ["nope"]\n'}) == [
        "a/mods/x.toml:3:1: mod.requires.0: requires mod 'nope', which was not found"
    ]
    cycle = {"p.toml": '[mod]\nname = "p"\nrequires = ["q"]\n', "q.toml": '[mod]\nname = "q"\nrequires = ["p"]\n'}
    assert problems_of(registry, tmp_path / "b", cycle) == ["b/mods/p.toml:3:1: mod.requires: dependency cycle: p -> q -> p"]
    twins = {"one.toml": '[mod]\nname = "twin"\n', "two.toml": '[mod]\nname = "twin"\n'}
    assert problems_of(registry, tmp_path / "c", twins) == [
        "c/mods/two.toml:2:1: mod.name: mod 'twin' is also defined by c/mods/one.toml"
    ]


def test_a_byte_for_byte_copy_of_a_mod_is_the_same_mod(registry, tmp_path):
    # As in a checkout whose mods/ are also installed (not editable) as the bundled ones.
    from sandmod.plugins.toml_mods import bundled_mods_dir

    text = (bundled_mods_dir() / "water.toml").read_text()
    ruleset = load_ruleset(None, [write_mods(tmp_path / "mods", {"water.toml": text})], registry)
    water = [m for m in ruleset.mods if m.name == "water"]
    assert len(water) == 1 and water[0].source.name == _bundled("water.toml")
    assert problems_of(registry, tmp_path / "edited", {"water.toml": text + "\n# edited\n"}) == [
        "edited/mods/water.toml:5:1: mod.name: mod 'water' is also defined by " + _bundled("water.toml")
    ]


def test_load_order_puts_dependencies_first(registry):
    ruleset = load_ruleset(["lava"], registry=registry)
    names = [m.name for m in ruleset.mods]
    assert names == ["base", "lava"]
    names = [m.name for m in load_ruleset(["wood"], registry=registry).mods]
    assert names == ["base", "water", "fire", "wood"]


def test_bare_names_prefer_the_mods_a_mod_requires(registry, tmp_path):
    # The user's own 'glass' does not make the sand mod's 'glass' ambiguous: sand requires the glass mod.
    mods = write_mods(tmp_path / "mods", {"mine.toml": '[mod]\nname = "mine"\n[elements.glass]\narchetype = "static"\ncolor = "#000000"\n'})
    rs = load_ruleset(["sand", "mine"], [mods], registry=registry)
    assert rs.tables.heated_into[rs.index("sand")] == rs.index("glass:glass")


def test_each_element_gets_its_shades_scorched_shades_and_glow_colours(ruleset):
    from sandmod.rules.compiler import GLOW_COLOURS, SCORCHED_SHADES, SHADES

    looks, n = ruleset.looks, len(ruleset.elements)
    assert (looks.normal.shape, looks.scorched.shape, looks.glow.shape) == ((n, SHADES), (n, SCORCHED_SHADES), (n, len(GLOW_COLOURS)))
    assert ruleset.shades == SHADES == 8 and looks.normal.dtype == np.uint16
    used = np.concatenate([looks.normal.ravel(), looks.scorched[1:].ravel(), looks.glow[1:].ravel()])
    assert sorted(used.tolist()) == list(range(len(ruleset.colours)))  # every one its own colour, none unused
    assert ruleset.colours.dtype == np.uint8 and ruleset.colours.shape == (8 + (n - 1) * 15, 3)  # the air only shades
    stone = ruleset.index("stone")
    rgb = ruleset.colours.astype(int)
    assert all(abs(rgb[k, 0] - 0x6B) < 40 for k in looks.normal[stone])
    assert rgb[looks.scorched[stone]].sum(axis=1).max() < rgb[looks.normal[stone]].sum(axis=1).min()  # darker
    assert all(r > g > b for r, g, b in rgb[looks.glow[stone]])  # glowing: red over green over blue


def test_empty_must_stay_empty(registry, tmp_path):
    problems = problems_of(
        registry,
        tmp_path,
        {
            "void.toml": """
                [mod]
                name = "void"

                [elements."base:empty"]
                archetype = "static"
                color = "#000000"
                override = true
            """
        },
    )
    assert problems == ["mods/void.toml:5:1: elements.base:empty.archetype: 'base:empty' must be 'empty'"]


def test_a_particle_cannot_carry_a_particle(registry, tmp_path):
    problems = problems_of(
        registry,
        tmp_path,
        {
            "sparks.toml": """
                [mod]
                name = "sparks"
                [elements.spark]
                archetype = "particle"
                color = "#ffdd00"
                carries = "base:particle"
            """
        },
        ["sparks"],
    )
    assert [p.split("/")[-1] for p in problems] == ["sparks.toml:6:1: elements.spark.carries: a particle cannot carry a particle ('base:particle')"]
