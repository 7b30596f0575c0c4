"""Points along the lines to draw, about a pixel apart on screen: where occlusion is decided."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from blueprint.columns import row_norm
from blueprint.scene.camera import clip_to_pixels, transform

from ..lines import Polylines

__all__ = ["Samples", "sample_polylines"]


@dataclass(frozen=True)
class Samples:
    """Points along polylines.

    eye : (S, 3) float64, eye coordinates
    pixel : (S, 2) float64, pixel coordinates (x right, y down, origin top-left)
    faces : (S, 2) int64, faces of the segment each sample lies on
    kind : (S,) uint8, kind of the segment each sample lies on (``lines.SILHOUETTE``, ...)
    edge : (S,) int64, the model's edge each sample lies on (-1: none, an intersection)
    line : (S,) int64, polyline of each sample
    vertex : (S,) bool, True where the sample is a vertex of its polyline
    inside : (S,) bool, True where the sample lies inside the view volume
    """

    eye: np.ndarray
    pixel: np.ndarray
    faces: np.ndarray
    kind: np.ndarray
    edge: np.ndarray
    line: np.ndarray
    vertex: np.ndarray
    inside: np.ndarray

    @functools.cached_property
    def across(self) -> tuple[np.ndarray, np.ndarray]:
        """(S,) bool: whether each sample's line has a screen direction there (from the
        neighbouring samples on the same line), and (S, 2) float64 the unit vector across it
        (0 where none); found once for the several tests that look to either side."""
        line, pixel = self.line, self.pixel
        # from the sample before to the sample after, then at the ends of the lines (few) from
        # or to the sample itself where the line has none there
        tangent = np.empty_like(pixel)
        np.subtract(pixel[2:], pixel[:-2], out=tangent[1:-1])
        same = line[1:] == line[:-1]
        last = np.flatnonzero(~same)
        ends = np.unique(np.r_[0, last, last + 1, len(line) - 1])
        ends = ends[(ends >= 0) & (ends < len(line))]
        ahead = np.where(np.r_[same, False][ends], ends + 1, ends)
        behind = np.where(np.r_[False, same][ends], ends - 1, ends)
        tangent[ends] = pixel[ahead] - pixel[behind]
        length = row_norm(tangent)
        good = length > 0
        unit = np.divide(tangent, length[:, None], out=tangent, where=good[:, None])
        unit[~good] = 0.0
        across = np.empty_like(pixel)
        np.negative(unit[:, 1], out=across[:, 0])
        across[:, 1] = unit[:, 0]
        return good, across


def sample_polylines(
    lines: Polylines,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    spacing: float = 1.0,
) -> Samples:
    """Samples about ``spacing`` pixels apart along every segment, its vertices included.

    Points are interpolated in model space, so on screen they fall on the projected segment
    (a straight line in perspective as well), a little unevenly spaced.
    """
    points, offsets = lines.points, lines.offsets
    if len(points) == 0:
        z = np.zeros((0, 2))
        none = np.zeros(0, bool)
        return Samples(
            np.zeros((0, 3)),
            z,
            np.zeros((0, 2), np.int64),
            np.zeros(0, np.uint8),
            np.zeros(0, np.int64),
            np.zeros(0, np.int64),
            none,
            none,
        )
    clip = transform(points, projection @ view)
    pix = clip_to_pixels(clip, size)
    line_of_point = np.repeat(np.arange(len(lines)), np.diff(offsets))
    is_last = np.zeros(len(points), bool)
    is_last[offsets[1:] - 1] = True
    starts = np.flatnonzero(~is_last)  # segment j runs from point j to point j + 1
    # in front of the eye at both ends: the screen length is meaningful
    w = clip[:, 3]
    length = row_norm(pix[starts + 1] - pix[starts])
    length = np.where((w[starts] > 0) & (w[starts + 1] > 0) & np.isfinite(length), length, 0.0)
    count = np.maximum(np.ceil(length / spacing), 1).astype(np.int64)
    count = np.minimum(count, 1 << 16)
    # the samples in their final order, point after point: a segment's samples from its first
    # point, a polyline's last point as one sample of its own after them
    per_point = np.ones(len(points), np.int64)
    per_point[starts] = count
    # every point's values repeated for its samples, not gathered sample by sample
    total = np.cumsum(per_point)
    k = np.arange(total[-1]) - np.repeat(total - per_point, per_point)
    t = k / np.repeat(per_point, per_point)
    # the step to the next point (none after the very last)
    step = np.empty_like(points)
    np.subtract(points[1:], points[:-1], out=step[:-1])
    np.subtract(points[-1:], points[-1:], out=step[-1:])
    model = np.repeat(points, per_point, axis=0)
    model += t[:, None] * np.repeat(step, per_point, axis=0)
    last = offsets[1:] - 1
    model[total[last] - 1] = points[last]
    # a last point has the attributes of the segment before it
    source = np.arange(len(points))
    source[last] -= 1
    faces = np.repeat(lines.faces[source], per_point, axis=0)
    kind = np.repeat(lines.kind[source], per_point)
    edge = np.repeat(lines.edge[source], per_point)
    vertex = k == 0
    line = np.repeat(line_of_point, per_point)
    eye = transform(model, view)
    clip = eye @ projection.T
    inside = (
        (clip[:, 3] > 0)
        & (clip[:, 2] >= -clip[:, 3])
        & (clip[:, 2] <= clip[:, 3])
        & (np.abs(clip[:, 0]) <= clip[:, 3])
        & (np.abs(clip[:, 1]) <= clip[:, 3])
    )
    return Samples(eye[:, :3], clip_to_pixels(clip, size), faces, kind, edge, line, vertex, inside)
