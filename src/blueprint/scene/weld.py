"""Vertex welding: vertices closer than a tolerance merged into one, as triangle soups need.

Smoothing normals (``blueprint.scene.normals``) and the object-space silhouette method
(``blueprint.silhouette``) both start from it; it depends on the geometry only.
"""

from __future__ import annotations

import numpy as np

__all__ = ["weld"]

# Default weld tolerance, relative to the bounding-box diagonal.
_REL_TOL = 1e-6
# The cell itself and the 13 lexicographically positive offsets: together they pair every
# cell with each of its 26 neighbours once.
_FORWARD_OFFSETS = np.array(
    [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)], dtype=np.int64
)[13:]
# Large odd multipliers for a spatial hash of integer cell coordinates (Teschner et al. 2003).
_HASH = np.array([73856093, 19349663, 83492791], dtype=np.int64)


def _check_mesh(positions: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    positions = np.asarray(positions, dtype=np.float64)
    faces = np.asarray(faces)
    if positions.ndim != 2 or positions.shape[1] != 3:
        raise ValueError(f"positions must have shape (V, 3), got {positions.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"faces must have shape (F, 3), got {faces.shape}")
    if faces.size and not np.issubdtype(faces.dtype, np.integer):
        raise ValueError(f"faces must hold integers, got dtype {faces.dtype}")
    faces = faces.astype(np.int64)
    if faces.size and (faces.min() < 0 or faces.max() >= len(positions)):
        raise ValueError(f"face indices must lie in [0, {len(positions)})")
    if not np.isfinite(positions).all():
        raise ValueError("positions must be finite")
    return positions, faces


def _close_pairs(points: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of distinct points with ``|p_i - p_j| <= tol``, found through a grid hash.

    With cells slightly larger than `tol`, two points within `tol` lie in the same or in
    adjacent cells whichever side of a cell boundary they fall, so probing each point's cell
    and its neighbours finds every pair. Cells are bucketed by a wrapping integer hash: a
    collision only merges two buckets, adding candidates that the distance test rejects.
    """
    scaled = (points - points.min(axis=0)) / (tol * (1.0 + 1e-9))
    if scaled.max(initial=0.0) >= 2.0**52:
        raise ValueError("weld tolerance is too small relative to the mesh extent")
    cells = np.floor(scaled).astype(np.int64)

    order = np.argsort(cells @ _HASH, kind="stable")
    bucket_hash, bucket_start, bucket_count = np.unique(
        (cells @ _HASH)[order], return_index=True, return_counts=True
    )
    firsts, seconds = [], []
    for offset in _FORWARD_OFFSETS:
        probe = (cells + offset) @ _HASH
        target = np.minimum(np.searchsorted(bucket_hash, probe), len(bucket_hash) - 1)
        found = bucket_hash[target] == probe
        if not offset.any():
            # Within its own cell a point only needs probing if it is not alone there.
            found &= bucket_count[target] > 1
        i, target = np.flatnonzero(found), target[found]
        # Each probing point against every point of its target bucket, without a loop.
        count = bucket_count[target]
        rank = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        i = np.repeat(i, count)
        j = order[np.repeat(bucket_start[target], count) + rank]
        diff = points[i] - points[j]
        keep = (i != j) & (np.einsum("ij,ij->i", diff, diff) <= tol * tol)
        firsts.append(i[keep])
        seconds.append(j[keep])
    return np.concatenate(firsts), np.concatenate(seconds)


def _components(label: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Connected components of the graph whose edges are the pairs (i, j): each vertex gets the
    smallest vertex index of its component. Clusters of near-duplicates are a few vertices
    across, so this takes a few rounds; in numpy, so that drawing does not load scipy.
    Returns component numbers 0 to C-1."""
    while True:
        low = np.minimum(label[i], label[j])
        before = label.copy()
        np.minimum.at(label, i, low)
        np.minimum.at(label, j, low)
        # pointer jumping: follow labels to their roots
        while True:
            jumped = label[label]
            if np.array_equal(jumped, label):
                break
            label = jumped
        if np.array_equal(label, before):
            return np.unique(label, return_inverse=True)[1].reshape(-1)


def weld(positions: np.ndarray, faces: np.ndarray, tol: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices that lie within `tol` of each other.

    Merging is transitive: chains of vertices each within `tol` of the next collapse into one.
    A merged vertex takes the position of its lowest-index member, and welded vertices keep
    the order of their first occurrence. The cost grows with the square of the number of
    vertices per `tol`-sized cell, so `tol` should stay well below the mesh's edge lengths.

    Parameters
    ----------
    positions : np.ndarray
        (V, 3) float vertex positions.
    faces : np.ndarray
        (F, 3) integer vertex indices.
    tol : float, optional
        Euclidean merge distance. Defaults to 1e-6 times the bounding-box diagonal; 0 merges
        exact duplicates only.

    Returns
    -------
    positions : np.ndarray
        (V', 3) float64 welded positions, V' <= V.
    faces : np.ndarray
        (F, 3) int64 faces remapped to the welded positions.
    """
    positions, faces = _check_mesh(positions, faces)
    if len(positions) == 0:
        return positions.copy(), faces
    if tol is None:
        tol = _REL_TOL * float(np.linalg.norm(np.ptp(positions, axis=0)))
    elif not (np.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol must be a finite non-negative number, got {tol}")

    # Exact duplicates first: triangle soups repeat every vertex several times, and collapsing
    # them keeps the grid cells nearly empty for the near-duplicate search.
    # Adding 0.0 turns -0.0 into 0.0, which row-unique would otherwise tell apart by bytes.
    unique, inverse = np.unique(positions + 0.0, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    label = np.arange(len(unique))
    if tol > 0 and len(unique) > 1:
        i, j = _close_pairs(unique, tol)
        label = _components(label, np.asarray(i, np.int64), np.asarray(j, np.int64))

    group = label[inverse]
    # Number the groups by their first original vertex so the output order is stable.
    group_first = np.full(group.max() + 1, len(positions), dtype=np.int64)
    np.minimum.at(group_first, group, np.arange(len(positions)))
    rank = np.empty_like(group_first)
    rank[np.argsort(group_first, kind="stable")] = np.arange(len(group_first))
    return positions[np.sort(group_first)], rank[group][faces]
