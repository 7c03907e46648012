"""A swatch card: every element's colours as the renders show them, with its name."""

from __future__ import annotations

from ..rules.compiler import Ruleset

SWATCH = 16  # pixels per colour square
GAP = 8  # pixels between groups
ROW = SWATCH + 4
BACKGROUND = (24, 24, 30)
TEXT = (230, 230, 230)
MUTED = (150, 150, 160)


def card_layout(ruleset: Ruleset) -> tuple[int, int, int]:
    """The x of the first shade, scorched and glow square (each group one square per colour)."""
    looks = ruleset.looks
    shades_x = GAP
    scorched_x = shades_x + looks.normal.shape[1] * SWATCH + GAP
    glow_x = scorched_x + looks.scorched.shape[1] * SWATCH + GAP
    return shades_x, scorched_x, glow_x


def swatch_card(ruleset: Ruleset):
    """A pillow RGB image: a header, then one row per element (shades, scorched, glowing; id, archetype)."""
    from PIL import Image, ImageDraw, ImageFont

    looks = ruleset.looks
    shades_x, scorched_x, glow_x = card_layout(ruleset)
    text_x = glow_x + looks.glow.shape[1] * SWATCH + GAP
    font = ImageFont.load_default()
    measure = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    kind_x = text_x + int(max(measure.textlength(e.id, font=font) for e in ruleset.elements)) + 2 * GAP
    width = kind_x + int(max(measure.textlength(e.spec.archetype, font=font) for e in ruleset.elements)) + 2 * GAP
    height = ROW * (len(ruleset.elements) + 1) + GAP
    image = Image.new("RGB", (max(width, kind_x + 80), height), BACKGROUND)
    draw = ImageDraw.Draw(image)
    labels = ((shades_x, "shades"), (scorched_x, "scorched"), (glow_x, "hot"), (text_x, "element"), (kind_x, "moves as"))
    for x, label in labels:
        draw.text((x, 4), label, fill=MUTED, font=font)
    for row, element in enumerate(ruleset.by_id, start=1):
        top = row * ROW + 2
        for x, indices in ((shades_x, looks.normal), (scorched_x, looks.scorched), (glow_x, looks.glow)):
            for j, index in enumerate(indices[element.index]):
                colour = tuple(int(c) for c in ruleset.colours[index])
                draw.rectangle([x + j * SWATCH, top, x + (j + 1) * SWATCH - 1, top + SWATCH - 1], fill=colour)
        draw.text((text_x, top + 3), element.id, fill=TEXT, font=font)
        draw.text((kind_x, top + 3), element.spec.archetype, fill=MUTED, font=font)
    return image
