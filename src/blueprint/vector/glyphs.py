"""Glyphs (boxes, arrows, paths, labels) as vector lines and texts: the raster glyphs' geometry
and depth test (``blueprint.compose.glyphs``), kept as polylines instead of pixels. A stretch
of a glyph behind the model's front surface is its own polyline, drawn as the glyph file's
``[hidden]`` says: dashed (the dash pattern as a line style, not cut into pieces), dimmed, or
left out."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.color import RGBA
from blueprint.compose.glyphs.draw import glyph_labels
from blueprint.compose.glyphs.parse import Glyphs
from blueprint.compose.glyphs.projection import View
from blueprint.compose.glyphs.strokes import arrow_stroke, box_stroke, path_stroke, stroke_samples
from blueprint.compose.glyphs.values import Hidden
from blueprint.scene.camera import Camera

__all__ = ["GlyphLines", "GlyphText", "glyph_lines"]


@dataclass(frozen=True)
class GlyphText:
    """A label at pixel ``(x, y)``; ``hidden`` where the model's front surface covers it."""

    x: float
    y: float
    text: str
    color: RGBA
    size: float
    anchor: str
    hidden: bool


@dataclass(frozen=True)
class GlyphLines:
    """Glyph polylines in pixels: polyline ``i`` is ``points[offsets[i]:offsets[i + 1]]``, of
    glyph ``glyph[i]`` (its colour, width and own dash in ``color``, ``width``, ``dash``), and
    ``hidden[i]`` where it runs behind the front surface (drawn as ``mode`` says)."""

    points: np.ndarray
    offsets: np.ndarray
    glyph: np.ndarray
    hidden: np.ndarray
    color: tuple[RGBA, ...]
    width: tuple[float, ...]
    dash: tuple[tuple[float, ...] | None, ...]
    texts: tuple[GlyphText, ...]
    mode: Hidden

    def __len__(self) -> int:
        return len(self.offsets) - 1

    def style(self, i: int) -> tuple[RGBA, float, tuple[float, ...] | None, float]:
        """(colour, width in pixels, dash pattern in pixels or None, opacity) of polyline ``i``."""
        k = int(self.glyph[i])
        if self.hidden[i] and self.mode.mode == "dashed":
            return self.color[k], self.width[k], tuple(self.mode.dash), 1.0
        if self.hidden[i] and self.mode.mode == "dim":
            return self.color[k], self.width[k], self.dash[k], self.mode.opacity
        return self.color[k], self.width[k], self.dash[k], 1.0


def glyph_lines(
    glyphs: Glyphs, camera: Camera, size: tuple[int, int], depth: np.ndarray | None
) -> GlyphLines:
    """The glyphs as polylines for ``camera`` at ``size`` (W, H), split where they pass behind
    the front surface given by ``depth`` ((H, W) window depth, 1.0 where none, row 0 at the
    top; None hides nothing). Stretches behind are left out where the glyphs' hidden mode is
    "none"."""
    w, h = (int(v) for v in size)
    view = View(camera, w, h, depth)
    strokes = [path_stroke(p) for p in glyphs.paths]
    strokes += [box_stroke(b) for b in glyphs.boxes]
    strokes += [arrow_stroke(a, camera) for a in glyphs.arrows]
    points, counts, owner, behind_of = [], [], [], []
    for k, stroke in enumerate(strokes):
        sampled = stroke_samples(stroke, view, 1.0)
        if sampled is None:
            continue
        seg, behind = sampled.seg, sampled.behind
        # runs of samples of one segment on one side of the front surface
        first = np.r_[True, (seg[1:] != seg[:-1]) | (behind[1:] != behind[:-1])]
        start = np.flatnonzero(first)
        end = np.r_[start[1:], len(seg)] - 1
        s = seg[start]
        a = sampled.xy[s, 0] + sampled.lo[start, None] * (sampled.xy[s, 1] - sampled.xy[s, 0])
        b = sampled.xy[s, 0] + sampled.hi[end, None] * (sampled.xy[s, 1] - sampled.xy[s, 0])
        run_behind = behind[start]
        # a run continues the previous one's polyline where it starts where that one ended
        joined = np.r_[
            False,
            (run_behind[1:] == run_behind[:-1])
            & (sampled.polyline[s[1:]] == sampled.polyline[s[:-1]])
            & np.all(np.abs(a[1:] - b[:-1]) < 1e-6, axis=1),
        ]
        line = np.cumsum(~joined) - 1
        for i in range(int(line[-1]) + 1):
            rows = np.flatnonzero(line == i)
            if glyphs.hidden.mode == "none" and run_behind[rows[0]]:
                continue
            points.append(np.vstack([a[rows[:1]], b[rows]]))
            counts.append(len(rows) + 1)
            owner.append(k)
            behind_of.append(bool(run_behind[rows[0]]))
    texts = []
    for point, text, color, text_size, anchor in glyph_labels(glyphs, view):
        clip = view.clip(point)
        if clip[2] + clip[3] <= 0:
            continue
        xy, z = view.screen(clip)
        hidden = bool(view.hidden(xy[None], view.eye_depth(np.atleast_1d(z)))[0])
        if hidden and glyphs.hidden.mode == "none":
            continue
        texts.append(GlyphText(float(xy[0]), float(xy[1]), text, color, float(text_size), anchor, hidden))
    return GlyphLines(
        np.concatenate(points) if points else np.zeros((0, 2)),
        np.r_[0, np.cumsum(counts)].astype(np.int64),
        np.array(owner, np.int32),
        np.array(behind_of, bool),
        tuple(s.color for s in strokes),
        tuple(float(s.width) for s in strokes),
        tuple(s.dash for s in strokes),
        tuple(texts),
        glyphs.hidden,
    )
