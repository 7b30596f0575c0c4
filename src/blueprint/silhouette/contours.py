"""Smooth contours: where a surface whose normals are interpolated across its triangles turns
from the view (Hertzmann and Zorin, "Illustrating smooth surfaces", SIGGRAPH 2000).

A mesh's own silhouette edges follow its triangles: on a scan, whose noise folds the surface
a little everywhere, they zigzag across the true outline and break into loops. Here every
vertex takes the area-weighted mean of its faces' normals, ``g = n . v`` (``v`` towards the
eye) is evaluated at the vertices and taken as linear along each edge, and the contour is its
zero set: in every face whose corners differ in the sign of ``g``, the segment between the two
edges where ``g`` crosses zero. Neighbouring faces compute the crossing on their shared edge
alike, so the segments meet end to end into smooth curves.

This holds only where the surface is smooth: faces with a vertex on a crease, a border, a
non-manifold edge or a degenerate face (``feature_vertices``) keep the mesh's exact
silhouette edges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.columns import indexed_cross, row_norm

from .edges import _projected, _row_dots, feature_vertices
from .mesh import Adjacency

__all__ = ["ContourSet", "SmoothSurface", "smooth_contours", "smooth_surface", "toward_eye"]

# Vertex normals this close (a cosine) to square with the view direction are seen edge-on.
_EDGE_ON = 1e-7


@dataclass(frozen=True)
class SmoothSurface:
    """The view-independent half of smooth contours.

    Attributes
    ----------
    smooth : (F,) bool
        Faces with no vertex on a feature whose corners' vertex normals lie on their own side
        (less than 90 degrees from the face's normal): where contours come from ``normals``.
    normals : (V, 3) float64
        Unit vertex normals of the oriented faces, area-weighted (zero where they cancel).
    """

    smooth: np.ndarray
    normals: np.ndarray


@dataclass(frozen=True)
class ContourSet:
    """Smooth contour segments of one view, each inside one face.

    Attributes
    ----------
    segments3d : (N, 2, 3) float64
        Model-space endpoints, after clipping to the near plane.
    segments2d : (N, 2, 2) float64
        Pixel coordinates (x right, y down, origin top-left).
    faces : (N,) int64
        The face each segment lies in.
    edges : (N, 2) int64
        The adjacency's edge each endpoint lies on (where the segment enters and leaves its
        face); an endpoint moved by clipping keeps its edge.
    """

    segments3d: np.ndarray
    segments2d: np.ndarray
    faces: np.ndarray
    edges: np.ndarray


def smooth_surface(
    adj: Adjacency, crease_angle: float = 30.0, sharp: np.ndarray | None = None
) -> SmoothSurface:
    """The smooth faces and the vertex normals of a mesh (``SmoothSurface``); ``sharp``: its
    sharp edges at ``crease_angle`` (``edges.mesh_sharp_edges``) where the caller has them."""
    area_normals = indexed_cross(adj.positions, adj.faces)
    summed = np.zeros((len(adj.positions), 3))
    corner_weight = np.empty((len(adj.faces), 3))  # one array for the three axes' weights
    for axis in range(3):
        corner_weight[:] = area_normals[:, axis, None]
        summed[:, axis] = np.bincount(
            adj.faces.reshape(-1), corner_weight.reshape(-1), minlength=len(adj.positions)
        )
    del corner_weight
    length = row_norm(summed)
    normals = summed / np.where(length > 0, length, 1.0)[:, None]
    feature = feature_vertices(adj, crease_angle, sharp)
    smooth = ~(feature[adj.faces[:, 0]] | feature[adj.faces[:, 1]] | feature[adj.faces[:, 2]])
    for k in range(3):
        smooth &= _row_dots(adj.face_normals, None, normals, adj.faces[:, k]) > 0.0
    return SmoothSurface(smooth, normals)


def smooth_contours(
    adj: Adjacency, surface: SmoothSurface, view: np.ndarray, projection: np.ndarray, size: tuple[int, int]
) -> ContourSet:
    """The zero set of the interpolated ``n . v`` inside the smooth faces of ``surface``, for
    the camera of ``view`` and ``projection`` ((4, 4) float, OpenGL conventions;
    ``projection[3, 3] == 1`` orthographic) at ``size`` (width, height) pixels.

    A vertex where ``g`` is zero (within ``_EDGE_ON``) counts as turned away, so a face holds
    at most one segment, and a crossing at such a vertex lies on it.
    """
    toward = toward_eye(adj.positions, view, projection)
    facing = np.einsum("ij,ij->i", surface.normals, toward)
    # a vertex seen edge-on within rounding counts as turned away: a plane seen edge-on has no
    # contour across it, whichever way its vertices' normals round
    front = facing > _EDGE_ON * np.linalg.norm(toward, axis=1)
    corners = front[adj.faces]
    faces = np.flatnonzero(surface.smooth & corners.any(axis=1) & ~corners.all(axis=1))
    # the edges (k, k + 1) whose ends differ, two a face: the first found and the other
    changes = corners[faces] != corners[faces][:, [1, 2, 0]]
    first = np.argmax(changes, axis=1)
    second = 2 - np.argmax(changes[:, ::-1], axis=1)
    keys = _edge_keys(adj)
    ends = []
    edges = []
    for k in (first, second):
        a = adj.faces[faces, k]
        b = adj.faces[faces, (k + 1) % 3]
        # the crossing from the edge's lower vertex, so both faces of an edge find one point
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        t = facing[lo] / (facing[lo] - facing[hi])
        ends.append(adj.positions[lo] + t[:, None] * (adj.positions[hi] - adj.positions[lo]))
        edges.append(np.searchsorted(keys, lo * len(adj.positions) + hi))
    model = np.stack(ends, axis=1)
    model, pixels, keep = _projected(model, view, projection, size)
    return ContourSet(model, pixels, faces[keep].astype(np.int64), np.stack(edges, axis=1)[keep])


def toward_eye(positions: np.ndarray, view: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """(V, 3) float64: from each of ``positions`` (V, 3) towards the eye of the camera of
    ``view`` and ``projection`` (OpenGL conventions; ``projection[3, 3] == 1`` orthographic:
    the view direction reversed, one for all)."""
    camera_to_model = np.linalg.inv(np.asarray(view, np.float64))
    if projection[3, 3] == 1.0:
        return np.broadcast_to(camera_to_model[:3, 2], positions.shape)
    return camera_to_model[:3, 3] - positions


def _edge_keys(adj: Adjacency) -> np.ndarray:
    """(E,) int64 ``lo * V + hi`` of the adjacency's edges, ascending as its edges are."""
    return adj.edges[:, 0] * len(adj.positions) + adj.edges[:, 1]
