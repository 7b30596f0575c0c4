"""Preprocessing of a triangle soup: vertex welding (``blueprint.scene.weld``), edge
connectivity, consistent winding.

This is the "CPU-Preprocess" stage of the conventional object-space silhouette method
(weld, connect, orient); everything here depends only on the geometry, not on the view.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from blueprint import parallel
from blueprint.columns import column_cross, row_norm
from blueprint.scene.weld import weld
from blueprint.sorting import SortedKeys, unique_first

__all__ = ["Adjacency", "build_adjacency", "connect", "weld"]

# Faces whose doubled area is below this fraction of their longest edge squared get a zero
# normal: their cross product is rounding noise and its direction would be arbitrary.
_DEGENERATE_REL_AREA = 1e-12
# Levels of the winding search's breadth-first distances found one at a time, at most.
_MAX_LEVELS = 4096
# Faces whose half-edge keys and normals a thread makes at a time.
_BLOCK = 1 << 15
# Sorted half-edges a thread reads at a time.
_ROWS = 1 << 16


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
    if merged is not None:
        return merged
    return _orient_searched(num_faces, np.asarray(pair_faces, np.int64), pair_parity)


def _orient_merged(
    num_faces: int, pair_faces: np.ndarray, pair_parity: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """``_orient`` by merging trees of faces, with NumPy alone (scipy, which the search needs,
    is slow to import): every round, each tree's root hangs under the lowest root that a pair
    joins it to and the trees are flattened by pointer jumping; then the roots left are
    numbered afresh and the pairs rewritten between them, so that a round costs what its roots
    and pairs number, not what the faces do (a few rounds on real meshes, each with about half
    the pairs of the one before). Each face's flip relative to its component's root is made
    last, from the rounds' hangings in reverse. None where a pair within one tree disagrees
    with the flips found: a surface that cannot be wound consistently, whose leftover
    inconsistency the search places."""
    index = _index_type(max(num_faces, len(pair_faces)))
    # the pairs between roots, numbered among the roots: u and v, and q where their flips differ
    u = pair_faces[:, 0].astype(index)
    v = pair_faces[:, 1].astype(index)
    q = np.asarray(pair_parity, bool)
    parent = np.arange(num_faces, dtype=index)
    flip = np.zeros(num_faces, bool)  # relative to the parent
    face = None  # each root's face; None while every face is one
    roots = num_faces
    hung = []
    while len(u):
        low, high = np.minimum(u, v), np.maximum(u, v)
        lowest = np.full(roots, roots, index)
        np.minimum.at(lowest, high, low)
        # a pair from each higher root to its lowest, whose parity is the flip between them
        chosen = np.empty(roots, index)
        hit = np.flatnonzero(low == lowest[high])
        chosen[high[hit]] = hit
        del low, high, hit
        hooked = np.flatnonzero(lowest < roots)
        up = np.arange(roots, dtype=index)
        up[hooked] = lowest[hooked]
        turn = np.zeros(roots, bool)
        turn[hooked] = q[chosen[hooked]]
        del lowest, chosen
        up = _to_roots(up, turn)
        q = q ^ turn[u] ^ turn[v]
        kept = up == np.arange(roots, dtype=index)
        number = np.cumsum(kept, dtype=index)
        number -= 1
        number = number[up]  # each root's number after the round, its tree's root's
        u, v = number[u], number[v]
        inside = u == v
        if q[inside].any():
            return None
        outside = ~inside
        u, v, q = u[outside], v[outside], q[outside]
        hooked_face = hooked if face is None else face[hooked]
        parent[hooked_face] = up[hooked] if face is None else face[up[hooked]]
        flip[hooked_face] = turn[hooked]
        hung.append(hooked_face)
        face = np.flatnonzero(kept) if face is None else face[kept]
        roots = len(face)
    # a round's hung roots hang under roots of its end, which later rounds hung in turn
    for hooked_face in reversed(hung):
        above = parent[hooked_face]
        flip[hooked_face] ^= flip[above]
        parent[hooked_face] = parent[above]
    # roots only ever hang under lower ones: each component's root is its lowest face
    root = parent == np.arange(num_faces, dtype=index)
    return flip, (np.cumsum(root) - 1)[parent]


def _index_type(count: int) -> type:
    """int32 for indices below ``count`` where they fit (half the memory to read), else int64."""
    return np.int32 if count <= np.iinfo(np.int32).max else np.int64


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


def _edge_keys(
    faces: np.ndarray, num_vertices: int, key: np.ndarray, proper: np.ndarray, lo: int, hi: int
) -> None:
    """``key[3 * lo : 3 * hi]``: each half-edge of faces ``lo`` to ``hi`` keyed ``low * V +
    high`` of its two vertices, and ``proper[lo:hi]`` False, their keys ``(V - 1) * V`` (no
    edge's: its lower vertex is below V - 1), where a face repeats an index."""
    rows = key.reshape(-1, 3)
    for begin in range(lo, hi, _BLOCK):
        block = faces[begin : min(begin + _BLOCK, hi)]
        out = rows[begin : begin + len(block)]
        for k in range(3):
            a, b = block[:, k], block[:, (k + 1) % 3]
            column = np.minimum(a, b)
            column *= num_vertices
            column += np.maximum(a, b)
            out[:, k] = column
            proper[begin : begin + len(block)] &= a != b
        improper = ~proper[begin : begin + len(block)]
        if improper.any():
            out[improper] = (num_vertices - 1) * num_vertices


def _key_changes(half: SortedKeys, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[i + 1]``, for ``i`` from ``lo`` to ``hi``: sorted keys ``i + 1`` and ``i`` differ."""
    for begin in range(lo, hi, _ROWS):
        stop = min(begin + _ROWS, hi)
        keys = half.keys(slice(begin, stop + 1))
        np.not_equal(keys[1:], keys[:-1], out=out[begin + 1 : stop + 1])


def _edge_ends(
    half: SortedKeys, at: np.ndarray, num_vertices: int, out: np.ndarray, lo: int, hi: int
) -> None:
    """``out[lo:hi]``: the two vertices, lower first, of the keys ``low * V + high`` sorted at
    positions ``at[lo:hi]``."""
    for begin in range(lo, hi, _ROWS):
        stop = min(begin + _ROWS, hi)
        keys = half.keys(at[begin:stop])
        ends = out[begin:stop]
        np.floor_divide(keys, num_vertices, out=ends[:, 0])
        np.multiply(ends[:, 0], num_vertices, out=ends[:, 1])
        np.subtract(keys, ends[:, 1], out=ends[:, 1])


def _incident_faces(half: SortedKeys, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi, 1]``: the faces of the half-edges sorted at ``lo`` to ``hi``."""
    for begin in range(lo, hi, _ROWS):
        stop = min(begin + _ROWS, hi)
        np.floor_divide(half.order(slice(begin, stop)), 3, out=out[begin:stop, 1])


def _unit_normals(positions: np.ndarray, faces: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]``: the unit normals of faces ``lo`` to ``hi``, zero where a face's doubled
    area is below ``_DEGENERATE_REL_AREA`` of its longest edge squared: ``indexed_cross`` over
    its ``row_norm``, a block at a time, the corners gathered once for both."""
    columns = [positions[:, k] for k in range(3)]
    for begin in range(lo, hi, _BLOCK):
        block = faces[begin : min(begin + _BLOCK, hi)]
        u, v, w = [], [], []
        for column in columns:
            corner = [column[block[:, k]] for k in range(3)]
            u.append(corner[1] - corner[0])
            v.append(corner[2] - corner[0])
            w.append(corner[2] - corner[1])
        cross = column_cross(u, v)
        area2 = row_norm(cross)
        # squared edge lengths summed x, then y, then z; the edge from corner 2 to 0 is -v
        longest2 = None
        for d in (u, w, v):
            length2 = d[0] * d[0]
            length2 += d[1] * d[1]
            length2 += d[2] * d[2]
            longest2 = length2 if longest2 is None else np.maximum(longest2, length2)
        good = area2 > _DEGENERATE_REL_AREA * longest2
        normals = out[begin : begin + len(block)]
        normals[:] = 0.0
        np.divide(cross, area2[:, None], out=normals, where=good[:, None])


def build_adjacency(positions: np.ndarray, faces: np.ndarray, weld_tol: float | None = None) -> Adjacency:
    """Weld a triangle soup, build its edge connectivity and make its winding consistent.

    This is the view-independent preprocessing of the object-space silhouette method; time it
    separately from the per-frame :func:`blueprint.silhouette.classify_edges`.

    Parameters
    ----------
    positions, faces : np.ndarray
        The soup: (V, 3) float vertex positions, (F, 3) integer vertex indices.
    weld_tol : float, optional
        Passed to :func:`weld` as `tol`.

    Returns
    -------
    Adjacency
        The welded, connected and oriented mesh.
    """
    positions, faces = weld(positions, faces, weld_tol)
    return _connected(positions, faces)  # the weld's faces are new: oriented in place


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
    return _connected(positions, np.array(faces, dtype=np.int64).reshape(-1, 3))


def _connected(positions: np.ndarray, faces: np.ndarray) -> Adjacency:
    """``connect`` of (F, 3) int64 ``faces`` that it may reorder in place (the result's)."""
    positions = np.asarray(positions, dtype=np.float64)
    num_faces, num_vertices = len(faces), max(len(positions), 1)

    # Half-edge h runs from corner h % 3 of face h // 3 to its next corner; one stable sort of
    # their edges' keys orders them by edge, then face, and the keys of the half-edges of
    # faces with a repeated index (lines or points: they bound nothing, and their edges would
    # only add false borders and break the two-face count of real edges) sort after the rest.
    key = np.empty(3 * num_faces, np.int64)
    proper = np.ones(num_faces, bool)
    parallel.run(partial(_edge_keys, faces, num_vertices, key, proper), num_faces)
    halves = 3 * int(np.count_nonzero(proper))
    del proper
    # read by position, a block at a time: no array of every sorted key or of the order
    half = SortedKeys(key)
    del key
    new_edge = np.empty(halves + 1, bool)  # and one past the last, for the pairs below
    new_edge[0] = new_edge[halves] = True
    parallel.run(partial(_key_changes, half, new_edge), max(halves - 1, 0))
    at = np.flatnonzero(new_edge[:halves])
    edges = np.empty((len(at), 2), np.int64)
    parallel.run(partial(_edge_ends, half, at, num_vertices, edges), len(at))
    del at
    edge_faces = np.empty((halves, 2), np.int64)
    # the threads write their blocks first: the new array's pages are touched side by side
    parallel.run(partial(_incident_faces, half, edge_faces), halves)
    np.cumsum(new_edge[:halves], out=edge_faces[:, 0])
    edge_faces[:, 0] -= 1

    # Manifold edges: exactly two incidences, adjacent after sorting by edge.
    two = new_edge[:-2] & ~new_edge[1:-1]
    two &= new_edge[2:]
    del new_edge
    at = np.flatnonzero(two)
    del two
    first = half.order(at)
    at += 1
    second = half.order(at)
    del at, half
    start = faces.reshape(-1)
    same_direction = start[first] == start[second]
    pair_faces = np.empty((len(first), 2), _index_type(num_faces))
    np.floor_divide(first, 3, out=pair_faces[:, 0])
    np.floor_divide(second, 3, out=pair_faces[:, 1])
    del first, second, start
    flipped, component = _orient(num_faces, pair_faces, same_direction)
    del pair_faces, same_direction
    turned = np.flatnonzero(flipped)
    faces[turned, 1:] = faces[turned, 2:0:-1]
    del turned
    normals = np.empty((num_faces, 3))
    parallel.run(partial(_unit_normals, positions, faces, normals), num_faces)
    return Adjacency(
        positions=positions,
        faces=faces,
        flipped=flipped,
        edges=edges,
        edge_faces=edge_faces,
        component=component,
        face_normals=normals,
    )
