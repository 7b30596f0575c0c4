"""Corner normals smoothed within a crease angle, robust to soups and inconsistent winding."""

from __future__ import annotations

import numpy as np

from blueprint.columns import face_cross
from blueprint.scene.weld import weld

# Vertices with more faces than this (fans of cylinder caps, cones) keep flat normals: their
# smoothing would cost degree² pairs, and such fans are planar or pointed anyway.
_MAX_DEGREE = 64
# Pairs of corners around a vertex smoothed at a time (``corner_normals``): some 100 bytes each.
_PAIR_BLOCK = 1 << 20


def weld_ids(positions: np.ndarray, faces: np.ndarray, rel_tol: float = 1e-6) -> np.ndarray:
    """(F, 3) int64: vertex ids where vertices at the same position (within ``rel_tol`` of the
    bounding-box diagonal) share an id, so triangle soups smooth like indexed meshes."""
    used = positions[faces.reshape(-1)].astype(np.float64)
    diag = float(np.linalg.norm(np.ptp(used, axis=0))) or 1.0
    _, welded = weld(positions, faces, tol=diag * rel_tol)
    return welded


def crease_vertices(welded: np.ndarray, unit: np.ndarray, crease_angle: float) -> np.ndarray:
    """(V,) bool: the welded vertex lies on a crease (an edge whose two faces' normals differ,
    up to sign, by more than ``crease_angle`` degrees, unless it is a crease edge on its own),
    a border or a non-manifold edge.

    Parameters
    ----------
    welded : (F, 3) int
        Welded vertex ids per face (``weld_ids``).
    unit : (F, 3) float
        Unit face normals (zero for degenerate faces).
    crease_angle : float
        Degrees.
    """
    edges = np.sort(welded[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    edge_face = np.repeat(np.arange(len(welded)), 3)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    edges = edges[order]
    starts = np.flatnonzero(np.r_[True, (edges[1:] != edges[:-1]).any(axis=1)])
    count = np.diff(np.r_[starts, len(edges)])
    pair = starts[count == 2]
    cos = np.einsum("ij,ij->i", unit[edge_face[order[pair]]], unit[edge_face[order[pair + 1]]])
    crease = edges[pair[np.abs(cos) < np.cos(np.radians(crease_angle)) - 1e-9]]
    vertices = int(welded.max(initial=-1)) + 1
    sharp = np.zeros(vertices, bool)
    sharp[edges[starts[count != 2]].ravel()] = True
    sharp[crease[~lone_creases(crease, sharp)].ravel()] = True
    return sharp


def lone_creases(crease: np.ndarray, anchored: np.ndarray) -> np.ndarray:
    """(E,) bool: which of the crease edges are alone: both ends on no other crease edge and
    not ``anchored`` (on a border or non-manifold edge). A scan's noise lifts single edges past
    the crease angle; a crease of a made thing runs on into others or to a border.

    Parameters
    ----------
    crease : (E, 2) int
        The crease edges' (welded) vertex indices.
    anchored : (V,) bool
        Vertices on a border or non-manifold edge.
    """
    free = np.bincount(crease.ravel(), minlength=len(anchored))[: len(anchored)] == 1
    free &= ~anchored
    return free[crease[:, 0]] & free[crease[:, 1]]


def corner_normals(positions: np.ndarray, faces: np.ndarray, crease_angle: float = 30.0) -> np.ndarray:
    """Normal per triangle corner: the area-weighted mean of the normals of the faces around the
    corner's vertex that lie within ``crease_angle`` degrees of the corner's face; at a vertex
    on no crease edge (``crease_vertices``), of all the faces around it.

    A scan's noise tilts faces that share only a vertex by more than the crease angle while
    every edge between them stays below it; splitting the normal there would draw a crease
    fragment, a speck, at each such vertex. A crease is an edge: where no edge is one, the
    surface is smooth; nor is a crease edge on its own, touching no other crease edge, border
    or non-manifold edge, one: the creases of made things run on. Vertices on borders and
    non-manifold edges keep the pairwise rule: where patches meet without sharing edges
    (T-junctions, open seams), their edges say nothing about the angle between them.

    Normals are compared up to sign, so faces wound the wrong way still smooth with their
    neighbours; each corner keeps its own face's orientation.

    Parameters
    ----------
    positions : (V, 3) float
    faces : (F, 3) int
    crease_angle : float
        Degrees; 0 gives flat (per-face) normals.

    Returns
    -------
    (F, 3, 3) float32
        Unit normal for corner ``j`` of face ``i`` at ``[i, j]``.
    """
    tri = positions[faces].astype(np.float64)
    area_normals = face_cross(tri)
    length = np.linalg.norm(area_normals, axis=1)
    unit = area_normals / np.where(length > 0, length, 1.0)[:, None]
    flat = np.repeat(unit[:, None, :], 3, axis=1)
    if crease_angle <= 0 or len(faces) == 0:
        return flat.astype(np.float32)

    welded = weld_ids(positions, faces)
    sharp = crease_vertices(welded, unit, crease_angle)
    vertex = welded.reshape(-1)
    corner_face = np.repeat(np.arange(len(faces)), 3)
    order = np.argsort(vertex, kind="stable")
    sorted_vertex = vertex[order]
    starts = np.flatnonzero(np.r_[True, sorted_vertex[1:] != sorted_vertex[:-1]])
    degree = np.diff(np.r_[starts, len(order)])
    group_start = np.repeat(starts, degree)
    group_size = np.repeat(degree, degree)
    smooth = group_size <= _MAX_DEGREE

    # every ordered pair (corner a, corner b) around the same vertex, a block of corners at a
    # time: a vertex of degree d makes d pairs a corner, so all at once would hold up to
    # _MAX_DEGREE times the corners
    a_sorted = np.flatnonzero(smooth)
    ends = np.cumsum(group_size[a_sorted])
    pairs = int(ends[-1]) if len(ends) else 0
    cuts = np.r_[0, np.searchsorted(ends, np.arange(_PAIR_BLOCK, pairs, _PAIR_BLOCK)), len(a_sorted)]
    cos_crease = np.cos(np.radians(crease_angle)) - 1e-9
    summed_sorted = np.zeros((len(vertex), 3))
    for lo, hi in zip(cuts[:-1].tolist(), cuts[1:].tolist(), strict=True):
        if lo == hi:
            continue
        block = a_sorted[lo:hi]
        counts = group_size[block]
        a_idx = np.repeat(block, counts)
        within = np.arange(len(a_idx)) - np.repeat(np.cumsum(counts) - counts, counts)
        face_b = corner_face[order[group_start[a_idx] + within]]
        cos = np.einsum("ij,ij->i", unit[corner_face[order[a_idx]]], unit[face_b])
        keep = (np.abs(cos) >= cos_crease) | ~sharp[sorted_vertex[a_idx]]
        contribution = area_normals[face_b[keep]] * np.sign(cos[keep])[:, None]
        # a block's corners are a run of the sorted corners
        target = a_idx[keep] - block[0]
        span = block[-1] + 1 - block[0]
        for axis in range(3):
            summed_sorted[block[0] : block[-1] + 1, axis] += np.bincount(
                target, contribution[:, axis], minlength=span
            )
    summed = np.empty_like(summed_sorted)
    summed[order] = summed_sorted
    norm = np.linalg.norm(summed, axis=1)
    result = flat.reshape(-1, 3).copy()
    ok = norm > 0
    result[ok] = summed[ok] / norm[ok, None]
    return result.reshape(-1, 3, 3).astype(np.float32)
