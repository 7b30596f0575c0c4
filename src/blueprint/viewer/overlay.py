"""CPU-side pieces of the viewer: the heads-up lines and the help box as an overlay, and
screenshot names. Images are (H, W, 4) uint8 RGBA, row 0 at the top, straight alpha."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

# What shows through where a style has no paper.
BACKDROP = (200, 200, 200)
LINE_HEIGHT = 17
FONT_SIZE = 12
HELP_LINES = (
    "mouse  left drag: orbit   right drag / shift+left: pan   wheel: zoom",
    "click  pick a part (again on the same spot: the part behind it; on paper: none)",
    "D / shift+D  one layer more / fewer      A  all layers",
    "S  next style      1-7  iso front back left right top bottom",
    "M  depth mask: peel until the picked part shows",
    "O  orthographic / perspective      T  turntable on / off",
    "P  save a screenshot next to the model      H  this help      Esc  quit",
)


@functools.lru_cache(maxsize=4)
def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: the fixed bitmap font
        return ImageFont.load_default()


def help_overlay(size: tuple[int, int], help_box: bool) -> np.ndarray:
    """(H, W, 4) uint8 straight-alpha overlay of window ``size`` (W, H): clear, with the help
    box in the middle if asked."""
    from PIL import Image, ImageDraw

    w, h = size
    picture = Image.new("RGBA", (w, h), (0, 0, 0, 0))
    if help_box:
        font = _font(FONT_SIZE)
        draw = ImageDraw.Draw(picture, "RGBA")
        widths = [draw.textlength(line, font=font) for line in HELP_LINES]
        box_w = int(max(widths)) + 24
        box_h = LINE_HEIGHT * len(HELP_LINES) + 16
        x0, y0 = max(0, (w - box_w) // 2), max(0, (h - box_h) // 2)
        draw.rectangle((x0, y0, x0 + box_w, y0 + box_h), fill=(0, 0, 0, 200), outline=(255, 255, 255, 255))
        for i, line in enumerate(HELP_LINES):
            draw.text((x0 + 12, y0 + 8 + i * LINE_HEIGHT), line, fill=(255, 255, 255, 255), font=font)
    return np.asarray(picture)


def band_overlay(rows: np.ndarray, lines: list[str]) -> np.ndarray:
    """The top ``rows`` (R, W, 4) of an overlay with the heads-up ``lines`` drawn over them in a
    band of ``LINE_HEIGHT`` pixels a line (cut to R rows): what changes from frame to frame."""
    from PIL import Image, ImageDraw

    picture = Image.fromarray(np.ascontiguousarray(rows), "RGBA")
    band_h = min(rows.shape[0], LINE_HEIGHT * len(lines))
    if band_h:
        # drawn on a band of its own and pasted, so no glyph reaches below the band
        band = Image.new("RGBA", (rows.shape[1], band_h), (0, 0, 0, 170))
        ink = ImageDraw.Draw(band, "RGBA")
        font = _font(FONT_SIZE)
        for i, line in enumerate(lines):
            ink.text((6, i * LINE_HEIGHT + 2), line, fill=(255, 255, 255, 255), font=font)
        picture.paste(band, (0, 0))
    return np.asarray(picture)


def screenshot_path(model_path: Path) -> Path:
    """The first free ``NAME-N.png`` beside the model (N = 1, 2, ...): never an existing file."""
    folder, stem = model_path.parent, model_path.stem
    n = 1
    while (folder / f"{stem}-{n}.png").exists():
        n += 1
    return folder / f"{stem}-{n}.png"
