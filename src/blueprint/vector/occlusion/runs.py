"""Sampled polylines cut into 2D pieces of one occlusion level each: what the writers draw."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .coincident import suppress_coincident
from .samples import Samples

__all__ = ["Pieces", "split_by_level"]


@dataclass(frozen=True)
class Pieces:
    """2D polylines of one level each: piece ``i`` is ``points[offsets[i]:offsets[i + 1]]``."""

    points: np.ndarray
    offsets: np.ndarray
    part: np.ndarray
    level: np.ndarray

    def __len__(self) -> int:
        return len(self.offsets) - 1

    @classmethod
    def empty(cls) -> Pieces:
        return cls(np.zeros((0, 2)), np.zeros(1, np.int64), np.zeros(0, np.int32), np.zeros(0, np.int32))


def _smooth(level: np.ndarray, line: np.ndarray, pixel: np.ndarray, min_run: float) -> np.ndarray:
    """Absorb runs of one level shorter than ``min_run`` pixels: flicker below the resolution.

    A short run between two runs of one level takes their level; a short run at the end of a
    polyline takes the level of the longer run beside it (the typical case: a hidden edge that
    ends on an outline, whose last pixel sees past the outline).
    """
    level = level.copy()
    n = len(level)
    if n < 2 or min_run <= 0:
        return level
    for _ in range(2):
        change = np.r_[True, (line[1:] != line[:-1]) | (level[1:] != level[:-1])]
        start = np.flatnonzero(change)
        end = np.r_[start[1:], n]  # exclusive
        if len(start) < 2:
            break
        # a run's length: from halfway to the previous sample to halfway to the next one
        step = np.r_[np.linalg.norm(np.diff(pixel, axis=0), axis=1), 0.0]
        step[np.r_[line[1:] != line[:-1], True]] = 0.0
        along = np.r_[0.0, np.cumsum(step)]
        lo = np.where(start > 0, 0.5 * (along[start - 1] + along[start]), along[start])
        hi = np.where(end < n, 0.5 * (along[end - 1] + along[end]), along[end - 1])
        hi = np.where(end < n, hi, along[end - 1])
        length = hi - lo
        run_line = line[start]
        run_level = level[start]
        has_prev = np.r_[False, run_line[1:] == run_line[:-1]]
        has_next = np.r_[run_line[:-1] == run_line[1:], False]
        prev_level = np.r_[-2, run_level[:-1]]
        next_level = np.r_[run_level[1:], -2]
        prev_len = np.r_[0.0, length[:-1]]
        next_len = np.r_[length[1:], 0.0]
        short = (length < min_run) & (run_level >= 0)
        inner = short & has_prev & has_next & (prev_level == next_level) & (prev_level >= 0)
        head = short & ~has_prev & has_next & (next_len > length) & (next_level >= 0)
        tail = short & has_prev & ~has_next & (prev_len > length) & (prev_level >= 0)
        target = np.where(inner | tail, prev_level, np.where(head, next_level, run_level))
        if not (inner | head | tail).any():
            break
        level = np.repeat(target, end - start).astype(level.dtype)
    return level


def split_by_level(
    samples: Samples,
    level: np.ndarray,
    part: np.ndarray,
    max_level: int,
    min_run: float = 2.0,
    coincident: float = 0.5,
) -> Pieces:
    """Cut the sampled polylines into 2D pieces of one level each.

    A piece runs over consecutive samples of one polyline with one level; its ends are the
    midpoints towards the neighbouring samples of other levels (so pieces of different levels
    meet), and of its inner samples only the polyline's vertices are kept (the others lie on
    the straight segments between them). Samples outside the view or deeper than
    ``max_level`` are dropped, and so are samples on a line of lower level (see
    :func:`suppress_coincident`, within ``coincident`` pixels; 0 keeps them).
    """
    n = len(level)
    if n == 0:
        return Pieces.empty()
    level = _smooth(level, samples.line, samples.pixel, min_run)
    level = np.where(level <= max_level, level, -1)
    if coincident > 0:
        level = suppress_coincident(samples, level, coincident, min_run=min_run)
    line, pixel = samples.line, samples.pixel
    keep = (level >= 0) & (level <= max_level)
    # runs: consecutive samples of one line with one level
    change = np.r_[True, (line[1:] != line[:-1]) | (level[1:] != level[:-1])]
    run = np.cumsum(change) - 1
    run_start = np.flatnonzero(change)
    run_end = np.r_[run_start[1:], n]  # exclusive
    run_keep = keep[run_start]
    # a neighbour across a level change on the same line gives a midpoint end
    joined_before = np.r_[False, line[run_start[1:]] == line[run_start[1:] - 1]]
    joined_after = np.r_[line[run_end[:-1] - 1] == line[run_end[:-1]], False]
    # samples kept as points: vertices, and the first and last sample of every run
    is_point = samples.vertex.copy()
    is_point[run_start] = True
    is_point[run_end - 1] = True
    chosen = np.flatnonzero(is_point & run_keep[run])
    runs = np.flatnonzero(run_keep)
    before = runs[joined_before[runs]]
    after = runs[joined_after[runs]]
    mid_before = 0.5 * (pixel[run_start[before]] + pixel[run_start[before] - 1])
    mid_after = 0.5 * (pixel[run_end[after] - 1] + pixel[run_end[after]])
    # order all points by (run, position): midpoints before go first, after go last
    pts = np.concatenate([pixel[chosen], mid_before, mid_after])
    owner = np.concatenate([run[chosen], before, after])
    pos = np.concatenate([chosen.astype(np.float64), run_start[before] - 0.5, run_end[after] - 0.5])
    order = np.lexsort((pos, owner))
    pts, owner = pts[order], owner[order]
    # a piece needs two points
    per_run = np.bincount(owner, minlength=len(run_start))
    good = per_run >= 2
    point_keep = good[owner]
    pts, owner = pts[point_keep], owner[point_keep]
    pieces = np.flatnonzero(good)
    offsets = np.r_[0, np.cumsum(per_run[pieces])].astype(np.int64)
    return Pieces(
        pts,
        offsets,
        part[line[run_start[pieces]]].astype(np.int32),
        level[run_start[pieces]].astype(np.int32),
    )
