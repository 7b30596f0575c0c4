"""Sampled polylines cut into 2D pieces of one occlusion level each (``Lines``, each with the
kind and the edges of the line it was cut from): what the writers draw."""

from __future__ import annotations

import numpy as np

from ..linework import Lines, runs_of
from .coincident import suppress_coincident
from .samples import Samples

__all__ = ["split_by_level"]


def _along(line: np.ndarray, pixel: np.ndarray) -> np.ndarray:
    """(S + 1,) pixels along the polylines up to each sample, the last entry the end of it all:
    the steps between samples of one polyline summed (a level does not change it)."""
    step = np.zeros(len(line))
    d = np.diff(pixel, axis=0)
    step[:-1] = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
    step[np.r_[line[1:] != line[:-1], True]] = 0.0
    return np.r_[0.0, np.cumsum(step)]


def _run_lengths(level, line, along):
    """Runs of one level along each polyline: start (inclusive), end (exclusive) and length in
    pixels, from halfway to the previous sample to halfway to the next one (the polyline's own
    ends where there is none); ``along`` from :func:`_along`."""
    start, end, lo, hi = _runs(level, line, along)
    return start, end, hi - lo


def _runs(level, line, along):
    """``_run_lengths``' start and end of every run, and where its pixels begin and end."""
    n = len(level)
    change = np.r_[True, (line[1:] != line[:-1]) | (level[1:] != level[:-1])]
    start = np.flatnonzero(change)
    end = np.r_[start[1:], n]
    lo = np.where(start > 0, 0.5 * (along[start - 1] + along[start]), along[start])
    hi = np.where(end < n, 0.5 * (along[end - 1] + along[end]), along[end - 1])
    return start, end, lo, hi


def _smooth(
    level: np.ndarray, line: np.ndarray, pixel: np.ndarray, min_run: float, along: np.ndarray | None = None
) -> np.ndarray:
    """Hysteresis along each polyline: a level holds until another one has lasted ``min_run``
    pixels. Runs shorter than that (flicker where surfaces nearly coincide, a line's last pixel
    seeing past an outline) take a neighbour's level, the shortest runs first.

    Each round merges every short run whose length is a local minimum among its polyline's runs
    into the longer of its neighbours (the one of equal level where both are equal), so a
    staircase of short runs collapses from its shortest step outward and two runs never trade
    places. Samples outside the view (level -1) neither take nor give a level. The rounds work
    on the runs, not the samples: runs of one line that come to one level join. ``along``:
    ``_along(line, pixel)``, where the caller has it.
    """
    n = len(level)
    if n < 2 or min_run <= 0:
        return level.copy()
    along = _along(line, pixel) if along is None else along
    start, end, lo, hi = _runs(level, line, along)
    run_line, run_level = line[start], level[start]
    smoothed = np.empty(n, level.dtype)
    # a line without short runs changes no more and leaves the rounds; the runs of such lines
    # before each run still count in its place among all runs, which breaks ties
    before = np.zeros(len(start), np.int64)
    runs = len(start)
    while runs >= 2:
        merged = _merged_levels(hi - lo, run_line, run_level, min_run, before + np.arange(len(start)))
        if merged is None:
            break
        target, short = merged
        stays = _with_any(short, run_line)
        done = ~stays
        _fill(smoothed, start[done], end[done], run_level[done])
        before = (before + np.cumsum(done) - done)[stays]
        start, end, lo, hi = start[stays], end[stays], lo[stays], hi[stays]
        run_line, target = run_line[stays], target[stays].astype(level.dtype)
        # a joined run begins where its first run began and ends where its last one ended
        first = np.r_[True, (run_line[1:] != run_line[:-1]) | (target[1:] != target[:-1])]
        last = np.r_[first[1:], True]
        runs -= len(first) - np.count_nonzero(first)
        start, lo, before = start[first], lo[first], before[first]
        run_line, run_level = run_line[first], target[first]
        end, hi = end[last], hi[last]
    _fill(smoothed, start, end, run_level)
    return smoothed


def _with_any(flag: np.ndarray, run_line: np.ndarray) -> np.ndarray:
    """(R,) bool: whether any run of each run's polyline has ``flag`` (runs in line order)."""
    if len(flag) == 0:
        return flag
    first = np.flatnonzero(np.r_[True, run_line[1:] != run_line[:-1]])
    return np.repeat(np.logical_or.reduceat(flag, first), np.diff(np.r_[first, len(flag)]))


def _fill(out: np.ndarray, start: np.ndarray, end: np.ndarray, value: np.ndarray) -> None:
    """``out[start[i]:end[i]] = value[i]`` for every i (ranges apart, in order)."""
    count = end - start
    total = int(count.sum())
    if total == 0:
        return
    at = np.arange(total) + np.repeat(start - (np.cumsum(count) - count), count)
    out[at] = np.repeat(value, count)


def _merged_levels(
    length: np.ndarray, run_line: np.ndarray, run_level: np.ndarray, min_run: float, index: np.ndarray
):
    """One round of ``_smooth`` over runs in order (their ``length`` in pixels, polyline,
    level and place among all runs): each run under ``min_run`` pixels beside another of its
    line, and shorter than its short neighbours, takes the level of its longer neighbour (of
    both, where they agree); the runs' levels after the round and which runs were short, or
    None where no run is short."""
    has_prev = np.r_[False, run_line[1:] == run_line[:-1]] & (np.r_[-1, run_level[:-1]] >= 0)
    has_next = np.r_[run_line[:-1] == run_line[1:], False] & (np.r_[run_level[1:], -1] >= 0)
    short = (length < min_run) & (run_level >= 0) & (has_prev | has_next)
    if not short.any():
        return None
    # ties between equal lengths broken by a hash of the run, so plateaus merge in few rounds
    key = length + 1e-6 * ((index * 2654435761) % 1000) / 1000
    prev_key = np.where(has_prev, np.r_[np.inf, key[:-1]], np.inf)
    next_key = np.where(has_next, np.r_[key[1:], np.inf], np.inf)
    merge = short & (key < np.where(np.r_[False, short[:-1]], prev_key, np.inf))
    merge &= key < np.where(np.r_[short[1:], False], next_key, np.inf)
    prev_len = np.where(has_prev, np.r_[0.0, length[:-1]], -1.0)
    next_len = np.where(has_next, np.r_[length[1:], 0.0], -1.0)
    prev_level = np.r_[-1, run_level[:-1]]
    next_level = np.r_[run_level[1:], -1]
    take_prev = np.where(has_prev & has_next & (prev_level == next_level), True, prev_len >= next_len)
    return np.where(merge, np.where(take_prev, prev_level, next_level), run_level), short


def _drop_slivers(level: np.ndarray, samples: Samples, min_run: float, along: np.ndarray) -> np.ndarray:
    """Leave out runs shorter than ``min_run`` pixels that border a left-out stretch of their
    own polyline (a coincident line or an edge that is no edge, level -1 inside the view): what
    a pixel test could not decide at the ends of such a stretch. A short line of its own, or
    one running out of the view, stays; ``along`` as ``_along`` of the samples."""
    start, end, length = _run_lengths(level, samples.line, along)
    run_line, run_level = samples.line[start], level[start]
    left_out = (run_level < 0) & samples.inside[start]
    before = np.r_[False, (run_line[1:] == run_line[:-1]) & left_out[:-1]]
    after = np.r_[(run_line[:-1] == run_line[1:]) & left_out[1:], False]
    sliver = (run_level >= 0) & (length < min_run) & (before | after)
    return np.where(np.repeat(sliver, end - start), -1, level).astype(level.dtype)


def _piece_points(runs: int, at: np.ndarray, owner: np.ndarray, before, mid_before, after, mid_after):
    """The points of the pieces that ``split_by_level`` cuts, of ``runs`` runs: the samples'
    points ``at`` of runs ``owner`` (in order), a midpoint ``mid_before`` before runs ``before``
    and ``mid_after`` after runs ``after``. Returns (N, 2) points, (P + 1,) offsets and the
    runs that make pieces (those of two points or more), each run's points in order: the
    midpoint before it, its samples', the midpoint after it, each written where it goes."""
    in_run = np.bincount(owner, minlength=runs)
    has_before = np.zeros(runs, np.int64)
    has_before[before] = 1
    per_run = has_before + in_run
    per_run[after] += 1
    good = per_run >= 2
    pieces = np.flatnonzero(good)
    offsets = np.r_[0, np.cumsum(per_run[pieces])].astype(np.int64)
    first_point = np.zeros(runs, np.int64)
    first_point[pieces] = offsets[:-1]
    first_point += has_before
    pts = np.empty((offsets[-1], 2))
    rank = np.arange(len(owner)) - (np.cumsum(in_run) - in_run)[owner]
    taken = good[owner]
    pts[first_point[owner[taken]] + rank[taken]] = at[taken]
    taken = good[before]
    pts[first_point[before[taken]] - 1] = mid_before[taken]
    taken = good[after]
    pts[first_point[after[taken]] + in_run[after[taken]]] = mid_after[taken]
    return pts, offsets, pieces


def split_by_level(
    samples: Samples,
    level: np.ndarray,
    part: np.ndarray,
    max_level: int,
    min_run: float = 2.5,
    coincident: float = 0.5,
    behind: np.ndarray | None = None,
    renderer=None,
) -> Lines:
    """Cut the sampled polylines into 2D pieces of one level each, with their polyline's part
    and kind and the edges their samples lie on.

    A piece runs over consecutive samples of one polyline with one level and kind; its ends
    are the midpoints towards the neighbouring samples of other levels (so pieces of different
    levels meet), or where only the kind changes the vertex where it does, and of its inner
    samples only the polyline's vertices are kept (the others lie on the straight segments
    between them). Samples outside the view or deeper than ``max_level`` are dropped, and so
    are samples on a line of lower level (see :func:`suppress_coincident`, within
    ``coincident`` pixels; 0 keeps them). A level change must hold for ``min_run`` pixels (see
    :func:`_smooth`). ``behind`` (S,) bool, samples behind a shaded part's surface, cuts pieces
    too (a change must hold as long). A
    ``renderer`` runs the search for coincident samples on the GPU.
    """
    n = len(level)
    if n == 0:
        return Lines.empty()
    along = _along(samples.line, samples.pixel)
    behind = (
        np.zeros(n, bool)
        if behind is None
        else _smooth(behind.astype(np.int32), samples.line, samples.pixel, min_run, along) > 0
    )
    level = _smooth(level, samples.line, samples.pixel, min_run, along)
    level = np.where(level <= max_level, level, -1)
    if coincident > 0:
        level = suppress_coincident(samples, level, coincident, renderer=renderer)
        # a left-out stretch can end inside a run and leave a sliver of it beside another level
        level = _smooth(level, samples.line, samples.pixel, min_run, along)
    level = _drop_slivers(level, samples, min_run, along)
    line, pixel = samples.line, samples.pixel
    keep = (level >= 0) & (level <= max_level)
    # runs: consecutive samples of one line with one level (and one side of the shading)
    kind = samples.kind
    same = (line[1:] == line[:-1]) & (level[1:] == level[:-1]) & (behind[1:] == behind[:-1])
    # where only the kind changes, at a vertex of the line, the pieces meet at that vertex
    kind_only = np.r_[False, same & (kind[1:] != kind[:-1])]
    change = np.r_[True, ~same] | kind_only
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
    before = runs[joined_before[runs] & ~kind_only[run_start[runs]]]
    after = runs[joined_after[runs]]
    mid_before = 0.5 * (pixel[run_start[before]] + pixel[run_start[before] - 1])
    at_vertex = kind_only[run_end[after]][:, None]
    mid_after = np.where(
        at_vertex, pixel[run_end[after]], 0.5 * (pixel[run_end[after] - 1] + pixel[run_end[after]])
    )
    pts, offsets, pieces = _piece_points(
        len(run_start), pixel[chosen], run[chosen], before, mid_before, after, mid_after
    )
    # each piece's edges: those of its samples, in order, each run of one edge once
    piece_of_run = np.full(len(run_start), -1, np.int64)
    piece_of_run[pieces] = np.arange(len(pieces))
    owner = piece_of_run[run]
    on_edge = (owner >= 0) & (samples.edge >= 0)
    edges, edge_offsets = runs_of(samples.edge[on_edge], owner[on_edge], len(pieces))
    first = run_start[pieces]
    return Lines(
        pts,
        offsets,
        part[line[first]].astype(np.int32),
        samples.kind[first].astype(np.uint8),
        level[first].astype(np.int32),
        edges,
        edge_offsets,
        behind[first],
    )
