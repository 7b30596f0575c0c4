"""Glyph pixels: screen pieces and label texts composited onto a straight-alpha RGBA canvas in
place, the pieces through the silhouette rasteriser and the texts through PIL's default font."""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from blueprint.color import RGBA

__all__ = ["ANCHOR_SIDES", "LABEL_GAP", "composite", "draw_pieces", "draw_text"]

# gap between a label and its anchor point, as a fraction of the text size
LABEL_GAP = 0.3

ANCHOR_SIDES = {  # anchor -> (horizontal, vertical) position of the point on the text box
    "left": (0, 0.5),
    "right": (1, 0.5),
    "center": (0.5, 0.5),
    "top": (0.5, 0),
    "bottom": (0.5, 1),
    "top-left": (0, 0),
    "top-right": (1, 0),
    "bottom-left": (0, 1),
    "bottom-right": (1, 1),
}


def composite(canvas: np.ndarray, x0: int, y0: int, coverage: np.ndarray, color: RGBA) -> None:
    """Straight-alpha ``over`` of ``color`` at ``coverage`` (h, w) onto the uint8 RGBA
    ``canvas`` at (x0, y0), in place; pixels without coverage keep their exact values."""
    h, w = coverage.shape
    region = canvas[y0 : y0 + h, x0 : x0 + w]
    alpha = coverage.astype(np.float64) * color[3]
    touched = alpha > 0
    if not touched.any():
        return
    a_s = alpha[touched][:, None]
    dst = region[touched].astype(np.float64)
    a_d = dst[:, 3:4] / 255.0
    a_o = a_s + a_d * (1 - a_s)
    rgb = (np.asarray(color[:3]) * 255.0 * a_s + dst[:, :3] * a_d * (1 - a_s)) / a_o
    out = np.concatenate([rgb, a_o * 255.0], axis=1)
    region[touched] = np.clip(np.rint(out), 0, 255).astype(np.uint8)


def draw_pieces(
    canvas: np.ndarray, pieces: np.ndarray, opacity: np.ndarray, color: RGBA, width: float
) -> None:
    """Draw (K, 2, 2) pixel segments at (K,) opacities, ``width`` pixels wide, onto ``canvas``."""
    if not len(pieces):
        return
    h, w = canvas.shape[:2]
    reach = width / 2 + 1.0
    lo = np.floor(pieces.reshape(-1, 2).min(axis=0) - reach).astype(int)
    hi = np.ceil(pieces.reshape(-1, 2).max(axis=0) + reach).astype(int)
    x0, y0 = max(lo[0], 0), max(lo[1], 0)
    x1, y1 = min(hi[0], w), min(hi[1], h)
    if x1 <= x0 or y1 <= y0:
        return
    # the silhouette package (and scipy with it) loads only when a drawing has glyphs
    from blueprint.silhouette.raster import draw_segments

    coverage = draw_segments(pieces - [x0, y0], x1 - x0, y1 - y0, width, opacity)
    composite(canvas, x0, y0, coverage, color)


@lru_cache(maxsize=32)
def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: one bitmap size
        return ImageFont.load_default()


def draw_text(
    canvas: np.ndarray,
    xy: np.ndarray,
    text: str,
    color: RGBA,
    size: float,
    anchor: str,
    opacity: float,
) -> None:
    """Draw ``text`` (``size`` pixels high, at ``opacity``) onto ``canvas`` with its ``anchor``
    point at the pixel position ``xy``, pushed out by ``LABEL_GAP``."""
    from PIL import Image, ImageDraw

    font = _font(max(1, round(size)))
    probe = ImageDraw.Draw(Image.new("L", (1, 1)))
    left, top, right, bottom = probe.multiline_textbbox((0, 0), text, font=font, anchor="la")
    fx, fy = ANCHOR_SIDES[anchor]
    gap = LABEL_GAP * size
    # the point sits at (fx, fy) of the text box, pushed out by the gap on the sides it touches
    x = xy[0] + gap * (0.5 - fx) * 2 * (fx != 0.5) - (left + fx * (right - left))
    y = xy[1] + gap * (0.5 - fy) * 2 * (fy != 0.5) - (top + fy * (bottom - top))
    x0, y0 = math.floor(x + left), math.floor(y + top)
    x1, y1 = math.ceil(x + right) + 1, math.ceil(y + bottom) + 1
    h, w = canvas.shape[:2]
    cx0, cy0, cx1, cy1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
    if cx1 <= cx0 or cy1 <= cy0:
        return
    mask = Image.new("L", (cx1 - cx0, cy1 - cy0), 0)
    ImageDraw.Draw(mask).multiline_text(
        (round(x) - cx0, round(y) - cy0), text, fill=255, font=font, anchor="la"
    )
    coverage = np.asarray(mask, np.float64) / 255.0 * opacity
    composite(canvas, cx0, cy0, coverage, color)
