"""Dimensions drawn after ISO 129, as sheet marks in pixels: extension lines from the part (a
small gap off it, a little beyond the dimension line), a dimension line with closed arrowheads at
both ends, the value above the line (parallel to it, read from below or from the right); and
diameters: a line through the circle's centre, arrowheads on the circle, "Ø value" on a shoulder.

Pure geometry, no GPU: pictures (``blueprint.compose.glyphs.marks``) and vector drawings draw the
same marks, so that they print the same numbers.
"""

from __future__ import annotations

import math

import numpy as np

from blueprint.scene.camera import clip_to_pixels, transform
from blueprint.scene.sheet import Marks, Text
from blueprint.scene.units import UNITS_MM

__all__ = [
    "DIMENSION_WIDTH",
    "UNITS_MM",
    "diameter_marks",
    "dimension_margin",
    "format_value",
    "linear_dimension",
    "overall_dimensions",
]

# ISO 129 measures in millimetres on paper: the gap between the part and an extension line,
# how far an extension line runs past the dimension line, the dimension line's distance from
# the part, the arrowhead's length, the text's height.
GAP_MM, OVERSHOOT_MM, OFFSET_MM, ARROW_MM, TEXT_MM = 1.0, 2.0, 8.0, 3.0, 3.5
#: Thin lines, in base line widths: the hatch pen (0.18 mm against 0.25 mm).
DIMENSION_WIDTH = 0.7


def dimension_margin(size: tuple[int, int], per_mm: float, margin: float = 0.05) -> float:
    """The fit margin (``Camera.fit``'s, a fraction of the picture a side) of a view of ``size``
    pixels that leaves room past ``margin`` for its overall dimensions below and right of the
    model (ISO 129's offset and overshoot, ``per_mm`` pixels a mm), at most 0.4."""
    room = (OFFSET_MM + OVERSHOOT_MM + 1.0) * per_mm
    return min(margin + room / max(min(size), 1), 0.4)


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


def _marks(lines: list, texts: list[Text]) -> Marks:
    segments = np.asarray(lines, np.float64).reshape(-1, 2, 2)
    kinds = np.full(len(segments), "dimension")
    return Marks(segments, np.full(len(segments), DIMENSION_WIDTH), tuple(texts), kinds)


def _measures(per_mm: float) -> tuple[float, float, float, float, float]:
    return tuple(v * per_mm for v in (GAP_MM, OVERSHOOT_MM, OFFSET_MM, ARROW_MM, TEXT_MM))


def linear_dimension(
    a: np.ndarray,
    b: np.ndarray,
    side: np.ndarray,
    text: str,
    per_mm: float,
    offset: float | None = None,
) -> Marks:
    """A dimension between the pixels ``a`` and ``b`` (2,), its line ``offset`` pixels (default
    ISO 129's 8 mm) from them towards ``side`` (a (2,) direction across the measured points),
    with extension lines, arrowheads and ``text`` above the line; ``per_mm`` pixels a mm of
    ISO 129's measures."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    gap, over, default, arrow, height = _measures(per_mm)
    offset = default if offset is None else float(offset)
    side = np.asarray(side, np.float64)
    side = side / (np.linalg.norm(side) or 1.0)
    # the dimension line runs square to ``side``: what a -> b spans along ``side`` the
    # extension lines take up
    along = b - a
    along = along - (along @ side) * side
    length = float(np.linalg.norm(along))
    if length == 0.0:
        return _marks([], [])
    d = along / length
    start = a + side * offset
    end = start + along
    # extension lines run from a gap off each point to a little beyond the dimension line
    sign = 1.0 if offset >= 0 else -1.0
    lines = [
        [a + side * sign * gap, start + side * sign * over],
        [b + side * sign * gap, end + side * sign * over],
        [start, end],
    ]
    lines += _arrow(start, -d, arrow)
    lines += _arrow(end, d, arrow)
    # read from below or from the right: the text's direction points rightwards, or up
    read = d if (d[0] > 1e-9 or (abs(d[0]) <= 1e-9 and d[1] < 0)) else -d
    above = np.array([read[1], -read[0]])
    middle = (start + end) / 2 + above * 0.4 * height
    angle = math.degrees(math.atan2(-read[1], read[0]))
    angle = 0.0 if abs(angle) < 1e-9 else angle
    return _marks(
        lines, [Text(float(middle[0]), float(middle[1]), height, text, "middle", angle, "dimension")]
    )


def overall_dimensions(
    positions: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    mm_per_model: float,
    per_mm: float,
) -> Marks:
    """The overall width (below the view) and height (right of it) of ``positions`` (N, 3) as an
    orthographic camera (``view``, ``projection``) sees them on a picture of ``size`` pixels.

    The values come from the vertices in the camera's frame, exact, not from the pixels, in mm
    (``mm_per_model``); ``per_mm`` pixels a mm of ISO 129's measures.
    """
    eye = transform(positions, view)
    lo, hi = eye[:, :2].min(axis=0), eye[:, :2].max(axis=0)
    px = clip_to_pixels(transform(np.array([[lo[0], lo[1], 0.0], [hi[0], hi[1], 0.0]]), projection), size)
    left, right = sorted(px[:, 0])
    top, bottom = sorted(px[:, 1])
    width = format_value(float(hi[0] - lo[0]) * mm_per_model)
    height = format_value(float(hi[1] - lo[1]) * mm_per_model)
    return Marks.concatenate(
        [
            linear_dimension([left, bottom], [right, bottom], [0.0, 1.0], width, per_mm),
            linear_dimension([right, top], [right, bottom], [1.0, 0.0], height, per_mm),
        ]
    )


def diameter_marks(
    centre: np.ndarray, radius: float, text: str, per_mm: float, toward: str = "right"
) -> Marks:
    """A diameter after ISO 129: a line at 45° through ``centre`` (2,) pixels across the circle
    of ``radius`` pixels, arrowheads on the circle pointing out, and ``text`` ("Ø 12") on a
    shoulder beyond the circle's upper right (or upper left, ``toward="left"``), long enough
    for it."""
    _, _, _, arrow, height = _measures(per_mm)
    centre = np.asarray(centre, np.float64)
    across = 1.0 if toward == "right" else -1.0
    u = np.array([across, -1.0]) / math.sqrt(2.0)  # up and to that side on a picture
    near, far = centre - u * radius, centre + u * radius
    knee = far + u * (arrow + height)
    shoulder = knee + np.array([across * 0.6 * height * len(text), 0.0])
    lines = [[near, far], [far, knee], [knee, shoulder]]
    lines += _arrow(far, u, arrow)
    lines += _arrow(near, -u, arrow)
    middle = (knee + shoulder) / 2 - np.array([0.0, 0.4 * height])
    return _marks(lines, [Text(float(middle[0]), float(middle[1]), height, text, "middle", kind="dimension")])
