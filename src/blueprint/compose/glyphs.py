"""Glyphs: boxes, arrows, paths and text labels in model coordinates, drawn into a blueprint
with the same depth test as its edges, so that what lies behind a surface is drawn as a hidden
line (dimmed or dashed) or left out.

A glyph file is TOML or JSON (chosen by extension)::

    [hidden]                      # how glyph pieces behind a surface are drawn
    mode = "dim"                  # "dim" (lower opacity), "dashed" or "none"
    opacity = 0.35                # dim mode
    dash = [4, 3]                 # dashed mode: on, off lengths in pixels

    [[box]]
    min = [-7, 14, -26]
    max = [7, 66, 26]
    color = "#ff8800"             # optional, every glyph; default DEFAULT_COLOR
    width = 2                     # optional: line width in pixels
    label = "gear"                # optional: text at the box's top corner on screen

    [[arrow]]
    from = [-45, 90, 40]
    to = [-45, 52, 0]
    head = 0.1                    # head length, fraction of the arrow's length

    [[path]]
    points = [[0, 0, 0], [1, 0, 0], [1, 1, 0]]
    closed = false
    dash = [6, 4]                 # optional for box, arrow and path: on, off in pixels

    [[label]]
    at = [0, 80, 0]
    text = "gear"
    size = 14                     # pixels
    anchor = "left"               # which side of the text sits at the point

``load_glyphs`` reads a file and ``Glyphs.from_dict`` validates plain data (both raise
``InputError`` with one line naming the file and the entry); ``draw_glyphs`` draws them over an
image, given the camera and the blueprint's front depth layer; ``render_with_glyphs`` peels
that layer itself. No GPU here except through ``render_with_glyphs``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from blueprint.compose.style import RGBA, hex_color
from blueprint.errors import InputError
from blueprint.scene.camera import Camera
from blueprint.settings import Entry, read_settings, show
from blueprint.silhouette.raster import draw_segments

__all__ = [
    "ANCHORS",
    "HIDDEN_MODES",
    "Arrow",
    "Box",
    "Glyphs",
    "Hidden",
    "Label",
    "Path3D",
    "draw_glyphs",
    "load_glyphs",
    "render_with_glyphs",
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
# Glyph segments are sampled this often (pixels along the screen) for the depth test.
SAMPLE_STEP = 0.5
# A sample is hidden when the front surface is nearer than its eye depth by more than this
# fraction of it. The surface is taken as the farthest of the 3x3 pixels around the sample's, so
# a glyph lying on a face (even one seen at a grazing angle) or along a silhouette never hides
# itself; an occluder's outline lets the glyph through by at most a pixel.
DEPTH_TOLERANCE = 1e-3
# gap between a label and its anchor point, as a fraction of the text size
LABEL_GAP = 0.3
# arrow head half-width, as a fraction of the head length
HEAD_SPREAD = 0.45

_SOURCE_DEFAULT = "glyphs"
_MAX_WIDTH = 64.0
_SIZE_RANGE = (4.0, 256.0)
_MAX_POINTS = 100_000


# -- data ------------------------------------------------------------------------------------
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
class Glyphs:
    """Everything in one glyph file. Drawn in this order: paths, boxes, arrows, labels."""

    boxes: tuple[Box, ...] = ()
    arrows: tuple[Arrow, ...] = ()
    paths: tuple[Path3D, ...] = ()
    labels: tuple[Label, ...] = ()
    hidden: Hidden = field(default_factory=Hidden)
    source: str = _SOURCE_DEFAULT

    def __len__(self) -> int:
        return len(self.boxes) + len(self.arrows) + len(self.paths) + len(self.labels)

    @classmethod
    def from_dict(cls, data: Any, source: str = _SOURCE_DEFAULT) -> Glyphs:
        """Validate plain data (a parsed TOML or JSON document) into ``Glyphs``.

        Raises ``InputError`` naming ``source``, the entry (``box 2``) and the problem.
        """
        return _parse(data, str(source))


def load_glyphs(path: str | os.PathLike) -> Glyphs:
    """Read a glyph file: ``.toml`` or ``.json``. Raises ``InputError`` on any problem."""
    return _parse(read_settings(path, "glyph file"), str(path))


# -- validation ------------------------------------------------------------------------------
_KINDS = {
    "arrow": ("from", "to", "head", "color", "width", "dash", "label"),
    "box": ("min", "max", "color", "width", "dash", "label"),
    "label": ("at", "text", "color", "size", "anchor"),
    "path": ("points", "closed", "color", "width", "dash", "label"),
}
_REQUIRED = {"arrow": ("from", "to"), "box": ("min", "max"), "label": ("at", "text"), "path": ("points",)}
_HIDDEN_KEYS = ("mode", "opacity", "dash")
_TOP = (*sorted(_KINDS), "hidden")


class _Entry(Entry):
    """A glyph's table: colours default to ``DEFAULT_COLOR``, widths are pixels."""

    def color(self, key: str = "color", default: str = DEFAULT_COLOR) -> RGBA:
        return super().color(key, default)

    def width(self) -> float:
        return self.number("width", 2.0, 0.0, _MAX_WIDTH, lo_open=True)


def _parse(data: Any, source: str) -> Glyphs:
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


# -- projection ------------------------------------------------------------------------------
@dataclass
class _View:
    """A camera at an image size: model points to pixels and eye depths, and the surface test."""

    camera: Camera
    width: int
    height: int
    depth: np.ndarray | None  # (H, W) window depth of the front surface, 1.0: none

    def __post_init__(self) -> None:
        self.mvp = self.camera.projection_matrix() @ self.camera.view_matrix()

    def clip(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) model points -> (..., 4) clip coordinates."""
        return points @ self.mvp[:, :3].T + self.mvp[:, 3]

    def screen(self, clip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(..., 4) clip coordinates in front of the near plane -> (..., 2) pixels, (...) NDC z."""
        ndc = clip[..., :3] / clip[..., 3:4]
        x = (ndc[..., 0] + 1) * 0.5 * self.width
        y = (1 - ndc[..., 1]) * 0.5 * self.height
        return np.stack([x, y], axis=-1), ndc[..., 2]

    def eye_depth(self, z_ndc: np.ndarray) -> np.ndarray:
        """Distance along the view axis from NDC z (the inverse of the projection's z)."""
        n, f = self.camera.near, self.camera.far
        if self.camera.ortho:
            return (z_ndc * (f - n) + (f + n)) / 2
        return 2 * f * n / ((f + n) - z_ndc * (f - n))

    def hidden(self, xy: np.ndarray, eye: np.ndarray) -> np.ndarray:
        """(N,) bool: the front surface lies nearer than these (N, 2) screen samples at (N,) eye
        depths by more than ``DEPTH_TOLERANCE``; the surface is the farthest of the 3x3 pixels
        around the sample's pixel (window depth grows with eye depth, so the farthest window
        depth is the farthest surface). Samples off the image are never hidden."""
        if self.depth is None:
            return np.zeros(len(xy), bool)
        ix = np.floor(xy[:, 0]).astype(np.int64)
        iy = np.floor(xy[:, 1]).astype(np.int64)
        inside = (ix >= 0) & (ix < self.width) & (iy >= 0) & (iy < self.height)
        ix, iy = ix[inside], iy[inside]
        far = np.zeros(len(ix), np.float64)
        for dy in (-1, 0, 1):
            rows = np.clip(iy + dy, 0, self.height - 1)
            for dx in (-1, 0, 1):
                np.maximum(far, self.depth[rows, np.clip(ix + dx, 0, self.width - 1)], out=far)
        surface = np.full(len(xy), np.inf)
        covered = far < 1.0
        surface[np.flatnonzero(inside)[covered]] = self.eye_depth(2.0 * far[covered] - 1.0)
        return surface < eye * (1 - DEPTH_TOLERANCE)


# -- glyph geometry --------------------------------------------------------------------------
@dataclass
class _Stroke:
    """One line glyph as 3D segments: (S, 2, 3) endpoints and the polyline each belongs to."""

    segments: np.ndarray
    polyline: np.ndarray
    color: RGBA
    width: float
    dash: tuple[float, ...] | None


def _polylines_to_stroke(polylines: list[np.ndarray], closed: bool, color, width, dash) -> _Stroke:
    segments, owner = [], []
    for k, pts in enumerate(polylines):
        if closed and len(pts) > 2:
            pts = np.vstack([pts, pts[:1]])
        segments.append(np.stack([pts[:-1], pts[1:]], axis=1))
        owner.append(np.full(len(pts) - 1, k))
    return _Stroke(np.concatenate(segments), np.concatenate(owner), color, width, dash)


_BOX_EDGES = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]


def _box_corners(box: Box) -> np.ndarray:
    lo, hi = np.asarray(box.min), np.asarray(box.max)
    corner = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    return lo + corner * (hi - lo)


def _box_stroke(box: Box) -> _Stroke:
    c = _box_corners(box)
    return _polylines_to_stroke([c[[a, b]] for a, b in _BOX_EDGES], False, box.color, box.width, box.dash)


def _arrow_stroke(arrow: Arrow, camera: Camera) -> _Stroke:
    start, end = np.asarray(arrow.start), np.asarray(arrow.end)
    axis = end - start
    length = float(np.linalg.norm(axis))
    direction = axis / length
    lines = [np.stack([start, end])]
    if arrow.head > 0:
        view = camera.view_matrix()
        if camera.ortho:
            sight = -view[2, :3]
        else:
            sight = end - np.asarray(camera.eye)
        across = np.cross(direction, sight)
        if np.linalg.norm(across) < 1e-9 * max(np.linalg.norm(sight), 1e-300):
            across = view[1, :3]  # pointing along the line of sight: spread along screen up
        across = across / np.linalg.norm(across)
        head = arrow.head * length
        base = end - direction * head
        for side in (1.0, -1.0):
            lines.append(np.stack([base + side * HEAD_SPREAD * head * across, end]))
    return _polylines_to_stroke(lines, False, arrow.color, arrow.width, arrow.dash)


def _path_stroke(path: Path3D) -> _Stroke:
    pts = np.asarray(path.points, float)
    return _polylines_to_stroke([pts], path.closed, path.color, path.width, path.dash)


# -- drawing ---------------------------------------------------------------------------------
def _dash_on(arc: np.ndarray, pattern: tuple[float, ...], scale: float) -> np.ndarray:
    bounds = np.cumsum(np.asarray(pattern) * scale)
    phase = np.mod(arc, bounds[-1])
    return np.searchsorted(bounds, phase, side="right") % 2 == 0


def _near_clip(clip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cut (S, 2, 4) clip-space segments at the near plane (z >= -w); returns the kept
    segments and the mask of those kept."""
    e = clip[..., 2] + clip[..., 3]
    keep = (e[:, 0] > 0) | (e[:, 1] > 0)
    clip, e = clip[keep].copy(), e[keep]
    for end in (0, 1):
        cut = e[:, end] <= 0
        if cut.any():
            a, b = e[cut, end], e[cut, 1 - end]
            # a hair inside the plane, so w stays positive
            t = (a / (a - b))[:, None] * (1 + 1e-9)
            clip[cut, end] = clip[cut, end] + np.minimum(t, 1.0) * (clip[cut, 1 - end] - clip[cut, end])
    return clip, keep


def _screen_range(p0: np.ndarray, p1: np.ndarray, lo: float, hi_x: float, hi_y: float):
    """Liang-Barsky: the (S,) parameter range [t0, t1] of each screen segment inside the box."""
    t0 = np.zeros(len(p0))
    t1 = np.ones(len(p0))
    d = p1 - p0
    for axis, hi in ((0, hi_x), (1, hi_y)):
        flat = d[:, axis] == 0
        inside = (p0[:, axis] >= lo) & (p0[:, axis] <= hi)
        safe = np.where(flat, 1.0, d[:, axis])
        a, b = (lo - p0[:, axis]) / safe, (hi - p0[:, axis]) / safe
        t0 = np.where(flat, np.where(inside, t0, 2.0), np.maximum(t0, np.minimum(a, b)))
        t1 = np.where(flat, np.where(inside, t1, -1.0), np.minimum(t1, np.maximum(a, b)))
    return t0, t1


def _stroke_pieces(stroke: _Stroke, view: _View, hidden: Hidden, scale: float):
    """The screen pieces of a stroke: (K, 2, 2) pixel segments and (K,) opacities."""
    clip, keep = _near_clip(view.clip(stroke.segments))
    empty = np.zeros((0, 2, 2)), np.zeros(0)
    if not len(clip):
        return empty
    xy, z = view.screen(clip)
    owner = stroke.polyline[keep]
    full = np.linalg.norm(xy[:, 1] - xy[:, 0], axis=1)
    # arc length along each polyline on screen, so dashes run on across its corners
    start = np.zeros(len(full))
    for k in np.unique(owner):
        idx = np.flatnonzero(owner == k)
        start[idx] = np.cumsum(full[idx]) - full[idx]
    margin = stroke.width * scale + 2.0
    t0, t1 = _screen_range(xy[:, 0], xy[:, 1], -margin, view.width + margin, view.height + margin)
    live = t1 > t0
    if not live.any():
        return empty
    xy, z, full, start, t0, t1 = xy[live], z[live], full[live], start[live], t0[live], t1[live]

    counts = np.maximum(np.ceil(full * (t1 - t0) / SAMPLE_STEP), 1).astype(np.int64)
    seg = np.repeat(np.arange(len(counts)), counts)
    k = np.arange(len(seg)) - np.repeat(np.cumsum(counts) - counts, counts)
    span = (t1 - t0)[seg] / counts[seg]
    lo = t0[seg] + k * span
    hi = lo + span
    mid = (lo + hi) / 2
    # NDC z is affine along a projected line, so it interpolates linearly on screen
    p = xy[seg, 0] + mid[:, None] * (xy[seg, 1] - xy[seg, 0])
    eye = view.eye_depth(z[seg, 0] + mid * (z[seg, 1] - z[seg, 0]))
    behind = view.hidden(p, eye)
    arc = start[seg] + mid * full[seg]

    on = np.ones(len(seg), bool) if stroke.dash is None else _dash_on(arc, stroke.dash, scale)
    opacity = np.ones(len(seg))
    if hidden.mode == "none":
        on &= ~behind
    elif hidden.mode == "dim":
        opacity[behind] = hidden.opacity
    else:
        on[behind] = _dash_on(arc[behind], hidden.dash, scale)
    opacity[~on] = 0.0

    # merge runs of samples of one segment that are drawn alike
    key = np.column_stack([seg, opacity])
    first = np.r_[True, (key[1:] != key[:-1]).any(axis=1)]
    run_start = np.flatnonzero(first)
    run_end = np.r_[run_start[1:], len(seg)] - 1
    t_a, t_b = lo[run_start], hi[run_end]
    # Where a gap follows or precedes a run on its segment (a dash's end, or a cut where the
    # glyph goes out of sight in mode none), pull the run's end in by the round cap's radius so
    # the ink, not the centre line, stops there: gaps stay as long as the pattern says.
    s = seg[run_start]
    gap_before = np.r_[False, (opacity[run_start[:-1]] == 0) & (s[:-1] == s[1:])]
    gap_after = np.r_[(opacity[run_start[1:]] == 0) & (s[1:] == s[:-1]), False]
    cap = stroke.width * scale / 2 / np.maximum(full[s], 1e-12)
    t_a = t_a + np.where(gap_before, cap, 0.0)
    t_b = t_b - np.where(gap_after, cap, 0.0)
    short = t_a > t_b
    t_a[short] = t_b[short] = (t_a[short] + t_b[short]) / 2
    drawn = opacity[run_start] > 0
    s, t_a, t_b = s[drawn], t_a[drawn], t_b[drawn]
    a = xy[s, 0] + t_a[:, None] * (xy[s, 1] - xy[s, 0])
    b = xy[s, 0] + t_b[:, None] * (xy[s, 1] - xy[s, 0])
    return np.stack([a, b], axis=1), opacity[run_start[drawn]]


def _composite(canvas: np.ndarray, x0: int, y0: int, coverage: np.ndarray, color: RGBA) -> None:
    """Straight-alpha ``over`` of ``color`` at ``coverage`` (h, w) onto the uint8 RGBA
    ``canvas`` at (x0, y0), in place; pixels without coverage keep their exact values."""
    h, w = coverage.shape
    region = canvas[y0 : y0 + h, x0 : x0 + w]
    alpha = coverage.astype(np.float64) * color[3]
    touched = alpha > 0
    if not touched.any():
        return
    a_s = alpha[touched][:, None]
    dst = region[touched].astype(np.float64)
    a_d = dst[:, 3:4] / 255.0
    a_o = a_s + a_d * (1 - a_s)
    rgb = (np.asarray(color[:3]) * 255.0 * a_s + dst[:, :3] * a_d * (1 - a_s)) / a_o
    out = np.concatenate([rgb, a_o * 255.0], axis=1)
    region[touched] = np.clip(np.rint(out), 0, 255).astype(np.uint8)


def _draw_pieces(canvas: np.ndarray, pieces, opacity, color: RGBA, width: float) -> None:
    if not len(pieces):
        return
    h, w = canvas.shape[:2]
    reach = width / 2 + 1.0
    lo = np.floor(pieces.reshape(-1, 2).min(axis=0) - reach).astype(int)
    hi = np.ceil(pieces.reshape(-1, 2).max(axis=0) + reach).astype(int)
    x0, y0 = max(lo[0], 0), max(lo[1], 0)
    x1, y1 = min(hi[0], w), min(hi[1], h)
    if x1 <= x0 or y1 <= y0:
        return
    coverage = draw_segments(pieces - [x0, y0], x1 - x0, y1 - y0, width, opacity)
    _composite(canvas, x0, y0, coverage, color)


@lru_cache(maxsize=32)
def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: one bitmap size
        return ImageFont.load_default()


_ANCHOR_SIDES = {  # anchor -> (horizontal, vertical) position of the point on the text box
    "left": (0, 0.5),
    "right": (1, 0.5),
    "center": (0.5, 0.5),
    "top": (0.5, 0),
    "bottom": (0.5, 1),
    "top-left": (0, 0),
    "top-right": (1, 0),
    "bottom-left": (0, 1),
    "bottom-right": (1, 1),
}


def _draw_text(canvas: np.ndarray, xy, text: str, color: RGBA, size: float, anchor: str, opacity: float):
    from PIL import Image, ImageDraw

    font = _font(max(1, round(size)))
    probe = ImageDraw.Draw(Image.new("L", (1, 1)))
    left, top, right, bottom = probe.multiline_textbbox((0, 0), text, font=font, anchor="la")
    fx, fy = _ANCHOR_SIDES[anchor]
    gap = LABEL_GAP * size
    # the point sits at (fx, fy) of the text box, pushed out by the gap on the sides it touches
    x = xy[0] + gap * (0.5 - fx) * 2 * (fx != 0.5) - (left + fx * (right - left))
    y = xy[1] + gap * (0.5 - fy) * 2 * (fy != 0.5) - (top + fy * (bottom - top))
    x0, y0 = math.floor(x + left), math.floor(y + top)
    x1, y1 = math.ceil(x + right) + 1, math.ceil(y + bottom) + 1
    h, w = canvas.shape[:2]
    cx0, cy0, cx1, cy1 = max(x0, 0), max(y0, 0), min(x1, w), min(y1, h)
    if cx1 <= cx0 or cy1 <= cy0:
        return
    mask = Image.new("L", (cx1 - cx0, cy1 - cy0), 0)
    ImageDraw.Draw(mask).multiline_text(
        (round(x) - cx0, round(y) - cy0), text, fill=255, font=font, anchor="la"
    )
    coverage = np.asarray(mask, np.float64) / 255.0 * opacity
    _composite(canvas, cx0, cy0, coverage, color)


def _labels(glyphs: Glyphs, view: _View) -> list[tuple[np.ndarray, str, RGBA, float, str]]:
    """Every text to draw, including box, arrow and path labels: (point, text, colour, size, anchor)."""
    out = []
    for label in glyphs.labels:
        out.append((np.asarray(label.at, float), label.text, label.color, label.size, label.anchor))
    for box in glyphs.boxes:
        if box.label:
            corners = _box_corners(box)
            clip = view.clip(corners)
            front = clip[:, 2] + clip[:, 3] > 0
            if front.any():
                xy, _ = view.screen(clip[front])
                top = np.lexsort((xy[:, 0], xy[:, 1]))[0]
                out.append((corners[front][top], box.label, box.color, 14.0, "bottom-left"))
    for arrow in glyphs.arrows:
        if arrow.label:
            clip = view.clip(np.array([arrow.start, arrow.end]))
            anchor = "right"
            if (clip[:, 2] + clip[:, 3] > 0).all():
                xy, _ = view.screen(clip)
                dx, dy = xy[1] - xy[0]
                if abs(dy) > 2 * abs(dx):
                    anchor = "bottom" if dy > 0 else "top"
                else:
                    anchor = "right" if dx >= 0 else "left"
            out.append((np.asarray(arrow.start, float), arrow.label, arrow.color, 14.0, anchor))
    for path in glyphs.paths:
        if path.label:
            out.append((np.asarray(path.points[0], float), path.label, path.color, 14.0, "bottom-left"))
    return out


def draw_glyphs(
    image: np.ndarray,
    glyphs: Glyphs,
    camera: Camera,
    depth: np.ndarray | None,
    *,
    line_scale: float = 1.0,
) -> np.ndarray:
    """Draw glyphs over a blueprint, hidden where the blueprint's front surface covers them.

    Every glyph segment is projected with ``camera`` (cut at the near plane) and sampled every
    ``SAMPLE_STEP`` pixels; a sample is hidden when the front surface at its pixel is nearer
    than it by more than ``DEPTH_TOLERANCE`` of its eye depth (see there), and hidden pieces
    are drawn as ``glyphs.hidden`` says. Labels are tested at their anchor point.

    Parameters
    ----------
    image : (H, W, 4) uint8
        RGBA, straight alpha, row 0 at the top (``Frame.image``); (H, W, 3) is taken as opaque.
    glyphs : Glyphs
    camera : Camera
        The camera the image was drawn with (its aspect should be W / H).
    depth : (H, W) float or None
        Window depth in [0, 1] of the front surface (``Layers.depth[0]`` at the image size),
        1.0 where there is none, row 0 at the top. An (L, H, W) stack uses its layer 0.
        ``None``: nothing hides the glyphs.
    line_scale : float
        Multiplies line widths, dash lengths and text sizes (e.g. for larger prints).

    Returns
    -------
    np.ndarray
        A new image of the same shape and dtype uint8.
    """
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] not in (3, 4) or image.dtype != np.uint8:
        raise ValueError(f"image must be (H, W, 4) uint8, got {image.shape} {image.dtype}")
    if not (math.isfinite(line_scale) and line_scale > 0):
        raise ValueError(f"line_scale must be a positive number, got {line_scale}")
    h, w = image.shape[:2]
    if depth is not None:
        depth = np.asarray(depth)
        if depth.ndim == 3:
            depth = depth[0] if len(depth) else None
    if depth is not None and depth.shape != (h, w):
        raise ValueError(f"depth must be ({h}, {w}) like the image, got {depth.shape}")
    view = _View(camera, w, h, depth)
    if image.shape[2] == 4:
        canvas = image.copy()
    else:
        canvas = np.dstack([image, np.full((h, w), 255, np.uint8)])
    hidden = glyphs.hidden

    strokes = [_path_stroke(p) for p in glyphs.paths]
    strokes += [_box_stroke(b) for b in glyphs.boxes]
    strokes += [_arrow_stroke(a, camera) for a in glyphs.arrows]
    for stroke in strokes:
        pieces, opacity = _stroke_pieces(stroke, view, hidden, line_scale)
        _draw_pieces(canvas, pieces, opacity, stroke.color, stroke.width * line_scale)

    for point, text, color, size, anchor in _labels(glyphs, view):
        clip = view.clip(point)
        if clip[2] + clip[3] <= 0:
            continue
        xy, z = view.screen(clip)
        opacity = 1.0
        if view.hidden(xy[None], view.eye_depth(np.atleast_1d(z)))[0]:
            if hidden.mode == "none":
                continue
            opacity = hidden.opacity
        _draw_text(canvas, xy, text, color, size * line_scale, anchor, opacity)

    return canvas if image.shape[2] == 4 else canvas[..., :3].copy()


def render_with_glyphs(
    renderer,
    model,
    camera: Camera,
    size: tuple[int, int],
    glyphs: Glyphs | str | os.PathLike,
    frame_image: np.ndarray,
    *,
    line_scale: float = 1.0,
) -> np.ndarray:
    """Peel the front depth layer of ``model`` at ``camera`` and ``size`` and draw ``glyphs``
    (a ``Glyphs`` or a glyph file) over ``frame_image`` (the blueprint drawn with the same
    camera and size). Returns a new (H, W, 4) uint8 image."""
    if not isinstance(glyphs, Glyphs):
        glyphs = load_glyphs(glyphs)
    w, h = (int(v) for v in size)
    if frame_image.shape[:2] != (h, w):
        raise ValueError(f"frame_image is {frame_image.shape[1]}x{frame_image.shape[0]}, size is {w}x{h}")
    layers = renderer.peel(model, camera, size=(w, h), max_layers=1)
    depth = layers.depth[0] if len(layers.depth) else None
    return draw_glyphs(frame_image, glyphs, camera, depth, line_scale=line_scale)
