"""Overall dimensions of an orthographic view after ISO 129: extension lines from the part (a
small gap off it, a little beyond the dimension line), a dimension line with closed arrowheads at
both ends, the value above the line in millimetres (vertical ones read from the right).

The values come from the model's vertices in the camera's frame, exact, not from the pixels.
"""

from __future__ import annotations

import math

import numpy as np

from blueprint.scene.sheet import Marks, Text

__all__ = ["dimension_marks", "format_value"]

# ISO 129 measures in millimetres on paper: the gap between the part and an extension line,
# how far an extension line runs past the dimension line, the dimension line's distance from
# the part, the arrowhead's length, the text's height.
GAP_MM, OVERSHOOT_MM, OFFSET_MM, ARROW_MM, TEXT_MM = 1.0, 2.0, 8.0, 3.0, 3.5
# thin lines: the hatch pen (0.7 base line widths: 0.18 mm against 0.25 mm)
DIMENSION_WIDTH = 0.7


def format_value(mm: float) -> str:
    """A length in mm as drawings print it: at most one decimal, no trailing zeros."""
    text = f"{round(mm, 1):.1f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _arrow(tip: np.ndarray, direction: np.ndarray, length: float) -> list:
    """Two strokes of a closed 15° arrowhead (and its base) pointing along ``direction``."""
    back = tip - direction * length
    side = np.array([-direction[1], direction[0]]) * length * math.tan(math.radians(15))
    a, b = back + side, back - side
    return [[tip, a], [tip, b], [a, b]]


def dimension_marks(
    positions: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    mm_per_model: float,
    mm_per_px: float | None,
) -> Marks:
    """The overall width (below the view) and height (right of it) of ``positions`` (N, 3) as
    an orthographic camera sees them.

    Parameters
    ----------
    positions : (N, 3) float
        The model's used vertices.
    view, projection : (4, 4) float64
        The camera's matrices (orthographic).
    size : (int, int)
        The view in pixels.
    mm_per_model : float
        Millimetres per model unit (the values printed).
    mm_per_px : float or None
        Page millimetres per pixel on a drawing to scale; None for a drawing in pixels (ISO's
        measures taken at 96 pixels an inch).
    """
    w, h = size
    eye = np.c_[positions, np.ones(len(positions))] @ view.T
    lo, hi = eye[:, :2].min(axis=0), eye[:, :2].max(axis=0)
    corners = np.array([[lo[0], lo[1], 0, 1], [hi[0], hi[1], 0, 1]]) @ projection.T
    ndc = corners[:, :2] / corners[:, 3:4]
    px = np.c_[(ndc[:, 0] + 1) * 0.5 * w, (1 - ndc[:, 1]) * 0.5 * h]
    left, right = sorted(px[:, 0])
    top, bottom = sorted(px[:, 1])
    per_mm = 1.0 / mm_per_px if mm_per_px else 96.0 / 25.4
    gap, over, offset, arrow, text = (
        v * per_mm for v in (GAP_MM, OVERSHOOT_MM, OFFSET_MM, ARROW_MM, TEXT_MM)
    )
    lines: list = []
    texts = []
    # width, below the view
    y = bottom + offset
    lines += [[[left, bottom + gap], [left, y + over]], [[right, bottom + gap], [right, y + over]]]
    lines.append([[left, y], [right, y]])
    lines += _arrow(np.array([left, y]), np.array([-1.0, 0.0]), arrow)
    lines += _arrow(np.array([right, y]), np.array([1.0, 0.0]), arrow)
    width_mm = float(hi[0] - lo[0]) * mm_per_model
    texts.append(Text((left + right) / 2, y - 0.4 * text, text, format_value(width_mm), "middle"))
    # height, right of the view, its text read from the right
    x = right + offset
    lines += [[[right + gap, top], [x + over, top]], [[right + gap, bottom], [x + over, bottom]]]
    lines.append([[x, top], [x, bottom]])
    lines += _arrow(np.array([x, top]), np.array([0.0, -1.0]), arrow)
    lines += _arrow(np.array([x, bottom]), np.array([0.0, 1.0]), arrow)
    height_mm = float(hi[1] - lo[1]) * mm_per_model
    texts.append(Text(x - 0.4 * text, (top + bottom) / 2, text, format_value(height_mm), "middle", 90.0))
    segments = np.asarray(lines, np.float64)
    return Marks(segments, np.full(len(segments), DIMENSION_WIDTH), tuple(texts))
