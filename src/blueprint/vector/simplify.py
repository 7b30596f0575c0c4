"""Douglas–Peucker simplification of many polylines at once, vectorised over all of them."""

from __future__ import annotations

from functools import partial

import numpy as np

from blueprint import parallel

__all__ = ["douglas_peucker"]


def douglas_peucker(
    points: np.ndarray, offsets: np.ndarray, tolerance: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Simplify polylines so that no dropped point lies farther than `tolerance` from the result.

    Every polyline keeps its two ends. Each round splits every interval whose farthest inner
    point (distance to the chord, as a segment) exceeds `tolerance` at that point, for all
    polylines together, so the number of NumPy passes is the depth of the recursion, not the
    number of polylines.

    Parameters
    ----------
    points : (N, D) float
        The polylines' points, one after the other.
    offsets : (P + 1,) int
        Polyline ``i`` is ``points[offsets[i]:offsets[i + 1]]``; each has at least one point.
    tolerance : float
        Largest distance allowed between a dropped point and the simplified polyline, >= 0.

    Returns
    -------
    points : (M, D) float
        The kept points.
    offsets : (P + 1,) int64
        New offsets into them.
    kept : (N,) bool
        Which input points were kept.
    """
    points = np.asarray(points, dtype=np.float64)
    offsets = np.asarray(offsets, dtype=np.int64)
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise ValueError(f"tolerance must be a finite number >= 0, got {tolerance}")
    keep = np.zeros(len(points), dtype=bool)
    if len(points) == 0:
        return points.copy(), offsets.copy(), keep
    keep[offsets[:-1]] = True
    keep[offsets[1:] - 1] = True
    a, b = offsets[:-1], offsets[1:] - 1
    busy = b - a >= 2
    a, b = a[busy], b[busy]
    # the polylines' intervals split side by side on the pool, a block of them a thread: each
    # interval splits on its own, and marks only its own points
    parallel.run(partial(_split_intervals, points, a, b, float(tolerance) ** 2, keep), len(a))
    counts = (
        np.add.reduceat(keep.astype(np.int64), offsets[:-1]) if len(offsets) > 1 else np.zeros(0, np.int64)
    )
    return points[keep], np.r_[0, np.cumsum(counts)].astype(np.int64), keep


def _split_intervals(
    points: np.ndarray, a: np.ndarray, b: np.ndarray, tol2: float, keep: np.ndarray, lo: int, hi: int
) -> None:
    """Mark in ``keep`` the points that the intervals ``a[lo:hi]`` to ``b[lo:hi]`` keep: round
    after round, every interval whose farthest inner point lies farther than ``tol2``'s root
    from the chord is split there."""
    a, b = a[lo:hi], b[lo:hi]
    while len(a):
        inner = b - a - 1
        first = np.cumsum(inner) - inner
        owner = np.repeat(np.arange(len(a)), inner)
        index = a[owner] + 1 + (np.arange(int(inner.sum())) - first[owner])
        start, chord = points[a], points[b] - points[a]
        length2 = np.einsum("ij,ij->i", chord, chord)
        inv = np.divide(1.0, length2, out=np.zeros_like(length2), where=length2 > 0)
        rel = points[index] - start[owner]
        t = np.clip(np.einsum("ij,ij->i", rel, chord[owner]) * inv[owner], 0.0, 1.0)
        off = rel - t[:, None] * chord[owner]
        dist2 = np.einsum("ij,ij->i", off, off)
        far = np.maximum.reduceat(dist2, first)
        # the first inner point at the largest distance, per interval
        at_max = np.where(dist2 == far[owner], np.arange(len(index)), len(index))
        split_at = index[np.minimum.reduceat(at_max, first)]
        split = far > tol2
        m = split_at[split]
        keep[m] = True
        a = np.concatenate([a[split], m])
        b = np.concatenate([m, b[split]])
        busy = b - a >= 2
        a, b = a[busy], b[busy]
