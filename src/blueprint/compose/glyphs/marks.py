"""Sheet marks in a picture: the lines and texts of ``blueprint.scene.sheet.Marks`` (a plan
sheet's border, title block and labels; dimensions) composited onto a straight-alpha RGBA
canvas, the lines through the silhouette rasteriser, the texts through PIL, turned where a text
is (a vertical dimension's value reads from the right). And the marks of a glyph file's
dimensions, which vector drawings take too."""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from blueprint.color import RGBA
from blueprint.compose.glyphs.raster import composite, draw_pieces
from blueprint.compose.glyphs.values import Dimension
from blueprint.scene.camera import to_pixels
from blueprint.scene.dimension import format_value, linear_dimension
from blueprint.scene.sheet import Marks, Text

__all__ = ["SHEET_FONTS", "dimension_glyph_marks", "draw_mark_text", "draw_marks"]

#: TrueType fonts tried, in order, for texts with "Ø", "×" or "—" (PIL's own font has none of
#: them); PIL's own is the last resort.
SHEET_FONTS = ("DejaVuSans.ttf", "LiberationSans-Regular.ttf", "NotoSans-Regular.ttf", "FreeSans.ttf")


@lru_cache(maxsize=32)
def _font(size: int):
    from PIL import ImageFont

    for name in SHEET_FONTS:
        try:
            return ImageFont.truetype(name, size)
        except OSError:
            continue
    return ImageFont.load_default(size=size)


def draw_mark_text(canvas: np.ndarray, text: Text, color: RGBA) -> None:
    """Draw ``text`` onto the RGBA uint8 ``canvas`` in place: its baseline at ``(text.x,
    text.y)`` (its start or its middle there, as ``text.anchor`` says), ``text.height`` pixels
    high, turned ``text.angle`` degrees anticlockwise about that point."""
    from PIL import Image, ImageDraw

    if not text.text:
        return
    font = _font(max(1, round(text.height)))
    anchor = "ms" if text.anchor == "middle" else "ls"
    left, top, right, bottom = font.getbbox(text.text, anchor=anchor)
    # a square around the anchor holding the text at any angle
    reach = math.ceil(max(abs(left), abs(right), abs(top), abs(bottom))) + 2
    mask = Image.new("L", (2 * reach, 2 * reach), 0)
    ImageDraw.Draw(mask).text((reach, reach), text.text, fill=255, font=font, anchor=anchor)
    if text.angle:
        mask = mask.rotate(text.angle, resample=Image.Resampling.BICUBIC, center=(reach, reach))
    coverage = np.asarray(mask, np.float64) / 255.0
    x0, y0 = round(text.x) - reach, round(text.y) - reach
    h, w = canvas.shape[:2]
    cx0, cy0 = max(x0, 0), max(y0, 0)
    cx1, cy1 = min(x0 + 2 * reach, w), min(y0 + 2 * reach, h)
    if cx1 <= cx0 or cy1 <= cy0:
        return
    composite(canvas, cx0, cy0, coverage[cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0], color)


def draw_marks(canvas: np.ndarray, marks: Marks, color: RGBA, line_width: float = 1.0) -> None:
    """Draw ``marks`` onto the (H, W, 4) uint8 straight-alpha ``canvas`` in place, in ``color``:
    each line ``marks.widths`` times ``line_width`` pixels wide, then the texts."""
    for width in np.unique(marks.widths).tolist():
        lines = marks.lines[marks.widths == width]
        draw_pieces(canvas, lines, np.ones(len(lines)), color, max(width * line_width, 0.5))
    for text in marks.texts:
        draw_mark_text(canvas, text, color)


def dimension_glyph_marks(
    dimension: Dimension,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    mm_per_model: float,
    per_mm: float,
) -> Marks:
    """A glyph file's dimension as sheet marks in the pixels of a picture of ``size`` seen
    through ``view`` and ``projection`` ((4, 4) float64): its value the distance between its
    points in millimetres (``mm_per_model``) unless it has a text; ``per_mm`` pixels a mm of
    ISO 129's measures. Nothing where a point lies behind the camera or the two points are seen
    one behind the other."""
    if dimension.start is None or dimension.end is None:
        raise ValueError("a dimension given by edges has no points until anchored (blueprint.anchor_glyphs)")
    mvp = np.asarray(projection, np.float64) @ np.asarray(view, np.float64)

    def screen(point: np.ndarray) -> np.ndarray | None:
        if (mvp @ np.r_[point, 1.0])[3] <= 0:
            return None
        return to_pixels(point[None], view, projection, size)[0]

    start, end = np.asarray(dimension.start, np.float64), np.asarray(dimension.end, np.float64)
    a, b = screen(start), screen(end)
    empty = Marks(np.zeros((0, 2, 2)), np.zeros(0), ())
    if a is None or b is None or np.linalg.norm(b - a) < 1e-9:
        return empty
    d = (b - a) / np.linalg.norm(b - a)
    left = np.array([d[1], -d[0]])  # left of a -> b on a picture, y down
    offset = None
    if dimension.offset is not None:
        # the model direction that the screen's left is: eye x right, y up, to model
        towards = np.asarray(view, np.float64)[:3, :3].T @ np.array([left[0], -left[1], 0.0])
        moved = screen(start + towards * dimension.offset)
        offset = 0.0 if moved is None else float((moved - a) @ left)
    text = dimension.text or format_value(float(np.linalg.norm(end - start)) * mm_per_model)
    return linear_dimension(a, b, left, text, per_mm, offset)
