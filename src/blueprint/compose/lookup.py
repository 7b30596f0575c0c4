"""The style a drawing asks for: a name of ``STYLES``, a line style file, or a ``Style``. Above
both style modules, so that the raster styles need not know the files' (and a style by name,
most drawings', loads no line style module)."""

from __future__ import annotations

import os

from blueprint.compose.style import STYLES, Style
from blueprint.errors import InputError


def get_style(style: str | os.PathLike | Style, grid: float | None = None) -> Style:
    """A style of ``STYLES`` by name, a line style file (a path, or a name ending in ``.toml``
    or ``.json``: ``blueprint.compose.linestyle.load_raster_style``), or a Style; ``grid``
    overrides its grid spacing (pixels)."""
    if isinstance(style, str) and style in STYLES:
        style = STYLES[style]
    elif isinstance(style, str | os.PathLike):
        from blueprint.compose.linestyle import is_style_file, load_raster_style

        if not (isinstance(style, os.PathLike) or is_style_file(style)):
            raise InputError(f"unknown style {style!r} (choose {', '.join(STYLES)})")
        style = load_raster_style(style)
    return style if grid is None else style.with_options(grid=float(grid))
