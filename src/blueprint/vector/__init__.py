"""True vector drawings: visible and hidden lines as SVG, PDF and DXF, styled by occlusion level.

Lines are found in object space (silhouettes, borders, creases, part boundaries, intersections
between parts) and each piece of line gets its occlusion level from the depth layers peeled on
the GPU: how many surfaces lie in front of it.
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
from .style import LineStyle, VectorStyle, load_vector_style, vector_style

__all__ = [
    "FORMATS",
    "UNITS_MM",
    "LineStyle",
    "Page",
    "VectorDrawing",
    "VectorStyle",
    "draw_vector",
    "draw_vector_sheet",
    "load_vector_style",
    "parse_scale",
    "save_drawing",
    "vector_style",
]
