"""The figures a docs page shows a command printing, made again: each page is followed as a
reader would (its files written, its commands run in a new folder, with this checkout's
sandmod; the how-tos in a copy of the checkout), and each block of what a command prints is rewritten with what it printed this time.

    python tools/dev/pages.py docs/tutorial.md docs/how-to/rendering.md

``tests/test_docs.py`` checks that the pages show what their commands print, but for the
figures that vary from run to run (seconds, sizes); this puts one run's figures there, so
none is older than the code. Run it after a change that changes what a page's commands print.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import click

TESTS = Path(__file__).resolve().parent.parent.parent / "tests"
sys.path.insert(0, str(TESTS))

from pages import refreshed  # noqa: E402
from test_docs import _copy_checkout, _this_environment, follow  # noqa: E402


@click.command()
@click.argument("pages", nargs=-1, required=True, type=click.Path(exists=True, dir_okay=False, path_type=Path))
def main(pages: tuple[Path, ...]) -> None:
    """Run PAGES' commands and write what they printed into them; exit 1 if a page could not be followed
    (one whose commands install packages, say: they are not run here, not to change this environment)."""
    status = 0
    for page in pages:
        with tempfile.TemporaryDirectory() as folder:
            # the how-tos and the gallery are followed in a checkout, the tutorial in a new folder (as their tests do)
            where = _copy_checkout(Path(folder) / "checkout") if page.parent.name in ("how-to", "gallery") else Path(folder)
            try:
                outputs = follow(page, where, _this_environment(), installs=False)
            except AssertionError as failed:  # a command failed, or printed what the page does not show
                click.echo(f"{page}: left as it is: {str(failed).splitlines()[0]}", err=True)
                status = 1
                continue
        before = page.read_text(encoding="utf-8")
        after = refreshed(before, outputs)
        if after != before:
            page.write_text(after, encoding="utf-8")
        click.echo(f"{page}: {'figures made again' if after != before else 'unchanged'}")
    sys.exit(status)


if __name__ == "__main__":
    main()
