"""Points along the lines to draw, about a pixel apart on screen: where occlusion is decided."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from blueprint import parallel
from blueprint.columns import row_norm
from blueprint.scene.camera import clip_to_pixels, transform

from ..lines import Polylines

__all__ = ["Samples", "sample_polylines"]

# Points of the polylines sampled at once by one thread: their samples' temporaries, not every
# sample's, lie in memory together.
_POINTS = 1 << 14


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
        good = np.empty(len(self.line), bool)
        across = np.empty_like(self.pixel)
        parallel.run(functools.partial(_across, self.line, self.pixel, good, across), len(self.line))
        return good, across

    def forget_across(self) -> None:
        """Free ``across`` (found again if asked for), once the tests that look to either side
        of the lines are done."""
        self.__dict__.pop("across", None)


def _across(
    line: np.ndarray, pixel: np.ndarray, good: np.ndarray, across: np.ndarray, lo: int, hi: int
) -> None:
    """``Samples.across`` of the samples lo to hi, into ``good`` and ``across``: each one's
    tangent from the sample before to the sample after, or from or to the sample itself
    where its line has none there (at the lines' ends)."""
    if hi == lo:
        return
    n = len(line)
    tangent = np.empty((hi - lo, 2))
    inner_lo, inner_hi = max(lo, 1), min(hi, n - 1)
    if inner_hi > inner_lo:
        np.subtract(
            pixel[inner_lo + 1 : inner_hi + 1],
            pixel[inner_lo - 1 : inner_hi - 1],
            out=tangent[inner_lo - lo : inner_hi - lo],
        )
    # the lines' ends (few), and the array's
    before = np.r_[False, line[lo + 1 : hi] == line[lo : hi - 1]]
    if lo > 0:
        before[0] = line[lo - 1] == line[lo]
    after = np.r_[line[lo + 1 : hi] == line[lo : hi - 1], False]
    if hi < n:
        after[-1] = line[hi] == line[hi - 1]
    ends = np.flatnonzero(~(before & after))
    at = ends + lo
    tangent[ends] = pixel[np.where(after[ends], at + 1, at)] - pixel[np.where(before[ends], at - 1, at)]
    length = row_norm(tangent)
    good[lo:hi] = length > 0
    unit = np.divide(tangent, length[:, None], out=tangent, where=good[lo:hi, None])
    unit[~good[lo:hi]] = 0.0
    np.negative(unit[:, 1], out=across[lo:hi, 0])
    across[lo:hi, 1] = unit[:, 0]


def sample_polylines(
    lines: Polylines,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    spacing: float = 1.0,
    weigh: Callable[[int], None] | None = None,
) -> Samples:
    """Samples about ``spacing`` pixels apart along every segment, its vertices included.

    Points are interpolated in model space, so on screen they fall on the projected segment
    (a straight line in perspective as well), a little unevenly spaced. ``weigh`` is called
    with the count of samples before any is made (to refuse a drawing their memory would not
    fit, by raising).
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
    is_last = np.zeros(len(points), bool)
    is_last[offsets[1:] - 1] = True
    starts = np.flatnonzero(~is_last)  # segment j runs from point j to point j + 1
    # in front of the eye at both ends: the screen length is meaningful
    w = clip[:, 3]
    length = row_norm(pix[starts + 1] - pix[starts])
    length = np.where((w[starts] > 0) & (w[starts + 1] > 0) & np.isfinite(length), length, 0.0)
    del clip, pix, w  # the points' own, before the samples' arrays are made
    count = np.maximum(np.ceil(length / spacing), 1).astype(np.int64)
    count = np.minimum(count, 1 << 16)
    # the samples in their final order, point after point: a segment's samples from its first
    # point, a polyline's last point as one sample of its own after them
    per_point = np.ones(len(points), np.int64)
    per_point[starts] = count
    total = np.cumsum(per_point)
    n = int(total[-1])
    if weigh is not None:
        weigh(n)
    out = Samples(
        np.empty((n, 3)),
        np.empty((n, 2)),
        np.empty((n, 2), np.int64),
        np.empty(n, np.uint8),
        np.empty(n, np.int64),
        np.empty(n, np.int64),
        np.empty(n, bool),
        np.empty(n, bool),
    )
    sampled = functools.partial(_sampled, lines, is_last, per_point, total, view, projection, size, out)
    parallel.run(sampled, len(points))
    return out


def _sampled(
    lines: Polylines,
    is_last: np.ndarray,
    per_point: np.ndarray,
    total: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    out: Samples,
    lo: int,
    hi: int,
) -> None:
    """The samples of points lo to hi (``per_point`` each, ending at ``total``) into their rows
    of ``out``, a block of points at a time: every point's values repeated for its samples, not
    gathered sample by sample, and the temporaries those of a block. ``is_last`` (P,) marks each
    polyline's last point, which takes the attributes of the segment before it."""
    points = lines.points
    for first in range(lo, hi, _POINTS):
        last = min(first + _POINTS, hi)
        each = per_point[first:last]
        begin, end = int(total[first] - each[0]), int(total[last - 1])
        rows = slice(begin, end)
        k = np.arange(end - begin) - np.repeat(total[first:last] - each - begin, each)
        t = k / np.repeat(each, each)
        # the step to the next point (none after the very last)
        step = np.zeros((last - first, 3))
        ahead = min(last, len(points) - 1)
        np.subtract(points[first + 1 : ahead + 1], points[first:ahead], out=step[: ahead - first])
        model = np.repeat(points[first:last], each, axis=0)
        model += t[:, None] * np.repeat(step, each, axis=0)
        ends = np.flatnonzero(is_last[first:last])
        model[total[first + ends] - 1 - begin] = points[first + ends]
        source = np.arange(first, last)
        line = np.searchsorted(lines.offsets, source, side="right") - 1
        source[ends] -= 1
        out.faces[rows] = np.repeat(lines.faces[source], each, axis=0)
        out.kind[rows] = np.repeat(lines.kind[source], each)
        out.edge[rows] = np.repeat(lines.edge[source], each)
        out.line[rows] = np.repeat(line, each)
        out.vertex[rows] = k == 0
        eye = transform(model, view)
        clip = eye @ projection.T
        out.inside[rows] = (
            (clip[:, 3] > 0)
            & (clip[:, 2] >= -clip[:, 3])
            & (clip[:, 2] <= clip[:, 3])
            & (np.abs(clip[:, 0]) <= clip[:, 3])
            & (np.abs(clip[:, 1]) <= clip[:, 3])
        )
        out.eye[rows] = eye[:, :3]
        out.pixel[rows] = clip_to_pixels(clip, size)
