"""Colours as the styles and the settings files give them: ``#rrggbb`` and RGBA tuples. No GPU."""

from __future__ import annotations

from blueprint.errors import InputError

RGBA = tuple[float, float, float, float]


def hex_color(value: str, alpha: float = 1.0) -> RGBA:
    """'#rrggbb' to a linear-in-sRGB RGBA tuple in [0, 1]."""
    text = value.lstrip("#")
    if len(text) != 6:
        raise InputError(f"colour {value!r} is not of the form #rrggbb")
    try:
        r, g, b = (int(text[i : i + 2], 16) / 255 for i in (0, 2, 4))
    except ValueError:
        raise InputError(f"colour {value!r} is not of the form #rrggbb") from None
    return (r, g, b, alpha)
