"""The glyph value types: boxes, arrows, paths, labels and dimensions in model coordinates, and
how the pieces of them behind a surface are drawn. Plain frozen data, checked where it is read
(``parse``, which holds ``Glyphs``, a whole glyph file of them)."""

from __future__ import annotations

from dataclasses import dataclass

from blueprint.color import RGBA, hex_color

__all__ = [
    "ANCHORS",
    "DEFAULT_COLOR",
    "HIDDEN_MODES",
    "Arrow",
    "Box",
    "Dimension",
    "Hidden",
    "Label",
    "Path3D",
]

DEFAULT_COLOR = "#e53935"
HIDDEN_MODES = ("dim", "dashed", "none")
# which point of the text's box lies at the anchor (matplotlib's and SVG's sense)
ANCHORS = (
    "left",
    "right",
    "center",
    "top",
    "bottom",
    "top-left",
    "top-right",
    "bottom-left",
    "bottom-right",
)


@dataclass(frozen=True)
class Hidden:
    """How glyph pieces behind a surface are drawn: ``dim`` at ``opacity``, ``dashed`` with
    ``dash`` (on, off, ... pixels; hidden labels, which cannot be dashed, at ``opacity``), or
    ``none`` (left out)."""

    mode: str = "dim"
    opacity: float = 0.35
    dash: tuple[float, ...] = (4.0, 3.0)


@dataclass(frozen=True)
class Box:
    """An axis-aligned box: its 12 edges. ``label`` goes at its topmost corner on screen."""

    min: tuple[float, float, float]
    max: tuple[float, float, float]
    color: RGBA = hex_color(DEFAULT_COLOR)
    width: float = 2.0
    dash: tuple[float, ...] | None = None
    label: str = ""


@dataclass(frozen=True)
class Arrow:
    """A shaft from ``start`` to ``end`` with a head at ``end`` (``head``: its length as a
    fraction of the arrow's), drawn across the line of sight. ``label`` goes at the tail."""

    start: tuple[float, float, float]
    end: tuple[float, float, float]
    head: float = 0.1
    color: RGBA = hex_color(DEFAULT_COLOR)
    width: float = 2.0
    dash: tuple[float, ...] | None = None
    label: str = ""


@dataclass(frozen=True)
class Path3D:
    """A polyline through ``points`` (N >= 2), closed back to the first if ``closed``.
    ``label`` goes at the first point."""

    points: tuple[tuple[float, float, float], ...]
    closed: bool = False
    color: RGBA = hex_color(DEFAULT_COLOR)
    width: float = 2.0
    dash: tuple[float, ...] | None = None
    label: str = ""


@dataclass(frozen=True)
class Label:
    """Text at a point; ``anchor`` names the point of the text's box that sits there."""

    at: tuple[float, float, float]
    text: str
    color: RGBA = hex_color(DEFAULT_COLOR)
    size: float = 14.0
    anchor: str = "left"


@dataclass(frozen=True)
class Dimension:
    """A dimension between two model points after ISO 129: extension lines, a dimension line
    with arrowheads, and ``text`` above it (default: the distance from ``start`` to ``end`` in
    millimetres). ``offset`` is the dimension line's distance from the points in model units,
    to the left of ``start`` -> ``end`` on screen where positive; None: ISO 129's 8 mm on
    paper. Drawn over everything, as drawings show dimensions; ``width`` is the base line
    width in pixels (dimension lines are thin: 0.7 of it).

    ``edges`` anchors it to the model instead of to points: one edge number (rows of
    ``blueprint.edge_numbers``) measures that edge between its two ends, two measure the
    distance between those edges (``blueprint.vector.anchors.edge_distance`` says which).
    ``start`` and ``end`` are None until ``blueprint.vector.anchors.anchor_glyphs`` finds
    them on the model drawn."""

    start: tuple[float, float, float] | None
    end: tuple[float, float, float] | None
    text: str = ""
    offset: float | None = None
    color: RGBA = hex_color(DEFAULT_COLOR)
    width: float = 1.0
    edges: tuple[int, ...] = ()
