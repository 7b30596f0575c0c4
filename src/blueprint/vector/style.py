"""Line styles of vector drawings: colour, width, dash and opacity per occlusion level."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from blueprint.compose.style import Style, get_style, hex_color
from blueprint.errors import InputError

__all__ = ["LineStyle", "VectorStyle", "vector_style"]

RGB = tuple[float, float, float]


def _rgb(value) -> RGB:
    if isinstance(value, str):
        return hex_color(value)[:3]
    try:
        r, g, b = (float(v) for v in tuple(value)[:3])
    except (TypeError, ValueError):
        raise InputError(f"colour {value!r} is neither '#rrggbb' nor (r, g, b)") from None
    if not all(0.0 <= v <= 1.0 for v in (r, g, b)):
        raise InputError(f"colour {value!r} must have components in [0, 1]")
    return (r, g, b)


@dataclass(frozen=True)
class LineStyle:
    """How lines of one occlusion level are stroked.

    ``color`` is '#rrggbb' or (r, g, b) in [0, 1]; ``width`` and the on/off lengths of ``dash``
    are multiples of the drawing's base line width (``()`` is a solid line); ``opacity`` is in
    [0, 1].
    """

    color: RGB = (0.0, 0.0, 0.0)
    width: float = 1.0
    dash: tuple[float, ...] = ()
    opacity: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "color", _rgb(self.color))
        object.__setattr__(self, "dash", tuple(float(d) for d in self.dash))
        if not (self.width > 0):
            raise InputError(f"line width must be > 0, got {self.width}")
        if not 0.0 <= self.opacity <= 1.0:
            raise InputError(f"opacity must be in [0, 1], got {self.opacity}")
        if any(d < 0 for d in self.dash) or (self.dash and sum(self.dash) <= 0):
            raise InputError(f"dash lengths must be >= 0 and not all zero, got {self.dash}")

    @property
    def hex(self) -> str:
        return "#" + "".join(f"{round(c * 255):02x}" for c in self.color)


@dataclass(frozen=True)
class VectorStyle:
    """Paper and line styles of a vector drawing.

    ``levels[k]`` styles lines hidden behind ``k`` surfaces; levels past the last entry reuse
    it with the opacity multiplied by ``fade`` per level. Parts named in a drawing's highlight
    take ``highlight_color`` and ``highlight_width`` times the width, keeping the level's dash and
    opacity. ``paper`` is an (r, g, b) background or ``None`` (transparent).
    """

    name: str = "custom"
    paper: RGB | None = (1.0, 1.0, 1.0)
    levels: tuple[LineStyle, ...] = (LineStyle(),)
    fade: float = 0.8
    highlight_color: RGB = (1.0, 0.48, 0.0)
    highlight_width: float = 1.5
    title_color: RGB = field(default=(0.0, 0.0, 0.0))

    def __post_init__(self) -> None:
        if not self.levels:
            raise InputError("a vector style needs at least one level style")
        if self.paper is not None:
            object.__setattr__(self, "paper", _rgb(self.paper))
        object.__setattr__(self, "highlight_color", _rgb(self.highlight_color))
        object.__setattr__(self, "title_color", _rgb(self.title_color))
        object.__setattr__(self, "levels", tuple(self.levels))
        if not 0.0 <= self.fade <= 1.0:
            raise InputError(f"fade must be in [0, 1], got {self.fade}")
        if not self.highlight_width > 0:
            raise InputError(f"highlight width must be > 0, got {self.highlight_width}")

    def level(self, k: int, highlighted: bool = False) -> LineStyle:
        """The style of lines at occlusion level ``k``."""
        last = len(self.levels) - 1
        line = self.levels[min(k, last)]
        if k > last:
            line = replace(line, opacity=line.opacity * self.fade ** (k - last))
        if highlighted:
            line = replace(line, color=self.highlight_color, width=line.width * self.highlight_width)
        return line

    def with_levels(self, *levels: LineStyle) -> VectorStyle:
        return replace(self, levels=tuple(levels))


# Dash patterns by level, in base line widths: visible solid, then ever shorter dashes.
DASHES: tuple[tuple[float, ...], ...] = ((), (6.0, 3.0), (3.0, 3.0), (1.5, 3.0))


def vector_style(style: str | Style | VectorStyle = "blueprint", dashes: bool = True) -> VectorStyle:
    """The vector counterpart of a raster style (or a ``VectorStyle`` as it is).

    Level 0 is drawn in the style's ink; level ``k >= 1`` in its hidden ink at
    ``hidden_opacity * fade ** (k - 1)``, as the raster composes them, and with dashes
    (``dashes=False`` keeps every level solid, like the raster).
    """
    if isinstance(style, VectorStyle):
        return style
    raster = get_style(style)
    levels = [LineStyle(raster.ink[:3], 1.0, (), raster.ink[3])]
    for k in range(1, len(DASHES)):
        levels.append(
            LineStyle(
                raster.hidden_ink[:3],
                1.0,
                DASHES[k] if dashes else (),
                raster.hidden_ink[3] * raster.hidden_opacity * raster.fade ** (k - 1),
            )
        )
    paper = None if raster.paper is None else raster.paper[:3]
    return VectorStyle(
        name=raster.name,
        paper=paper,
        levels=tuple(levels),
        fade=raster.fade,
        highlight_color=(1.0, 0.55, 0.1) if paper is not None and sum(paper) < 1.5 else (0.9, 0.3, 0.0),
        title_color=raster.ink[:3],
    )
