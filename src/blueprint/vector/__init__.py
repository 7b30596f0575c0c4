"""True vector drawings: visible and hidden lines as SVG, PDF and DXF, styled by occlusion level.

Lines are found in object space (silhouettes, borders, creases, part boundaries, intersections
between parts) and each piece of line gets its occlusion level from the depth layers peeled on
the GPU: how many surfaces lie in front of it. Every line keeps its part, its kind and the
model's edges it was drawn from (``Lines``, in the numbering of ``edge_numbers``).
"""

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
