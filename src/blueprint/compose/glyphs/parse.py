"""``Glyphs``, everything in one glyph file, and glyph files (TOML or JSON) and plain data into
it, checked: any problem is one ``InputError`` line naming the file, the entry (``box 2``) and
what is wrong."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from blueprint.color import RGBA
from blueprint.compose.glyphs.values import (
    ANCHORS,
    DEFAULT_COLOR,
    HIDDEN_MODES,
    Arrow,
    Box,
    Dimension,
    Hidden,
    Label,
    Path3D,
)
from blueprint.errors import InputError
from blueprint.settings import GLYPH_LIMIT, Entry, is_number, read_settings, show

__all__ = ["Glyphs", "load_glyphs", "parse_glyphs"]

_MAX_WIDTH = 64.0
_SIZE_RANGE = (4.0, 256.0)
_MAX_POINTS = 100_000

_KINDS = {
    "arrow": ("from", "to", "head", "color", "width", "dash", "label"),
    "box": ("min", "max", "color", "width", "dash", "label"),
    "dimension": ("from", "to", "edge", "edges", "text", "offset", "color", "width"),
    "label": ("at", "text", "color", "size", "anchor"),
    "path": ("points", "closed", "color", "width", "dash", "label"),
}
_REQUIRED = {
    "arrow": ("from", "to"),
    "box": ("min", "max"),
    "dimension": (),
    "label": ("at", "text"),
    "path": ("points",),
}
# a dimension's offset from its points, in model units, either way
_MAX_OFFSET = 1e12
# edge numbers beyond this are no model's (and would not fit an int64 sum)
_MAX_EDGE = 2**53
_HIDDEN_KEYS = ("mode", "opacity", "dash")
_TOP = (*sorted(_KINDS), "hidden")


# what errors name when the glyphs come from no file
_DEFAULT_SOURCE = "glyphs"


@dataclass(frozen=True)
class Glyphs:
    """Everything in one glyph file. Drawn in this order: paths, boxes, arrows, labels,
    dimensions."""

    boxes: tuple[Box, ...] = ()
    arrows: tuple[Arrow, ...] = ()
    paths: tuple[Path3D, ...] = ()
    labels: tuple[Label, ...] = ()
    hidden: Hidden = field(default_factory=Hidden)
    source: str = _DEFAULT_SOURCE
    dimensions: tuple[Dimension, ...] = ()

    def __len__(self) -> int:
        return len(self.boxes) + len(self.arrows) + len(self.paths) + len(self.labels) + len(self.dimensions)

    @classmethod
    def from_dict(cls, data: Any, source: str = _DEFAULT_SOURCE) -> Glyphs:
        """Validate plain data (a parsed TOML or JSON document) into ``Glyphs``.

        Raises ``InputError`` naming ``source``, the entry (``box 2``) and the problem.
        """
        return parse_glyphs(data, str(source))


def load_glyphs(path: str | os.PathLike) -> Glyphs:
    """Read a glyph file: ``.toml`` or ``.json``. Raises ``InputError`` on any problem."""
    return parse_glyphs(read_settings(path, "glyph file"), str(path))


class _Entry(Entry):
    """A glyph's table: colours default to ``DEFAULT_COLOR``, widths are pixels."""

    def color(self, key: str = "color", default: str = DEFAULT_COLOR) -> RGBA:
        return super().color(key, default)

    def width(self) -> float:
        return self.number("width", 2.0, 0.0, _MAX_WIDTH, lo_open=True)


def parse_glyphs(data: Any, source: str) -> Glyphs:
    """``Glyphs`` from a parsed document; ``source`` names it in errors."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: must be a table of glyph lists ({', '.join(_TOP)}), got {show(data)}")
    for key in data:
        if key not in _TOP:
            raise InputError(f"{source}: unknown entry {key!r} (allowed: {', '.join(_TOP)})")
    hidden = Hidden()
    if "hidden" in data:
        entry = _Entry(f"{source}: hidden", data["hidden"], _HIDDEN_KEYS)
        hidden = Hidden(
            mode=entry.choice("mode", hidden.mode, HIDDEN_MODES),
            opacity=entry.number("opacity", hidden.opacity, 0.0, 1.0),
            dash=entry.dash("dash", list(hidden.dash)),
        )
    lists: dict[str, list] = {}
    for kind in _KINDS:
        items = data.get(kind, [])
        if not isinstance(items, list):
            raise InputError(
                f"{source}: {kind} must be a list of tables ([[{kind}]] in TOML), got a {_kind(items)}"
            )
    # counted before any is checked: each is projected and stroked every frame
    count = sum(len(data.get(kind, [])) for kind in _KINDS)
    if count > GLYPH_LIMIT:
        raise InputError(f"{source}: {count} glyphs, over the limit of {GLYPH_LIMIT}")
    for kind in _KINDS:
        items = data.get(kind, [])
        lists[kind] = [
            _Entry(f"{source}: {kind} {i}", table, _KINDS[kind], _REQUIRED[kind])
            for i, table in enumerate(items, 1)
        ]
    return Glyphs(
        boxes=tuple(_box(e) for e in lists["box"]),
        arrows=tuple(_arrow(e) for e in lists["arrow"]),
        paths=tuple(_path(e) for e in lists["path"]),
        labels=tuple(_label(e) for e in lists["label"]),
        hidden=hidden,
        source=source,
        dimensions=tuple(_dimension(e) for e in lists["dimension"]),
    )


def _kind(value: Any) -> str:
    return {dict: "table", str: "string", bool: "boolean"}.get(type(value), type(value).__name__)


def _box(e: _Entry) -> Box:
    lo, hi = e.point("min"), e.point("max")
    for axis, a, b in zip("xyz", lo, hi, strict=True):
        if a > b:
            raise e.fail(f"min must not exceed max ({axis}: {a:g} > {b:g})")
    return Box(lo, hi, e.color(), e.width(), e.dash(), e.string("label", ""))


def _arrow(e: _Entry) -> Arrow:
    start, end = e.point("from"), e.point("to")
    if start == end:
        raise e.fail("from and to are the same point")
    head = e.number("head", 0.1, 0.0, 1.0)
    return Arrow(start, end, head, e.color(), e.width(), e.dash(), e.string("label", ""))


def _path(e: _Entry) -> Path3D:
    points = e.table["points"]
    if not isinstance(points, list | tuple) or not 2 <= len(points) <= _MAX_POINTS:
        raise e.fail(f"points must be a list of 2 to {_MAX_POINTS} points [x, y, z], got {show(points)}")
    checked = []
    for k, p in enumerate(points, 1):
        checked.append(e.point(f"point {k}", p))
    closed = e.boolean("closed", False)
    return Path3D(tuple(checked), closed, e.color(), e.width(), e.dash(), e.string("label", ""))


def _label(e: _Entry) -> Label:
    return Label(
        e.point("at"),
        e.string("text", "", nonempty=True),
        e.color(),
        e.number("size", 14.0, *_SIZE_RANGE),
        e.choice("anchor", "left", ANCHORS),
    )


def _model_point(e: _Entry, key: str) -> tuple[float, float, float]:
    value = e.table[key]
    if not isinstance(value, list | tuple) or len(value) != 3 or not all(map(is_number, value)):
        raise e.fail(f"{key} must be 3 numbers [x, y, z] in model coordinates, got {show(value)}")
    return e.point(key)


def _edge_number(e: _Entry, key: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= _MAX_EDGE:
        raise e.fail(f"{key} must be an edge number (a whole number from 0), got {show(value)}")
    return value


def _anchors(e: _Entry) -> tuple[tuple | None, tuple | None, tuple[int, ...]]:
    """(start, end, edges) of a dimension: two model points, one edge or two edges."""
    given = [key for key in ("edge", "edges") if key in e.table]
    points = [key for key in ("from", "to") if key in e.table]
    if (given and points) or len(given) > 1:
        raise e.fail(f"give from and to, edge or edges, one of them alone (got {', '.join(points + given)})")
    if not given:
        if not points:
            raise e.fail("give from and to (model points), edge = N or edges = [N, M] (edge numbers)")
        for key in ("from", "to"):
            if key not in e.table:
                raise e.fail(f"{key} is missing")
        start, end = _model_point(e, "from"), _model_point(e, "to")
        if start == end:
            raise e.fail("from and to are the same point: a dimension measures between two")
        return start, end, ()
    if given == ["edge"]:
        return None, None, (_edge_number(e, "edge", e.table["edge"]),)
    value = e.table["edges"]
    if not isinstance(value, list | tuple) or len(value) != 2:
        raise e.fail(f"edges must be two edge numbers [N, M], got {show(value)}")
    edges = tuple(_edge_number(e, "edges", v) for v in value)
    if edges[0] == edges[1]:
        raise e.fail(f"edges names edge {edges[0]} twice: a dimension measures between two")
    return None, None, edges


def _dimension(e: _Entry) -> Dimension:
    start, end, edges = _anchors(e)
    offset = None
    if "offset" in e.table:
        offset = e.number("offset", 0.0, -_MAX_OFFSET, _MAX_OFFSET)
    width = e.number("width", 1.0, 0.0, _MAX_WIDTH, lo_open=True)
    return Dimension(start, end, e.string("text", ""), offset, e.color(), width, edges)
