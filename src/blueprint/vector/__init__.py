"""True vector drawings: visible and hidden lines as SVG, PDF and DXF, styled by occlusion level.

Lines are found in object space (silhouettes, borders, creases, part boundaries, intersections
between parts) and each piece of line gets its occlusion level from the depth layers peeled on
the GPU: how many surfaces lie in front of it. Every line keeps its part, its kind and the
model's edges it was drawn from (``Lines``, in the numbering of ``edge_numbers``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from blueprint.lazy import lazy_names

# each name loads with its module on first use: a picture's smooth contours
# (``vector.contour_ink``) need the lines and their occlusion, not the drawings and their files
_EXPORTS = {
    **dict.fromkeys(
        ("FORMATS", "UNITS_MM", "Page", "VectorDrawing", "draw_vector", "draw_vector_sheet", "parse_scale",
         "save_drawing"),
        "blueprint.vector.drawing",
    ),
    **dict.fromkeys(("edge_numbers", "edge_segments"), "blueprint.vector.lines"),
    **dict.fromkeys(("KINDS", "Lines"), "blueprint.vector.linework"),
    **dict.fromkeys(
        ("KindStyle", "LineStyle", "VectorStyle", "load_vector_style", "vector_style"),
        "blueprint.vector.style",
    ),
}  # fmt: skip

if TYPE_CHECKING:
    from .drawing import (
        FORMATS,
        UNITS_MM,
        Page,
        VectorDrawing,
        draw_vector,
        draw_vector_sheet,
        parse_scale,
        save_drawing,
    )
    from .lines import edge_numbers, edge_segments
    from .linework import KINDS, Lines
    from .style import KindStyle, LineStyle, VectorStyle, load_vector_style, vector_style

__all__ = [
    "FORMATS",
    "KINDS",
    "UNITS_MM",
    "KindStyle",
    "LineStyle",
    "Lines",
    "Page",
    "VectorDrawing",
    "VectorStyle",
    "draw_vector",
    "draw_vector_sheet",
    "edge_numbers",
    "edge_segments",
    "load_vector_style",
    "parse_scale",
    "save_drawing",
    "vector_style",
]

__getattr__, __dir__ = lazy_names(__name__, _EXPORTS, globals())
