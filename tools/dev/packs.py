"""Generated mod packs: many elements from many "authors", to load beside the bundled mods.

    python tools/dev/packs.py /tmp/packs --packs 20 --per-pack 25

writes ``/tmp/packs/pack01.toml`` ... ``pack20.toml``: 500 elements, every
archetype, each pack with an element made ``like`` a bundled one, tags, and
reactions among its own elements and on a tag. Every value comes from the
pack's and element's numbers, so the same arguments write the same files.
``sandmod validate --mods /tmp/packs`` loads them with the bundled mods.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import click

#: The archetypes the generated elements take, in turn.
KINDS = ("powder", "liquid", "static", "gas", "powder", "liquid")


def _number(*parts, below: int) -> int:
    """A number in 0..below-1 named by ``parts``: the same on every run and machine."""
    return int.from_bytes(hashlib.sha256(repr(parts).encode()).digest()[:8], "little") % below


def _colour(*parts) -> str:
    return "#" + "".join(f"{64 + _number(*parts, c, below=180):02x}" for c in "rgb")


def _element(pack: int, k: int) -> str:
    """One element's TOML table."""
    kind = KINDS[k % len(KINDS)]
    lines = [f"[elements.p{pack:02d}e{k:02d}]", f'archetype = "{kind}"', f'color = ["{_colour(pack, k, 0)}", "{_colour(pack, k, 1)}"]',
             f'tags = ["pack{pack:02d}"{", " + chr(34) + "fuel" + chr(34) if k % 7 == 2 else ""}]']
    if kind == "powder":
        lines += [f"density = {1100 + _number(pack, k, 'd', below=1500)}", f"friction = {0.2 + _number(pack, k, 'f', below=60) / 100:.2f}"]
    elif kind == "liquid":
        lines += [f"density = {600 + _number(pack, k, 'd', below=900)}", f"dispersion = {1 + _number(pack, k, 's', below=4)}"]
    elif kind == "gas":
        lines += [f"density = {0.2 + _number(pack, k, 'd', below=80) / 100:.2f}", "dispersion = 2"]
    if k % 5 == 4:
        lines.append(f"heated = {{ above = {300 + _number(pack, k, 'h', below=900)}, becomes = \"p{pack:02d}e{(k + 1) % 25:02d}\" }}")
    return "\n".join(lines)


def pack_text(pack: int, per_pack: int) -> str:
    """Mod ``packNN``: ``per_pack`` elements (the first made like bundled sand), and its reactions."""
    parts = [f'[mod]\nname = "pack{pack:02d}"\nversion = "1.0.0"\nrequires = ["sand"]\n',
             f'[elements.p{pack:02d}e00]\nlike = "sand:sand"\ncolor = "{_colour(pack, 0, 0)}"\ntags = ["pack{pack:02d}"]\n']
    parts += [_element(pack, k) + "\n" for k in range(1, per_pack)]
    for k in range(1, per_pack - 1, 6):
        parts.append(f'[[reactions]]\na = "p{pack:02d}e{k:02d}"\nb = "p{pack:02d}e{k + 1:02d}"\nb_becomes = "p{pack:02d}e{k:02d}"\nchance = 0.05\n')
    parts.append(f'[[reactions]]\na = "p{pack:02d}e{per_pack - 1:02d}"\nb = "#fuel"\nb_becomes = "empty"\nchance = 0.01\n')
    return "\n".join(parts)


def write_packs(folder: Path, packs: int = 20, per_pack: int = 25) -> list[Path]:
    """Write ``packs`` mods of ``per_pack`` elements each into ``folder``; their paths."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for pack in range(1, packs + 1):
        path = folder / f"pack{pack:02d}.toml"
        path.write_text(pack_text(pack, per_pack))
        paths.append(path)
    return paths


@click.command()
@click.argument("folder", type=click.Path(file_okay=False, path_type=Path))
@click.option("--packs", type=click.IntRange(1, 99), default=20, show_default=True)
@click.option("--per-pack", type=click.IntRange(2, 99), default=25, show_default=True)
def main(folder: Path, packs: int, per_pack: int) -> None:
    """Write generated mod packs into FOLDER."""
    write_packs(folder, packs, per_pack)
    click.echo(f"{packs} packs of {per_pack} elements in {folder}")


if __name__ == "__main__":
    main()
