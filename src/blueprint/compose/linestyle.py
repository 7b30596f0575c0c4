"""Line styles: colour, width, dash and opacity per occlusion level and per kind of line, and the
line style files that describe them. Vector drawings stroke lines with them
(``blueprint.vector.style``); a picture takes the same file as a raster ``Style``
(``raster_style``), its levels only: a picture's edges do not know their kind. GPU-free."""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path

from blueprint.compose.style import FILE_SUFFIXES, STYLES, Style, hex_color
from blueprint.errors import InputError

__all__ = [
    "FILE_SUFFIXES",
    "ISO_128",
    "KINDS",
    "KindStyle",
    "LineStyle",
    "VectorStyle",
    "is_style_file",
    "load_raster_style",
    "load_vector_style",
    "raster_style",
    "vector_style",
]

RGB = tuple[float, float, float]

# The kinds of line by code (``blueprint.vector.linework`` numbers them): what ``data-kind``,
# DXF layers and PDF groups say, and what a line style file's ``[kinds.NAME]`` names.
KINDS: tuple[str, ...] = (
    "",
    "silhouette",
    "border",
    "crease",
    "boundary",
    "intersection",
    "section",
    "hatch",
    "glyph",
    "dimension",
    "sheet",
    "smooth",
)


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
class KindStyle:
    """How lines of one kind differ from their level's style.

    ``width`` multiplies the level's width; ``color``, ``dash`` and ``opacity`` replace the
    level's where given (``None``: the level's own). ``levels[k]`` holds the same for level
    ``k`` alone (the last entry for deeper levels), over the kind's own values. ``show`` False
    leaves the kind out of the drawing (TechDraw's "smooth lines" switch, for ``smooth``).
    """

    width: float = 1.0
    color: RGB | None = None
    dash: tuple[float, ...] | None = None
    opacity: float | None = None
    show: bool = True
    levels: tuple[KindStyle, ...] = ()

    def __post_init__(self) -> None:
        if self.color is not None:
            object.__setattr__(self, "color", _rgb(self.color))
        if self.dash is not None:
            object.__setattr__(self, "dash", tuple(float(d) for d in self.dash))
        object.__setattr__(self, "levels", tuple(self.levels))
        if not (self.width > 0):
            raise InputError(f"line width must be > 0, got {self.width}")
        if self.opacity is not None and not 0.0 <= self.opacity <= 1.0:
            raise InputError(f"opacity must be in [0, 1], got {self.opacity}")

    def applied(self, line: LineStyle, level: int) -> LineStyle:
        """``line``, a level's style, as this kind draws it at ``level``."""
        for entry in (self, self.levels[min(level, len(self.levels) - 1)] if self.levels else None):
            if entry is None:
                continue
            line = replace(
                line,
                width=line.width * entry.width,
                color=line.color if entry.color is None else entry.color,
                dash=line.dash if entry.dash is None else entry.dash,
                opacity=line.opacity if entry.opacity is None else entry.opacity,
            )
        return line


# ISO 128's line widths by kind, in multiples of a level's width (visible lines 1, hidden 0.5 in
# the named styles; the pen is 0.25 mm on a drawing to scale): outlines, edges and
# intersections wide (0.5 mm visible, 0.25 mm hidden), tangent edges of smooth blends narrow,
# a section's outline wide and its hatching narrow, dimensions narrow.
ISO_128: dict[str, KindStyle] = {
    "silhouette": KindStyle(2.0),
    "border": KindStyle(2.0),
    "crease": KindStyle(2.0),
    "boundary": KindStyle(2.0),
    "intersection": KindStyle(2.0),
    "smooth": KindStyle(1.0),
    "section": KindStyle(2.0),
    "hatch": KindStyle(0.7),
    "dimension": KindStyle(1.0),
}


@dataclass(frozen=True)
class VectorStyle:
    """Paper and line styles of a vector drawing.

    ``levels[k]`` styles lines hidden behind ``k`` surfaces; levels past the last entry reuse
    it with the opacity multiplied by ``fade`` per level. ``kinds`` maps a kind's name
    (``KINDS``) to how its lines differ from their level's style (``line``); kinds not in it
    draw in their level's style. Parts named in a drawing's highlight take ``highlight_color``
    and ``highlight_width`` times the width, keeping the dash and opacity. ``paper`` is an
    (r, g, b) background or ``None`` (transparent).
    """

    name: str = "custom"
    paper: RGB | None = (1.0, 1.0, 1.0)
    levels: tuple[LineStyle, ...] = (LineStyle(),)
    fade: float = 0.8
    highlight_color: RGB = (1.0, 0.48, 0.0)
    highlight_width: float = 1.5
    title_color: RGB = field(default=(0.0, 0.0, 0.0))
    kinds: dict[str, KindStyle] = field(default_factory=lambda: dict(ISO_128), hash=False)

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
        for kind in self.kinds:
            if kind not in KINDS or not kind:
                raise InputError(f"unknown kind of line {kind!r} (choose {', '.join(KINDS[1:])})")

    def level(self, k: int, highlighted: bool = False) -> LineStyle:
        """The style of lines at occlusion level ``k``, whatever their kind."""
        last = len(self.levels) - 1
        line = self.levels[min(k, last)]
        if k > last:
            line = replace(line, opacity=line.opacity * self.fade ** (k - last))
        if highlighted:
            line = replace(line, color=self.highlight_color, width=line.width * self.highlight_width)
        return line

    def line(self, kind: int | str, k: int, highlighted: bool = False) -> LineStyle:
        """The style of lines of ``kind`` (a code or a name of ``KINDS``) at level ``k``: the
        level's, as the kind's entry changes it, then the highlight's colour and width."""
        name = KINDS[kind] if isinstance(kind, int) else kind
        line = self.level(k)
        entry = self.kinds.get(name)
        if entry is not None:
            line = entry.applied(line, k)
        if highlighted:
            line = replace(line, color=self.highlight_color, width=line.width * self.highlight_width)
        return line

    def shows(self, kind: int | str) -> bool:
        """Whether lines of ``kind`` are drawn at all."""
        entry = self.kinds.get(KINDS[kind] if isinstance(kind, int) else kind)
        return entry is None or entry.show

    def with_levels(self, *levels: LineStyle) -> VectorStyle:
        return replace(self, levels=tuple(levels))


# Dash patterns by level, in base line widths: visible solid, then ever shorter dashes.
DASHES: tuple[tuple[float, ...], ...] = ((), (6.0, 3.0), (3.0, 3.0), (1.5, 3.0))


def is_style_file(style: str | os.PathLike | Style | VectorStyle) -> bool:
    """Whether ``style`` names a line style file rather than a style of ``STYLES``."""
    return isinstance(style, str | os.PathLike) and Path(style).suffix.lower() in FILE_SUFFIXES


def vector_style(
    style: str | os.PathLike | Style | VectorStyle = "blueprint", dashes: bool = True
) -> VectorStyle:
    """The vector style ``style`` names: a ``VectorStyle`` as it is, a line style file (a path,
    or a name ending in ``.toml`` or ``.json``: see ``load_vector_style``), or the vector
    counterpart of a raster style (a ``Style`` or a name in ``blueprint.compose.style.STYLES``).

    The counterpart draws level 0 in the style's ink and width; level ``k >= 1`` in its hidden
    ink and width at ``hidden_opacity * fade ** (k - 1)``, as the raster composes them, and with
    dashes (``dashes=False`` keeps every level solid, like the raster).
    """
    if isinstance(style, VectorStyle):
        return style
    if isinstance(style, os.PathLike) or is_style_file(style):
        return load_vector_style(style)
    if isinstance(style, str) and style not in STYLES:
        raise InputError(f"unknown style {style!r} (choose {', '.join(STYLES)} or a line style file)")
    raster = STYLES[style] if isinstance(style, str) else style
    inks = raster.layer_inks(len(DASHES))
    levels = [
        LineStyle(
            tuple(float(c) for c in inks[k, :3]),
            raster.width if k == 0 else raster.hidden_width,
            DASHES[k] if dashes else (),
            float(inks[k, 3]),
        )
        for k in range(len(DASHES))
    ]
    paper = None if raster.paper is None else raster.paper[:3]
    return VectorStyle(
        name=raster.name,
        paper=paper,
        levels=tuple(levels),
        fade=raster.fade,
        highlight_color=(1.0, 0.55, 0.1) if paper is not None and sum(paper) < 1.5 else (0.9, 0.3, 0.0),
        title_color=raster.ink[:3],
    )


_STYLE_KEYS = (
    "base",
    "paper",
    "fade",
    "highlight_color",
    "highlight_width",
    "title_color",
    "levels",
    "kinds",
)
_LEVEL_KEYS = ("color", "width", "dash", "opacity")
_KIND_KEYS = ("color", "width", "dash", "opacity", "show", "levels")


def load_vector_style(path: str | os.PathLike) -> VectorStyle:
    """A vector style from a ``.toml`` or ``.json`` file; every key is optional::

        base = "paper"              # the named style it starts from (default: blueprint)
        paper = "#ffffff"           # or "none": a transparent page
        fade = 0.8                  # opacity factor per level past the last one listed
        highlight_color = "#e05a00"
        highlight_width = 1.5       # times the level's width
        title_color = "#000000"

        [[levels]]                  # level 0: visible lines
        color = "#000000"
        width = 1.0                 # times the drawing's line width
        dash = []                   # solid

        [[levels]]                  # level 1: behind one surface
        color = "#1d4f91"
        dash = [6, 3]               # on, off, ... in line widths
        opacity = 0.8

        [kinds.silhouette]          # a kind at every level (KINDS names them)
        width = 2.0                 # times its level's width
        color = "#000000"           # colour, dash and opacity replace the level's

        [[kinds.crease.levels]]     # a kind at level 0, then 1, ... (the last for deeper ones)
        width = 1.5

        [kinds.smooth]
        show = false                # tangent edges of smooth blends left out

    A level leaves out what it takes from the base's level at the same depth; ``levels``
    left out keeps the base's. A kind's entry replaces the base's (ISO 128 widths: ``ISO_128``),
    its width, where left out, the base's; kinds left out keep the base's. Raises
    ``InputError`` naming the file and the entry.
    """
    from blueprint.settings import Entry, read_settings, show

    name = str(path)
    top = Entry(name, read_settings(path, "line style file"), _STYLE_KEYS)
    base = vector_style(top.choice("base", "blueprint", tuple(STYLES)))

    def rgb(entry: Entry, key: str, default: RGB) -> RGB:
        return entry.color(key, "#000000")[:3] if key in entry.table else default

    paper = None if top.table.get("paper") == "none" else rgb(top, "paper", base.paper)

    raw = top.table.get("levels")
    if raw is None:
        levels = base.levels
    elif not isinstance(raw, list) or not raw:
        raise top.fail(f"levels must be a non-empty list of tables ([[levels]] in TOML), got {show(raw)}")
    else:
        levels = []
        for k, table in enumerate(raw):
            entry = Entry(f"{name}: levels {k}", table, _LEVEL_KEYS)
            like = base.level(k)
            levels.append(
                LineStyle(
                    color=rgb(entry, "color", like.color),
                    width=entry.number("width", like.width, 0.0, 16.0, lo_open=True),
                    dash=entry.dash("dash", list(like.dash), unit="line widths", solid_ok=True),
                    opacity=entry.number("opacity", like.opacity, 0.0, 1.0),
                )
            )
    kinds = dict(base.kinds)
    raw = top.table.get("kinds", {})
    if not isinstance(raw, dict):
        raise top.fail(f"kinds must be a table of kinds ([kinds.silhouette] in TOML), got {show(raw)}")
    for kind, table in raw.items():
        if kind not in KINDS or not kind:
            raise top.fail(f"kinds: unknown kind {kind!r} (choose {', '.join(KINDS[1:])})")
        kinds[kind] = _kind_style(Entry(f"{name}: kinds.{kind}", table, _KIND_KEYS), base.kinds.get(kind))
    return VectorStyle(
        name=Path(path).stem,
        paper=paper,
        levels=tuple(levels),
        kinds=kinds,
        fade=top.number("fade", base.fade, 0.0, 1.0),
        highlight_color=rgb(top, "highlight_color", base.highlight_color),
        highlight_width=top.number("highlight_width", base.highlight_width, 0.0, 16.0, lo_open=True),
        title_color=rgb(top, "title_color", base.title_color),
    )


def _kind_style(entry, base: KindStyle | None) -> KindStyle:
    """A kind's entry of a line style file, its width where left out the ``base``'s."""
    from blueprint.settings import Entry, show

    def own(item, default_width: float) -> dict:
        return dict(
            width=item.number("width", default_width, 0.0, 16.0, lo_open=True),
            color=item.color("color", "#000000")[:3] if "color" in item.table else None,
            dash=item.dash("dash", None, unit="line widths", solid_ok=True),
            opacity=item.number("opacity", 1.0, 0.0, 1.0) if "opacity" in item.table else None,
        )

    raw = entry.table.get("levels", [])
    if not isinstance(raw, list):
        raise entry.fail(f"levels must be a list of tables ([[kinds.NAME.levels]] in TOML), got {show(raw)}")
    levels = tuple(
        KindStyle(**own(Entry(f"{entry.where}: levels {k}", table, _LEVEL_KEYS), 1.0))
        for k, table in enumerate(raw)
    )
    return KindStyle(
        **own(entry, 1.0 if base is None else base.width),
        show=entry.boolean("show", True),
        levels=levels,
    )


def raster_style(style: VectorStyle, where: str | None = None) -> Style:
    """The raster ``Style`` of a line style: paper, each listed level's colour and opacity
    (past the last, fading by ``fade``), level 0's width for visible lines and level 1's for
    hidden ones (every hidden layer of a picture takes level 1's width), the highlight. Dashes
    are for vector drawings only. ``where`` (the file) prefixes errors."""
    visible, hidden = style.level(0), style.level(1)
    try:
        return Style(
            style.name,
            paper=None if style.paper is None else (*style.paper, 1.0),
            ink=(*visible.color, visible.opacity),
            hidden_ink=(*hidden.color, 1.0),
            hidden_opacity=hidden.opacity,
            fade=style.fade,
            highlight=(*style.highlight_color, 1.0),
            highlight_width=style.highlight_width,
            width=visible.width,
            hidden_width=hidden.width,
            level_inks=tuple((*line.color, line.opacity) for line in style.levels),
        )
    except InputError as exc:
        if where is None:
            raise
        raise InputError(f"{where}: {exc} (for a picture)") from None


def load_raster_style(path: str | os.PathLike) -> Style:
    """A picture's ``Style`` from a line style file (see ``load_vector_style`` for the format
    and ``raster_style`` for what a picture takes from it)."""
    return raster_style(load_vector_style(path), str(path))
