"""Line glyphs (paths, boxes, arrows) as 3D segments, and the screen pieces they are drawn as:
projected, sampled along the screen, tested against the front surface, dashed, and merged into
runs that are drawn alike."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.color import RGBA
from blueprint.compose.glyphs.projection import View, near_clip, screen_range
from blueprint.compose.glyphs.values import Arrow, Box, Hidden, Path3D
from blueprint.scene.camera import Camera

__all__ = [
    "HEAD_SPREAD",
    "SAMPLE_STEP",
    "Stroke",
    "StrokeSamples",
    "arrow_stroke",
    "box_corners",
    "box_stroke",
    "path_stroke",
    "stroke_pieces",
    "stroke_samples",
]

# Glyph segments are sampled this often (pixels along the screen) for the depth test.
SAMPLE_STEP = 0.5
# arrow head half-width, as a fraction of the head length
HEAD_SPREAD = 0.45

_BOX_EDGES = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]


@dataclass
class Stroke:
    """One line glyph as 3D segments: (S, 2, 3) endpoints and the polyline each belongs to."""

    segments: np.ndarray
    polyline: np.ndarray
    color: RGBA
    width: float
    dash: tuple[float, ...] | None


def _polylines_to_stroke(
    polylines: list[np.ndarray], closed: bool, color: RGBA, width: float, dash: tuple[float, ...] | None
) -> Stroke:
    segments, owner = [], []
    for k, pts in enumerate(polylines):
        if closed and len(pts) > 2:
            pts = np.vstack([pts, pts[:1]])
        segments.append(np.stack([pts[:-1], pts[1:]], axis=1))
        owner.append(np.full(len(pts) - 1, k))
    return Stroke(np.concatenate(segments), np.concatenate(owner), color, width, dash)


def box_corners(box: Box) -> np.ndarray:
    """(8, 3) corners of a box, corner ``4x + 2y + z`` at the max on the axes whose bit is set."""
    lo, hi = np.asarray(box.min), np.asarray(box.max)
    corner = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    return lo + corner * (hi - lo)


def box_stroke(box: Box) -> Stroke:
    c = box_corners(box)
    return _polylines_to_stroke([c[[a, b]] for a, b in _BOX_EDGES], False, box.color, box.width, box.dash)


def arrow_stroke(arrow: Arrow, camera: Camera) -> Stroke:
    """The shaft and, facing ``camera``, the two strokes of the head."""
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


def path_stroke(path: Path3D) -> Stroke:
    pts = np.asarray(path.points, float)
    return _polylines_to_stroke([pts], path.closed, path.color, path.width, path.dash)


def _dash_on(arc: np.ndarray, pattern: tuple[float, ...], scale: float) -> np.ndarray:
    bounds = np.cumsum(np.asarray(pattern) * scale)
    phase = np.mod(arc, bounds[-1])
    return np.searchsorted(bounds, phase, side="right") % 2 == 0


@dataclass
class StrokeSamples:
    """A stroke on screen, sampled for the depth test: segment ``s`` runs from ``xy[s, 0]`` to
    ``xy[s, 1]`` (pixels, ``full[s]`` long); sample ``i`` covers its parameters ``lo[i]`` to
    ``hi[i]`` on segment ``seg[i]``, lies ``arc[i]`` pixels along its polyline and is
    ``behind`` the front surface or not."""

    xy: np.ndarray
    full: np.ndarray
    seg: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    arc: np.ndarray
    behind: np.ndarray
    polyline: np.ndarray


def stroke_samples(stroke: Stroke, view: View, scale: float) -> StrokeSamples | None:
    """The stroke projected, cut at the near plane and the image (with a margin of the line's
    width), sampled every ``SAMPLE_STEP`` pixels and depth-tested; None where none of it shows."""
    clip, keep = near_clip(view.clip(stroke.segments))
    if not len(clip):
        return None
    xy, z = view.screen(clip)
    owner = stroke.polyline[keep]
    full = np.linalg.norm(xy[:, 1] - xy[:, 0], axis=1)
    # arc length along each polyline on screen, so dashes run on across its corners
    start = np.zeros(len(full))
    for k in np.unique(owner):
        idx = np.flatnonzero(owner == k)
        start[idx] = np.cumsum(full[idx]) - full[idx]
    margin = stroke.width * scale + 2.0
    t0, t1 = screen_range(xy[:, 0], xy[:, 1], -margin, view.width + margin, view.height + margin)
    live = t1 > t0
    if not live.any():
        return None
    xy, z, full, start, t0, t1 = xy[live], z[live], full[live], start[live], t0[live], t1[live]
    owner = owner[live]

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
    return StrokeSamples(xy, full, seg, lo, hi, arc, behind, owner)


def stroke_pieces(stroke: Stroke, view: View, hidden: Hidden, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The screen pieces of a stroke: (K, 2, 2) pixel segments and (K,) opacities."""
    sampled = stroke_samples(stroke, view, scale)
    if sampled is None:
        return np.zeros((0, 2, 2)), np.zeros(0)
    xy, full, seg, lo, hi = sampled.xy, sampled.full, sampled.seg, sampled.lo, sampled.hi
    arc, behind = sampled.arc, sampled.behind

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
