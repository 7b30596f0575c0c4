"""Preprocessing of a triangle soup: vertex welding (``blueprint.scene.weld``), edge
connectivity, consistent winding.

This is the "CPU-Preprocess" stage of the conventional object-space silhouette method
(weld, connect, orient); everything here depends only on the geometry, not on the view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.columns import indexed_cross, row_norm
from blueprint.scene.weld import weld
from blueprint.sorting import stable_argsort, unique_first

__all__ = ["Adjacency", "build_adjacency", "connect", "weld"]

# Faces whose doubled area is below this fraction of their longest edge squared get a zero
# normal: their cross product is rounding noise and its direction would be arbitrary.
_DEGENERATE_REL_AREA = 1e-12
# Levels of the winding search's breadth-first distances found one at a time, at most.
_MAX_LEVELS = 4096


@dataclass(frozen=True)
class Adjacency:
    """Welded, connected and consistently wound triangle mesh.

    Attributes
    ----------
    positions : np.ndarray
        (V, 3) float64 welded vertex positions.
    faces : np.ndarray
        (F, 3) int64 vertex indices into `positions`, in the original face order. Winding is
        consistent within each component where the surface is orientable.
    flipped : np.ndarray
        (F,) bool, True for faces whose winding was reversed.
    edges : np.ndarray
        (E, 2) int64 unique undirected edges, each row sorted ascending.
    edge_faces : np.ndarray
        (K, 2) int64 rows ``(edge index, face index)``, one per incidence, sorted by edge then
        face. Edges with three or more faces (non-manifold) keep all incidences. Faces with a
        repeated vertex index after welding contribute no incidences.
    component : np.ndarray
        (F,) int64 component id per face; components are the sets of faces connected through
        manifold (two-face) edges, i.e. the units over which winding was made consistent.
    face_normals : np.ndarray
        (F, 3) float64 unit normals of the oriented faces, zero for degenerate faces.
    """

    positions: np.ndarray
    faces: np.ndarray
    flipped: np.ndarray
    edges: np.ndarray
    edge_faces: np.ndarray
    component: np.ndarray
    face_normals: np.ndarray


def _orient(num_faces: int, pair_faces: np.ndarray, pair_parity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Flip flags and component ids (numbered by their lowest face) over manifold edges.

    `pair_faces` (M, 2) holds the two faces of each manifold edge and `pair_parity` (M,) is
    True where they traverse it in the same direction, i.e. where one of them must flip. The
    lowest-index face of every component keeps its winding. Where every component can be
    wound consistently, that winding is the only one, found by merging faces into components
    (``_orient_merged``); else a breadth-first search decides (``_orient_searched``).
    """
    merged = _orient_merged(num_faces, pair_faces, pair_parity)
    return merged if merged is not None else _orient_searched(num_faces, pair_faces, pair_parity)


def _orient_merged(
    num_faces: int, pair_faces: np.ndarray, pair_parity: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """``_orient`` by merging trees of faces, with NumPy alone (scipy, which the search needs,
    is slow to import): every round, each tree's root hangs under the lowest
    root that a pair joins it to, and the trees are flattened by pointer jumping, each face
    keeping its flip relative to its root; a few rounds on real meshes. None where a pair's
    parity disagrees with the flips found: a surface that cannot be wound consistently, whose
    leftover inconsistency the search places."""
    a, b = pair_faces[:, 0].astype(np.int64), pair_faces[:, 1].astype(np.int64)
    parity = pair_parity.astype(bool)
    parent = np.arange(num_faces)
    flip = np.zeros(num_faces, bool)  # relative to the parent: to the root between rounds
    ea, eb, ep = a, b, parity
    while True:
        ra, rb = parent[ea], parent[eb]
        live = ra != rb
        ea, eb, ep, ra, rb = ea[live], eb[live], ep[live], ra[live], rb[live]
        if len(ea) == 0:
            break
        between = flip[ea] ^ flip[eb] ^ ep  # the flip of one root relative to the other
        low, high = np.minimum(ra, rb), np.maximum(ra, rb)
        # each higher root's pair to the lowest root, the first such pair: the smallest key
        # low * pairs + pair, found in one pass where sorting the pairs by (high, low) would
        # order them all
        pairs = len(ea)
        best = np.full(num_faces, num_faces * pairs, np.int64)
        np.minimum.at(best, high, low * pairs + np.arange(pairs))
        first = best[best < num_faces * pairs] % pairs
        parent[high[first]] = low[first]
        flip[high[first]] = between[first]
        parent = _to_roots(parent, flip)
    if np.any(flip[a] ^ flip[b] ^ parity):
        return None
    # roots only ever hang under lower ones: each component's root is its lowest face
    root = parent == np.arange(num_faces)
    return flip, (np.cumsum(root) - 1)[parent]


def _orient_searched(
    num_faces: int, pair_faces: np.ndarray, pair_parity: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``_orient`` by a breadth-first search over manifold edges: it starts from the
    lowest-index face of every component at once and expands whole frontiers; a face takes its
    flip from the parent that first reaches it, so on non-orientable surfaces the leftover
    inconsistency sits on non-tree edges.
    """
    lo = np.minimum(pair_faces[:, 0], pair_faces[:, 1])
    hi = np.maximum(pair_faces[:, 0], pair_faces[:, 1])
    # scipy loads here, not with the package: only the object-space method needs it
    from scipy import sparse
    from scipy.sparse import csgraph

    graph = sparse.csr_matrix(
        (np.ones(2 * len(lo), np.int8), (np.concatenate([lo, hi]), np.concatenate([hi, lo]))),
        shape=(num_faces, num_faces),
    )
    _, component = csgraph.connected_components(graph, directed=False)
    if graph.nnz < 2 * len(lo):
        # Duplicate triangles share several edges (the constructor summed them): one parity per
        # face pair, its first, so that each face has one parity towards its parent.
        _, keep, _ = unique_first(lo * num_faces + hi)
        lo, hi, pair_parity = lo[keep], hi[keep], pair_parity[keep]

    # Breadth-first from the lowest face of every component at once: a face's distance from
    # its start comes from one search in scipy (from a node joined to every start), its parent
    # is its lowest-numbered neighbour one step nearer (the frontier order of a level-by-level
    # search), and its flip the parities along its parents, summed by pointer jumping.
    starts = unique_first(component)[1]
    root = num_faces
    source = np.concatenate([lo, hi, np.full(len(starts), root)])
    target = np.concatenate([hi, lo, starts])
    # the face pairs' graph with the root's row of starts added, in place of sorting the
    # pairs into a second matrix
    reach = sparse.csr_matrix(
        (
            np.r_[graph.data, np.ones(len(starts), np.int8)],
            np.r_[graph.indices, starts],
            np.r_[graph.indptr, graph.indptr[-1] + len(starts)],
        ),
        shape=(num_faces + 1, num_faces + 1),
    )
    distance = _distances(reach, root)[:num_faces]
    near = distance[source[: 2 * len(lo)]] == distance[target[: 2 * len(lo)]] - 1.0
    child, parent_of = target[: 2 * len(lo)][near], source[: 2 * len(lo)][near]
    parent = np.arange(num_faces)
    lowest = np.full(num_faces, num_faces)
    np.minimum.at(lowest, child, parent_of)
    has_parent = lowest < num_faces
    parent[has_parent] = lowest[has_parent]
    tree = parent_of == parent[child]
    flipped = np.zeros(num_faces, dtype=bool)
    flipped[child[tree]] = np.concatenate([pair_parity, pair_parity])[near][tree]
    _to_roots(parent, flipped)
    return flipped, component.astype(np.int64)


def _to_roots(parent: np.ndarray, flip: np.ndarray) -> np.ndarray:
    """Pointer jumping over a forest: each node's parent made its root, returned, and ``flip``
    (modified in place) made each node's flip relative to its root (the xor along the way)."""
    while True:
        above = parent[parent]
        if np.array_equal(above, parent):
            return parent
        flip ^= flip[parent]
        parent = above


def _distances(reach, root: int) -> np.ndarray:
    """(N,) float64 breadth-first distances of every node of the sparse graph ``reach`` from
    ``root`` (inf where it does not reach): ``csgraph.shortest_path(reach, method="D",
    unweighted=True, indices=root)``, from one breadth-first search, faster."""
    from scipy.sparse import csgraph

    order, predecessor = csgraph.breadth_first_order(reach, root, directed=True, return_predecessors=True)
    position = np.empty(reach.shape[0], np.int64)
    position[order] = np.arange(len(order))
    # the search appends each node's new neighbours in turn, so the positions of the nodes'
    # parents rise along the order, and each level ends where the last one's children do
    parent = position[predecessor[order[1:]]]
    ends = [1]
    while ends[-1] < len(order) and len(ends) < _MAX_LEVELS:
        ends.append(1 + int(np.searchsorted(parent, ends[-1])))
    if ends[-1] < len(order):  # a long strip of faces: a search a level would take longer
        return csgraph.shortest_path(reach, method="D", unweighted=True, indices=root)
    distance = np.full(reach.shape[0], np.inf)
    distance[order] = np.repeat(np.arange(len(ends), dtype=np.float64), np.diff(np.r_[0, ends]))
    return distance


def build_adjacency(positions: np.ndarray, faces: np.ndarray, weld_tol: float | None = None) -> Adjacency:
    """Weld a triangle soup, build its edge connectivity and make its winding consistent.

    This is the view-independent preprocessing of the object-space silhouette method; time it
    separately from the per-frame :func:`blueprint.silhouette.classify_edges`.

    Parameters
    ----------
    positions : np.ndarray
        (V, 3) float vertex positions.
    faces : np.ndarray
        (F, 3) integer vertex indices.
    weld_tol : float, optional
        Passed to :func:`weld` as `tol`.

    Returns
    -------
    Adjacency
        The welded, connected and oriented mesh.
    """
    return connect(*weld(positions, faces, weld_tol))


def connect(positions: np.ndarray, faces: np.ndarray) -> Adjacency:
    """Edge connectivity and consistent winding of a mesh whose topology is already known: the
    faces' indices say which corners are one vertex, and nothing is welded (a mesh torn along
    duplicated vertices stays torn).

    Parameters
    ----------
    positions : np.ndarray
        (V, 3) float vertex positions.
    faces : np.ndarray
        (F, 3) integer vertex indices into `positions`.

    Returns
    -------
    Adjacency
        The connected and oriented mesh; its `positions` are the given ones, as float64.
    """
    positions = np.asarray(positions, dtype=np.float64)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    num_faces, num_vertices = len(faces), max(len(positions), 1)

    # Half-edge k of face f runs from corner k to corner k + 1.
    start = faces.reshape(-1)
    end = faces[:, [1, 2, 0]].reshape(-1)
    # A face with a repeated index is a line or a point: it bounds nothing, so its edges
    # would only add false borders and break the two-face count of real edges.
    proper = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
    if proper.all():
        half_face = None  # half-edge h of face h // 3
    else:
        half_face = np.repeat(np.arange(num_faces, dtype=np.int64), 3)
        proper = np.repeat(proper, 3)
        start, end, half_face = start[proper], end[proper], half_face[proper]
    del proper

    key = np.minimum(start, end)
    key *= num_vertices
    key += np.maximum(start, end)
    # half-edges come in face order, so one stable sort by edge orders them by edge, then face
    order = stable_argsort(key)
    sorted_key = key[order]
    del key
    new_edge = np.ones(len(sorted_key), bool)
    new_edge[1:] = sorted_key[1:] != sorted_key[:-1]
    keys = sorted_key[new_edge]
    del sorted_key
    edges = np.empty((len(keys), 2), np.int64)
    np.floor_divide(keys, num_vertices, out=edges[:, 0])
    np.remainder(keys, num_vertices, out=edges[:, 1])
    del keys
    edge_faces = np.empty((len(order), 2), np.int64)
    np.subtract(np.cumsum(new_edge), 1, out=edge_faces[:, 0])
    if half_face is None:
        np.floor_divide(order, 3, out=edge_faces[:, 1])
    else:
        np.take(half_face, order, out=edge_faces[:, 1])

    # Manifold edges: exactly two incidences, adjacent after sorting by edge.
    starts = np.flatnonzero(new_edge)
    del new_edge
    count = np.diff(np.r_[starts, len(order)])
    manifold = order[np.repeat(count == 2, count)]
    del starts, count, order
    first, second = manifold[::2], manifold[1::2]
    same_direction = start[first] == start[second]
    pair_faces = np.stack([first, second], axis=1)
    if half_face is None:
        pair_faces //= 3
    else:
        pair_faces = half_face[pair_faces]
    flipped, component = _orient(num_faces, pair_faces, same_direction)
    faces = np.where(flipped[:, None], faces[:, [0, 2, 1]], faces)

    cross = indexed_cross(positions, faces)
    area2 = row_norm(cross)
    # squared edge lengths summed coordinate by coordinate, x then y then z (NumPy's reductions
    # over a short axis are slow), without the faces' (F, 3, 3) corners
    length2 = [None, None, None]
    for k in range(3):
        column = positions[:, k]
        corner = [column[faces[:, j]] for j in range(3)]
        for e, (a, b) in enumerate(((0, 1), (1, 2), (2, 0))):
            d = corner[b] - corner[a]
            d *= d
            length2[e] = d if length2[e] is None else length2[e] + d
    longest2 = np.maximum(np.maximum(length2[0], length2[1]), length2[2])
    del length2
    good = area2 > _DEGENERATE_REL_AREA * longest2
    normals = np.zeros_like(cross)
    normals[good] = cross[good] / area2[good, None]
    return Adjacency(
        positions=positions,
        faces=faces,
        flipped=flipped,
        edges=edges,
        edge_faces=edge_faces,
        component=component,
        face_normals=normals,
    )
