"""Line styles of vector drawings: colour, width, dash and opacity per occlusion level.

They and their files live in ``blueprint.compose.linestyle``, a layer down, since pictures take
the same files (``--style lines.toml`` for PNG too); vector drawings stroke their lines with
them, by these names.
"""

from blueprint.compose.linestyle import (
    DASHES,
    FILE_SUFFIXES,
    ISO_128,
    KindStyle,
    LineStyle,
    VectorStyle,
    is_style_file,
    load_vector_style,
    vector_style,
)

__all__ = [
    "DASHES",
    "FILE_SUFFIXES",
    "ISO_128",
    "KindStyle",
    "LineStyle",
    "VectorStyle",
    "is_style_file",
    "load_vector_style",
    "vector_style",
]
