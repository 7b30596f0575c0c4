"""Styles and the composition of edge layers into a picture."""

from blueprint.compose.lookup import get_style
from blueprint.compose.style import STYLES, Style, hex_color

__all__ = ["STYLES", "Style", "get_style", "hex_color"]
