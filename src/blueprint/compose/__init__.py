"""Styles and the composition of edge layers into a picture."""

from blueprint.compose.style import STYLES, Style, get_style, hex_color

__all__ = ["STYLES", "Style", "get_style", "hex_color"]
