"""Corner normals smoothed within a crease angle, robust to soups and inconsistent winding."""

from __future__ import annotations

from functools import partial

import numpy as np

from blueprint import parallel
from blueprint.columns import indexed_cross, row_norm, square_blocks, used_bounds
from blueprint.scene.weld import check_mesh, connected_components_of, weld_groups
from blueprint.sorting import SortedKeys, bucketed, stable_argsort

# Vertices with more faces than this (fans of cylinder caps, cones) keep flat normals: their
# smoothing would cost degree² pairs, and such fans are planar or pointed anyway.
_MAX_DEGREE = 64
# Around a vertex whose faces' normals all lie within this many degrees of the sum of their area
# normals, no two are 90 degrees apart (``corner_normals``).
_CONE = 44.0
# Faces a thread reads at a time: its blocks' temporaries stay small, however many threads.
_ROWS = 1 << 16
# Vertex ranges the vertices' sums are cut into at most (a byte's values: ``sorting.bucketed``),
# each of some ``_SUM_CORNERS`` corners at least (``_vertex_sums``): a range's sum holds some 40
# bytes a corner.
_SUM_RANGES = 256
_SUM_CORNERS = 1 << 16
# Pairs of corners around a vertex smoothed at a time (``corner_normals``): some 100 bytes each.
_PAIR_BLOCK = 1 << 18
# Corners of a block (vertices times their degree) from which their sums are made a corner at
# a time (``_sums_by_rows``), not as one table: each step is a few calls.
_ROWS_FROM = 1024
# A run of crease edges touching no border is a scan's noise while it has fewer edges than this
# and is shorter than ``_RUN_REL`` of the model's diagonal (``noise_creases``): the creases of
# made things run on, and where they are short the mesh is coarse, so they have few edges yet
# are long.
_RUN_EDGES = 8
_RUN_REL = 0.05


def weld_ids(positions: np.ndarray, faces: np.ndarray, rel_tol: float = 1e-6) -> np.ndarray:
    """(F, 3) int64: vertex ids where vertices at the same position (within ``rel_tol`` of the
    bounding-box diagonal of the vertices the faces use) share an id, numbered in the order of
    their first vertices, so triangle soups smooth like indexed meshes."""
    return _welded(positions, faces, rel_tol).astype(np.int64)


def _welded(
    positions: np.ndarray,
    faces: np.ndarray,
    rel_tol: float = 1e-6,
    distinct: bool = False,
    diagonal: float | None = None,
) -> np.ndarray:
    """``weld_ids`` as int32, which halves what the corners' ids take; ``distinct``: the
    positions are distinct already (``weld_groups``); ``diagonal``: ``_diagonal``'s, where the
    caller knows it."""
    positions, faces = check_mesh(positions, faces)
    if len(faces) == 0:
        return np.zeros((0, 3), np.int32)
    diagonal = _diagonal(positions, faces) if diagonal is None else diagonal
    group, _ = weld_groups(positions, diagonal * rel_tol, distinct)
    welded = np.empty(faces.shape, np.int32)
    parallel.take(group.astype(np.int32), faces, welded)
    return welded


def crease_vertices(
    welded: np.ndarray,
    unit: np.ndarray,
    crease_angle: float,
    positions: np.ndarray,
    faces: np.ndarray,
    diagonal: float | None = None,
) -> np.ndarray:
    """(V,) bool: the welded vertex lies on a crease (an edge whose two faces' normals differ,
    up to sign, by more than ``crease_angle`` degrees, unless it is in a run of noise,
    ``noise_creases``), a border or a non-manifold edge.

    Parameters
    ----------
    welded : (F, 3) int
        Welded vertex ids per face (``weld_ids``).
    unit : (F, 3) float
        Unit face normals (zero for degenerate faces).
    crease_angle : float
        Degrees.
    positions : (P, 3) float
        The vertices ``faces`` index: the crease edges' lengths.
    faces : (F, 3) int
    diagonal : float, optional
        ``_diagonal`` of the positions the faces use, where the caller knows it.
    """
    vertices = int(welded.max(initial=-1)) + 1
    # edge k of a face joins its corners k and k + 1; its key is lo * vertices + hi
    key = np.empty((len(welded), 3), np.int64)
    parallel.run(partial(_edge_keys, welded, vertices, key), len(welded))
    edges = SortedKeys(key.reshape(-1))
    del key
    # edges of two faces: runs of two equal keys (bool masks: run starts and lengths would take
    # eight bytes an edge each)
    same = np.zeros(edges.length + 1, bool)
    parallel.run(partial(_same_keys, edges, same), edges.length - 1)
    paired = np.empty(edges.length - 1, bool)
    parallel.run(partial(_runs_of_two, same, paired), len(paired))
    # the pairs' crease test as a mask over the edges: their positions would take eight bytes
    # a pair
    sharp_edge = np.zeros(len(paired), bool)
    limit = np.cos(np.radians(crease_angle)) - 1e-9
    parallel.run(partial(_pair_sharp, unit, edges, paired, limit, sharp_edge), len(paired))
    sharp_pair = parallel.flatnonzero(sharp_edge)
    del sharp_edge
    # the crease edges' lengths, from the first face of each
    length = _edge_lengths(positions, faces, edges.order(sharp_pair))
    crease = edges.keys(sharp_pair)
    # every other edge is a border or a non-manifold edge
    found = parallel.run(partial(_unpaired, paired), edges.length)
    del same, paired
    open_edges = edges.keys(np.concatenate(found))
    del found, edges
    sharp = np.zeros(vertices, bool)
    sharp[open_edges // vertices] = True
    sharp[open_edges % vertices] = True
    crease = np.stack([crease // vertices, crease % vertices], axis=1)
    diagonal = _diagonal(positions, faces) if diagonal is None else diagonal
    noise = noise_creases(crease, sharp, length, diagonal)
    sharp[crease[~noise].ravel()] = True
    return sharp


def _edge_lengths(positions: np.ndarray, faces: np.ndarray, corner: np.ndarray) -> np.ndarray:
    """(E,) float64: the lengths of the edges from each ``corner`` (of the faces, three a face)
    to the next corner of its face, a block at a time: their ends alone in float64."""
    corner_vertex = np.asarray(faces).reshape(-1)
    positions = np.asarray(positions)
    length = np.empty(len(corner))

    def measured(lo: int, hi: int) -> None:
        for start in range(lo, hi, _ROWS):
            at = corner[start : min(start + _ROWS, hi)]
            after = at - at % 3 + (at % 3 + 1) % 3
            ends = np.take(positions, corner_vertex[after], axis=0).astype(np.float64)
            ends -= np.take(positions, corner_vertex[at], axis=0)
            length[start : start + len(at)] = row_norm(ends)

    parallel.run(measured, len(corner))
    return length


def _edge_keys(welded: np.ndarray, vertices: int, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]`` (F, 3) int64: edge ``k`` of each face, from its corner ``k`` to ``k + 1``,
    keyed ``lo * vertices + hi`` of its welded vertices."""
    for start in range(lo, hi, _ROWS):
        rows = slice(start, min(start + _ROWS, hi))
        for k in range(3):
            a, b = welded[rows, k], welded[rows, (k + 1) % 3]
            np.multiply(np.minimum(a, b), vertices, out=out[rows, k], dtype=np.int64)
            out[rows, k] += np.maximum(a, b)


def _same_keys(edges: SortedKeys, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[1 + i]`` for ``i`` from lo to hi: the sorted keys ``i`` and ``i + 1`` of ``edges``
    are equal."""
    for start in range(lo, hi, _ROWS):
        stop = min(start + _ROWS, hi)
        run = edges.keys(slice(start, stop + 1))
        np.equal(run[1:], run[:-1], out=out[start + 1 : stop + 1])


def _runs_of_two(same: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[i]`` for ``i`` from lo to hi: sorted edges ``i`` and ``i + 1`` are a run of two
    equal keys (``same[1 + i]``: keys ``i`` and ``i + 1`` are equal)."""
    np.greater(same[lo + 1 : hi + 1], same[lo:hi], out=out[lo:hi])
    out[lo:hi] &= ~same[lo + 2 : hi + 2]


def _unpaired(paired: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """The sorted edges from lo to hi in no run of two (``paired[i]``: edges ``i`` and ``i + 1``
    are one), ascending."""
    alone = np.ones(hi - lo, bool)
    ahead = min(hi, len(paired))
    alone[: ahead - lo] &= ~paired[lo:ahead]
    behind = max(lo, 1)
    alone[behind - lo :] &= ~paired[behind - 1 : hi - 1]
    return np.flatnonzero(alone) + lo


def _pair_sharp(
    unit: np.ndarray, edges: SortedKeys, paired: np.ndarray, limit: float, out: np.ndarray, lo: int, hi: int
) -> None:
    """``out[i]`` for the ``paired`` sorted edges ``i`` from lo to hi: the faces of edges ``i``
    and ``i + 1`` (corners, three a face) have ``unit`` normals whose cosine is below ``limit``
    up to sign; a block at a time, so that no cosine of every edge is held."""
    for start in range(lo, hi, _ROWS):
        at = np.flatnonzero(paired[start : min(start + _ROWS, hi)])
        at += start
        one, other = (np.take(unit, edges.order(at + k) // 3, axis=0) for k in (0, 1))
        out[at] = np.abs(np.einsum("ij,ij->i", one, other)) < limit


def _diagonal(positions: np.ndarray, faces: np.ndarray) -> float:
    """The diagonal of the bounding box of the vertices the faces use (1 where it is 0)."""
    bounds = used_bounds(positions, faces)
    return 1.0 if bounds is None else diagonal_of(bounds)


def diagonal_of(bounds: np.ndarray) -> float:
    """The diagonal of (2, 3) ``bounds`` (``Model.bounds``), 1 where it is 0."""
    return float(np.linalg.norm(bounds[1] - bounds[0])) or 1.0


def noise_creases(crease: np.ndarray, anchored: np.ndarray, length: np.ndarray, size: float) -> np.ndarray:
    """(E,) bool: which of the crease edges are a scan's noise: in a run of crease edges (those
    joined end to end, junctions included) that touches no ``anchored`` vertex (on a border or
    a non-manifold edge), has fewer than ``_RUN_EDGES`` edges and is shorter than ``_RUN_REL``
    of ``size``. Noise lifts single edges and short runs of them past the crease angle; a crease
    of a made thing runs on into others or to a border, and is long where it has few edges.

    Parameters
    ----------
    crease : (E, 2) int
        The crease edges' (welded) vertex indices.
    anchored : (V,) bool
        Vertices on a border or non-manifold edge.
    length : (E,) float
        The crease edges' lengths.
    size : float
        The model's size (its bounding-box diagonal), in the units of ``length``.
    """
    if len(crease) == 0:
        return np.zeros(0, bool)
    # runs over the crease edges' own vertices only: the rest of the mesh takes no part; the
    # vertices numbered in order by a table over their ids (``np.unique``'s numbers, unsorted)
    present = np.zeros(len(anchored), bool)
    present[crease] = True
    used = np.flatnonzero(present)
    rank = np.cumsum(present, dtype=np.int64) - 1
    local = rank[crease]
    del present, rank
    run = connected_components_of(np.arange(len(used)), local[:, 0], local[:, 1])[local[:, 0]]
    edges = np.bincount(run)
    total = np.bincount(run, np.asarray(length, np.float64))
    held = np.zeros(len(edges), bool)
    held[run[anchored[used[local[:, 0]]] | anchored[used[local[:, 1]]]]] = True
    noise = ~held & (edges < _RUN_EDGES) & (total < _RUN_REL * size)
    return noise[run]


def corner_normals(
    positions: np.ndarray,
    faces: np.ndarray,
    crease_angle: float = 30.0,
    topology: dict | None = None,
    distinct: bool = False,
    diagonal: float | None = None,
) -> np.ndarray:
    """Normal per triangle corner: the area-weighted mean of the normals of the faces around the
    corner's vertex that lie within ``crease_angle`` degrees of the corner's face; at a vertex
    on no crease edge (``crease_vertices``), of all the faces around it.

    A scan's noise tilts faces that share only a vertex by more than the crease angle while
    every edge between them stays below it; splitting the normal there would draw a crease
    fragment, a speck, at each such vertex. A crease is an edge: where no edge is one, the
    surface is smooth; nor is a short run of crease edges touching no border or non-manifold
    edge (``noise_creases``): the creases of made things run on. Vertices on borders and
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
    topology : dict, optional
        Kept with the mesh (by ``scene.prepare``): the welded vertex ids (``"welded"``, (F, 3)
        int32) and the crease vertices (``("sharp", crease_angle)``, (V,) bool) are read from
        it where it holds them, and left in it where it does not: they take the sorts.
    distinct : bool
        The positions are distinct already (a soup's, ``Model.soup``): the weld looks for
        close ones alone (``weld_groups``).
    diagonal : float, optional
        Of the bounding box of the vertices the faces use (``diagonal_of`` of ``Model.bounds``),
        where the caller knows it: the weld's tolerance and the size a run of noise is
        measured against.

    Returns
    -------
    (F, 3, 3) float32
        Unit normal for corner ``j`` of face ``i`` at ``[i, j]``.
    """
    topology = {} if topology is None else topology
    faces = np.asarray(faces)
    smoothed = crease_angle > 0 and len(faces) > 0
    welded = topology.get("welded")
    if welded is None and smoothed:
        # welded before the faces' normals are made: the weld's temporaries never lie beside them
        diagonal = _diagonal(positions, faces) if diagonal is None else diagonal
        welded = topology["welded"] = _welded(positions, faces, distinct=distinct, diagonal=diagonal)
    area_normals = indexed_cross(np.asarray(positions), faces)
    unit = np.empty_like(area_normals)
    parallel.run(partial(_unit_rows, area_normals, unit), len(faces))
    if not smoothed:
        return np.repeat(unit.astype(np.float32)[:, None, :], 3, axis=1)
    sharp = topology.get(("sharp", float(crease_angle)))
    if sharp is None:
        sharp = topology[("sharp", float(crease_angle))] = crease_vertices(
            welded, unit, crease_angle, positions, faces, diagonal
        )
    vertices = len(sharp)
    vertex = welded.reshape(-1)
    # Where no pair of the faces around a vertex is told apart (no crease there, and every two
    # faces' normals less than 90 degrees apart, so none counts with a flipped sign), each of
    # its corners sums the area normals of all of them, in corner order as the pairs would.
    summed, degree = _vertex_sums(vertex, area_normals, vertices)
    norm = np.empty(vertices)
    parallel.run(partial(_row_norms, summed, norm), vertices)
    shared = ~sharp & (degree <= _MAX_DEGREE) & (norm > 0) & _within_cone(welded, unit, summed, norm)
    parallel.run(partial(_divided_where, summed, norm, shared), vertices)
    del norm
    vertex_normals = summed.astype(np.float32)
    del summed  # before the corners' normals are made
    result = np.empty((len(faces), 3, 3), np.float32)
    corners = result.reshape(-1, 3)
    parallel.take(vertex_normals, vertex, corners)
    del vertex_normals
    # the corners of the other vertices: their faces' own normals where the vertex has too
    # many, else from their pairs
    crowded = ~shared & (degree > _MAX_DEGREE)
    if crowded.any():
        flat = parallel.chosen_at(crowded, vertex)
        corners[flat] = np.take(unit, flat // 3, axis=0)
        del flat
    paired = parallel.chosen_at(~shared & ~crowded, vertex)
    if len(paired):
        _pairwise(paired, vertex[paired], area_normals, unit, sharp, crease_angle, corners)
    return result


def _vertex_sums(vertex: np.ndarray, area: np.ndarray, vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """Of the corners' ``vertex`` (3F,) among ``vertices``: (V, 3) the sum of the ``area`` (F, 3)
    normals of each vertex's faces, each adding its corners in order from zero, as one
    ``bincount`` would, bit for bit; and (V,) its corners. By ``bincount`` (which lets go of
    the GIL, where ``np.add.at`` holds it and threads would wait on each other), a range of
    vertices at a time: the corners put in order of their vertices' ranges
    (``sorting.bucketed``), then each range's corners summed (``_range_sums``), the ranges side
    by side on the pool."""
    summed = np.empty((vertices, 3))
    degree = np.empty(vertices, np.int64)
    wanted = min(_SUM_RANGES, max(1, len(vertex) // _SUM_CORNERS))
    shift = 0
    while ((vertices - 1) >> shift) + 1 > wanted:
        shift += 1
    ranges = ((vertices - 1) >> shift) + 1 if vertices else 0
    if ranges <= 1:
        corners = np.arange(len(vertex), dtype=np.int64)
        _summed_range(vertex, area, corners, 0, vertices, summed, degree)
        return summed, degree
    order, ends = bucketed(vertex, shift, ranges)
    parallel.run(partial(_range_sums, vertex, area, shift, order, ends, summed, degree), ranges, min_block=1)
    return summed, degree


def _range_sums(
    vertex: np.ndarray,
    area: np.ndarray,
    shift: int,
    order: np.ndarray,
    ends: np.ndarray,
    summed: np.ndarray,
    degree: np.ndarray,
    lo: int,
    hi: int,
) -> None:
    """``_vertex_sums`` of the vertex ranges from lo to hi: each range's corners, in corner
    order where they end in ``order`` (``ends``), summed."""
    for r in range(lo, hi):
        corners = order[ends[r - 1] if r else 0 : ends[r]]
        first = r << shift
        _summed_range(vertex, area, corners, first, min(len(degree), first + (1 << shift)), summed, degree)


def _summed_range(
    vertex: np.ndarray,
    area: np.ndarray,
    corners: np.ndarray,
    first: int,
    last: int,
    summed: np.ndarray,
    degree: np.ndarray,
) -> None:
    """``summed`` and ``degree`` of the vertices from ``first`` to ``last``, from their
    ``corners``, in order."""
    at = np.take(vertex, corners).astype(np.intp)
    at -= first
    rows = np.take(area, corners // 3, axis=0)
    degree[first:last] = np.bincount(at, minlength=last - first)
    for axis in range(3):
        summed[first:last, axis] = np.bincount(at, rows[:, axis], minlength=last - first)


def _sums_by_table(
    face: np.ndarray, unit: np.ndarray, area: np.ndarray, on_crease: np.ndarray, cos_crease: float
) -> np.ndarray:
    """(n * d, 3): for the corners (n, d) of n vertices of degree d on ``face``, the sum of the
    ``area`` normals of the faces around each corner's vertex that count for it (``_pairwise``),
    as a (n, d, d) table of the weights and one product: few calls, for few vertices."""
    u = np.take(unit, face, axis=0)  # (n, d, 3)
    cos = u[:, :, None, 0] * u[:, None, :, 0] + u[:, :, None, 1] * u[:, None, :, 1]
    cos += u[:, :, None, 2] * u[:, None, :, 2]
    weight = np.sign(cos)
    weight[(np.abs(cos) < cos_crease) & on_crease[:, None, None]] = 0.0
    return np.matmul(weight, np.take(area, face, axis=0)).reshape(-1, 3)


def _sums_by_rows(
    face: np.ndarray, unit: np.ndarray, area: np.ndarray, on_crease: np.ndarray, cos_crease: float
) -> np.ndarray:
    """``_sums_by_table``'s sums from each corner's normals as rows (d, 3, n), a corner at a
    time: over many vertices the table's reductions along its short rows cost NumPy half as
    much again. The weights are -1, 0 or 1, so each sum is exact but for the order of its
    additions, here the faces' corner order."""
    u, area = (np.take(v, face.T, axis=0).transpose(0, 2, 1).copy() for v in (unit, area))
    d = len(u)
    summed = np.empty((d, 3, face.shape[0]))
    for i in range(d):
        cos = u[i, 0] * u[:, 0] + u[i, 1] * u[:, 1]
        cos += u[i, 2] * u[:, 2]
        weight = np.sign(cos)
        weight[(np.abs(cos) < cos_crease) & on_crease] = 0.0
        np.sum(weight[:, None, :] * area, axis=0, out=summed[i])
    return summed.transpose(2, 0, 1).reshape(-1, 3)


def _faces_of_corners(corners: np.ndarray, lo: int, hi: int) -> None:
    """``corners[lo:hi]`` (three a face) to their faces, in place."""
    corners[lo:hi] //= 3


def _unit_rows(rows: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]``: ``rows[lo:hi]`` (N, 3) over their lengths (zero rows stay zero)."""
    for start in range(lo, hi, _ROWS):
        block = slice(start, min(start + _ROWS, hi))
        length = row_norm(rows[block])
        np.divide(rows[block], np.where(length > 0, length, 1.0)[:, None], out=out[block])


def _divided_where(rows: np.ndarray, by: np.ndarray, where: np.ndarray, lo: int, hi: int) -> None:
    """``rows[lo:hi]`` (N, 3) over ``by[lo:hi]`` in place where ``where``: no gathered copies of
    the rows chosen, as ``rows[where] /= ...`` makes."""
    np.divide(rows[lo:hi], by[lo:hi, None], out=rows[lo:hi], where=where[lo:hi, None])


def _row_norms(rows: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    out[lo:hi] = row_norm(rows[lo:hi])


def _within_cone(welded: np.ndarray, unit: np.ndarray, axis: np.ndarray, length: np.ndarray) -> np.ndarray:
    """(V,) bool: every face around the vertex has a unit normal within ``_CONE`` degrees of the
    vertex's ``axis`` (V, 3) of ``length`` (V,) (degenerate faces never are), so any two of
    them lie within twice that, less than 90 degrees apart: their cosine, computed, is
    positive."""
    outside = np.zeros(len(axis), bool)
    limit = np.cos(np.radians(_CONE)) * length

    def marked(lo: int, hi: int) -> None:
        # only True is written, by any thread, so the marks do not depend on their order
        for start in range(lo, hi, _ROWS):
            rows = slice(start, min(start + _ROWS, hi))
            for j in range(3):
                at = welded[rows, j]
                dot = np.einsum("ij,ij->i", unit[rows], np.take(axis, at, axis=0))
                outside[at[dot <= limit[at]]] = True

    parallel.run(marked, len(welded))
    return ~outside


def _pairwise(
    corners: np.ndarray,
    vertex: np.ndarray,
    area_normals: np.ndarray,
    unit: np.ndarray,
    sharp: np.ndarray,
    crease_angle: float,
    out: np.ndarray,
) -> None:
    """The normals of ``corners`` (all the corners of their vertices, ``vertex``) from every
    ordered pair of corners around a vertex: the other corner's face counts where it lies
    within the crease angle of this corner's face, or the vertex is on no crease, with the
    sign of their cosine; where that sum is zero, the corner's own face's. Written into ``out``
    (3F, 3) float32."""
    order = stable_argsort(vertex)
    corner_face = parallel.taken(corners, order)
    parallel.run(partial(_faces_of_corners, corner_face), len(corner_face))
    sorted_vertex = parallel.taken(vertex, order)
    # in order, a vertex's first corner is the one that passes every vertex before it
    starts = parallel.flatnonzero(parallel.rises(sorted_vertex))
    degree = np.diff(np.r_[starts, len(order)])
    cos_crease = np.cos(np.radians(crease_angle)) - 1e-9
    # the vertices of one degree d together: each its faces' d x d cosines and the sum of its
    # faces' area normals by each corner's, a block of vertices at a time (their pairs all at
    # once would take up to _MAX_DEGREE times the corners); each corner is written by one block
    work = square_blocks(degree, _PAIR_BLOCK)

    def blocks(lo: int, hi: int) -> None:
        for d, chosen in work[lo:hi]:
            first = starts[chosen]
            at = first[:, None] + np.arange(d)  # (n, d): the vertices' corners, in corner order
            face = corner_face[at]
            summing = _sums_by_rows if len(first) * d >= _ROWS_FROM else _sums_by_table
            summed = summing(face, unit, area_normals, sharp[sorted_vertex[first]], cos_crease)
            norm = row_norm(summed)
            ok = norm > 0
            summed /= np.where(ok, norm, 1.0)[:, None]
            own = np.take(unit, face.reshape(-1), axis=0)  # each corner's own face's
            out[corners[order[at.reshape(-1)]]] = np.where(ok[:, None], summed, own).astype(np.float32)

    parallel.run(blocks, len(work), min_block=1)
