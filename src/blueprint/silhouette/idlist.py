"""Adjacency lists for the ID-list variant of triangle-ID silhouettes (GPU-free).

For each vertex, the list of the triangles that share it, sorted ascending and appended one after
the other into one array, plus a pointer table of (start, count) per vertex and the vertex ids of
every face: the "two textures, one with the lists appended, one with the pointer indirection"
of the paper (section 4.3), with a third small table from face to vertices. A pixel's triangle
``t`` and its neighbour's triangle ``n`` are adjacent when ``n`` is in the list of one of ``t``'s
three vertices; sorted lists make that a binary search, so a vertex shared by hundreds of
triangles (the axis of the paper's Figure 2) costs a few fetches, not hundreds.

This is the preprocessing the vertex-storage method avoids: it depends on the topology, so it
must be redone whenever the topology changes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.scene.weld import weld

__all__ = ["IdLists", "build_id_lists", "id_lists_from_topology"]


@dataclass(frozen=True)
class IdLists:
    """Vertex-to-triangle lists of a triangle mesh.

    Attributes
    ----------
    face_vertices : np.ndarray
        (F, 3) int32 vertex ids of every face, after welding.
    pointers : np.ndarray
        (V, 2) int32 ``(start, count)`` of each vertex's list in `lists`.
    lists : np.ndarray
        (K,) int32 face indices: the faces around vertex ``v`` are
        ``lists[start : start + count]``, ascending, each face once.
    """

    face_vertices: np.ndarray
    pointers: np.ndarray
    lists: np.ndarray

    def adjacent(self, a: int, b: int) -> bool:
        """Whether faces `a` and `b` share a vertex (the test the shader makes per pixel)."""
        for v in self.face_vertices[a]:
            start, count = self.pointers[v]
            block = self.lists[start : start + count]
            i = int(np.searchsorted(block, b))
            if i < len(block) and block[i] == b:
                return True
        return False


def id_lists_from_topology(faces: np.ndarray, num_vertices: int | None = None) -> IdLists:
    """Lists from a connectivity that is already known (no welding).

    Parameters
    ----------
    faces : np.ndarray
        (F, 3) integer vertex indices.
    num_vertices : int, optional
        Number of vertices; defaults to ``faces.max() + 1``.
    """
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    count_v = int(num_vertices if num_vertices is not None else (faces.max() + 1 if faces.size else 0))
    vertex = faces.reshape(-1)
    face = np.repeat(np.arange(len(faces), dtype=np.int64), 3)
    # one (vertex, face) incidence per pair, sorted by vertex then face
    keys = np.unique(vertex * max(len(faces), 1) + face)
    vertex, face = keys // max(len(faces), 1), keys % max(len(faces), 1)
    counts = np.bincount(vertex, minlength=count_v)
    starts = np.cumsum(counts) - counts
    return IdLists(
        face_vertices=faces.astype(np.int32),
        pointers=np.stack([starts, counts], axis=1).astype(np.int32),
        lists=face.astype(np.int32),
    )


def build_id_lists(positions: np.ndarray, faces: np.ndarray, tol: float | None = None) -> IdLists:
    """Weld a triangle soup, then build its vertex-to-triangle lists.

    Parameters
    ----------
    positions, faces : np.ndarray
        The soup: (V, 3) float vertex positions, (F, 3) integer vertex indices.
    tol : float, optional
        Weld distance, as :func:`blueprint.silhouette.weld` (default 1e-6 of the diagonal).
    """
    welded, welded_faces = weld(positions, faces, tol)
    return id_lists_from_topology(welded_faces, len(welded))
