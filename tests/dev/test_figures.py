"""The figures in the docs' prose (``tools/dev/figures.py``): each entry's text is on its page, the cheap
ones are what the code gives now, and the tool reads a command's output as it should."""

from __future__ import annotations

import json

import pytest

from figures import FIGURES, ROOT, SLOW, Figure, _json, _settled, differences, missing, rewritten

CHEAP = [figure for figure in FIGURES if not figure.measured]


def test_every_figures_text_is_on_its_page_once_and_holds_the_figure():
    """A page reworded, or a figure changed by hand, must change its entry too: none is left behind."""
    lost = missing(FIGURES)
    assert lost == [], [f"{f.page}: {f.text!r}" for f in lost]
    for figure in FIGURES:
        assert figure.figure in figure.text, figure
        assert "changelog" not in figure.page.lower(), figure  # history, not figures of the code
    assert sum(figure.measured for figure in FIGURES) >= 20 and sum(not figure.measured for figure in FIGURES) >= 60


def _agree(figures: list[Figure]) -> None:
    wrong = differences(figures)
    assert wrong == [], "\n".join(f"{f.page}: {f.text!r} says {f.figure}, the code gives {now}" for f, now in wrong)


def test_a_measured_figures_text_shares_no_character_with_another_entrys():
    """So that ``--write``, changing one, leaves the others' texts as they are."""
    spans = {figure: ((start := (ROOT / figure.page).read_text(encoding="utf-8").find(figure.text)), start + len(figure.text)) for figure in FIGURES}
    for figure in (f for f in FIGURES if f.measured):
        (start, end) = spans[figure]
        overlapping = [other for other in FIGURES if other.page == figure.page and other != figure and spans[other][0] < end and start < spans[other][1]]
        assert overlapping == [], (figure, overlapping)


def test_the_cheap_figures_are_what_the_code_gives_now():
    """What ``python tools/dev/figures.py --check`` checks: counts, limits, the bundled mods' figures (seconds)."""
    _agree([figure for figure in CHEAP if figure.command not in SLOW])


@pytest.mark.slow  # runs the engine for seconds: fluids.py's scenes, the halves scene
def test_the_cheap_figures_that_run_the_engine_are_what_it_gives_now():
    _agree([figure for figure in CHEAP if figure.command in SLOW])


def test_a_figure_that_differs_is_found():
    said, outdated = (Figure("README.md", "the 7 tests", "7", f"echo 'tests: {n}'", r"^tests: (\d+)$") for n in (7, 8))
    assert differences([said]) == []
    assert differences([outdated]) == [(outdated, "8")]


def test_a_figure_is_read_from_what_its_command_prints():
    line = {"scene": "mix", "width": 512, "height": 512, "steps": 1000, "threads": 2, "mcell_updates_per_second": 359.64, "speedup": 1.497}
    printed = "compiling...\n" + json.dumps({**line, "threads": 1, "mcell_updates_per_second": 240.6}) + "\n" + json.dumps(line) + "\n"
    two = Figure("p.md", "| 360 |", "360", "x", _json("mcell_updates_per_second", scene="mix", threads=2), measured=True, digits=0)
    ratio = Figure("p.md", "| 1.50x |", "1.50", "x", _json("speedup", scene="mix", threads=2), measured=True, digits=2)
    assert (two.now(printed), ratio.now(printed)) == ("360", "1.50")
    assert Figure("p.md", "twelve elements", "twelve", "x", r"^n: (\d+)$").agrees("12")
    runs = "\n".join(json.dumps({"steps": 200, "seconds": s}) for s in (0.0064, 1.5))
    assert [_settled(runs, what) for what in ("asleep", "awake", "ratio")] == ["0.032", "7.5", "234"]


def test_a_new_figure_is_written_where_the_old_one_was():
    page = "It leaves out\nthe 25 tests marked slow, which take 25 s.\n"
    figure = Figure("README.md", "the 25 tests marked slow", "25", "x", r"(\d+)")
    assert rewritten(page, figure, "27") == page.replace("the 25 tests", "the 27 tests")
