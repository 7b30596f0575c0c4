"""Polygons made triangles as trimesh makes them (``trimesh.geometry.triangulate_quads``), so
that the NumPy readers give trimesh's faces in trimesh's order."""

from __future__ import annotations

import numpy as np

__all__ = ["triangulated"]


def triangulated(corners: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(T, 3): polygons triangulated as trimesh does: the triangles first, as they are;
    then every quad's (0, 1, 2), then every quad's (2, 3, 0); then each larger polygon as a
    fan from its first corner, in order; polygons of fewer than three corners left out.

    Parameters
    ----------
    corners : (C,) int
        The corners of every polygon, one polygon after another: the triangles' corners keep
        their type, int64 where polygons of more corners are cut.
    counts : (P,) int64
        The corners of each polygon.
    """
    if len(corners) == 3 * len(counts) and (counts == 3).all():
        return corners.reshape(-1, 3)  # triangles alone, as they are
    first = np.cumsum(counts) - counts
    tri = first[counts == 3]
    quad = first[counts == 4]
    fan = first[counts > 4]
    fan_counts = counts[counts > 4] - 2
    # the fans' triangles: polygon p's j-th (j from 1) is corners p0, pj, p(j+1)
    base = np.repeat(fan, fan_counts)
    step = np.arange(len(base)) - np.repeat(np.cumsum(fan_counts) - fan_counts, fan_counts) + 1
    rows = np.concatenate(
        [
            tri[:, None] + np.arange(3),
            quad[:, None] + np.array([0, 1, 2]),
            quad[:, None] + np.array([2, 3, 0]),
            np.stack([base, base + step, base + step + 1], axis=1),
        ]
    )
    return corners[rows].astype(np.int64, copy=False)
