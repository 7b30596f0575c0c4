"""A model's triangles made ready for the GPU: shared vertices split where their normal or part
differs, and the faces' corners as indices into them.

What the sorts find (the welded vertices, the crease vertices) is kept by the model's content,
so that another model of the same triangles (another view of a file loaded again, a batch)
skips them: some 12 bytes a triangle, where the arrays themselves, 100 bytes a triangle of a
triangle soup, would stay in memory through the drawing that uploaded them. A process that
prepares each model once (the command line's ``render``) keeps none (``topologies_kept``): no
later preparation would read them, and they would stay in memory through its drawing.
"""

from __future__ import annotations

import weakref
from collections import OrderedDict
from collections.abc import Iterator
from contextlib import contextmanager
from functools import partial

import numpy as np

from blueprint import parallel, settings
from blueprint.columns import ranges, square_blocks
from blueprint.scene.model import Model
from blueprint.scene.normals import corner_normals, diagonal_of
from blueprint.sorting import dense_ranks, stable_argsort, unique_first

__all__ = ["VERTEX", "feature_faces", "gpu_arrays", "topologies_kept", "topology"]

# One vertex of the vertex buffer: position, normal (zero without a crease angle), part.
VERTEX = np.dtype([("p", "f4", 3), ("n", "f4", 3), ("part", "i4")])
# Topologies kept, and the bytes they may hold together.
_KEPT = 4
_KEPT_BYTES = settings.MEMORY_BUDGET // 32
# Vertices whose fields are gathered at a time.
_BLOCK = 1 << 16
# A key's corners compared pairwise up to this many (``_pairs_by_normal``), and pairs of them
# compared at a time.
_TABLE_DEGREE = 64
_PAIR_BLOCK = 1 << 18
# Corners of a block (keys times their corners) from which they are compared a corner at a
# time (``_compared_by_rows``), not as one table: each step is a few calls.
_ROWS_FROM = 1024
# Quantized normal components lie in [-32767, 32767]: shifted by this, they take 17 bits each.
_SHIFT = 1 << 16

_topologies: OrderedDict[bytes, dict] = OrderedDict()
# each prepared model's feature faces by crease angle, while it lives (``feature_faces``)
_features: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
# whether preparations keep the topologies they find, and read those kept (``topologies_kept``)
_keeping = [True]


@contextmanager
def topologies_kept(keep: bool) -> Iterator[None]:
    """Within the block, the preparations keep the topologies they find and read those kept
    (``keep``), or keep and read none, nor digest the model's content to look them up: for a
    process that prepares each model once, where what is kept would only hold memory through
    its drawing. The prepared arrays are the same either way."""
    _keeping.append(bool(keep))
    try:
        yield
    finally:
        _keeping.pop()


def topology(model: Model) -> dict:
    """The topology kept for the model's content (``corner_normals``' ``topology``), the most
    recently used kept last; a new, empty one where none is."""
    key = model.content_digest()
    held = _topologies.get(key)
    if held is None:
        held = _topologies[key] = {}
    _topologies.move_to_end(key)
    return held


def _bound() -> None:
    """Forget the least recently used topologies beyond ``_KEPT`` or ``_KEPT_BYTES``."""
    sizes = [sum(a.nbytes for a in held.values()) for held in _topologies.values()]
    while len(sizes) > _KEPT or sum(sizes) > _KEPT_BYTES:
        _topologies.popitem(last=False)
        sizes.pop(0)


def gpu_arrays(model: Model, crease_angle: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The vertex and index arrays of ``model`` for ``render.mesh.GpuMesh``.

    Every corner of every face becomes a vertex, corners of one vertex of the model merged
    where their part and their normal (``corner_normals`` with ``crease_angle``, quantized to
    16 bits) are the same; without a crease angle (None) the normals are left zero. A triangle
    soup's corners (each a vertex of the model, or a vertex of a ``Model.soup`` each, prepared
    as those corners apart would be) are merged where they lie at one position, in one part,
    with one normal, bit for bit: the vertex draws as each of them would.

    Returns
    -------
    vertices : (N,) ``VERTEX``
        Ordered by model vertex, then part, then normal; a soup's by welded vertex and part,
        then the corners kept apart.
    indices : (3F,) uint32
        Face ``i``'s corners at ``3 i`` to ``3 i + 2``.
    """
    if crease_angle is None:
        return _prepare(model, crease_angle, None)
    known = topology(model) if _keeping[-1] else {}
    arrays = _prepare(model, crease_angle, known)
    _keep_features(model, crease_angle, known)
    if _keeping[-1]:
        _bound()
    return arrays


def feature_faces(model: Model, crease_angle: float) -> np.ndarray | None:
    """(F,) bool: the faces of ``model`` with a vertex on a crease (at ``crease_angle``), a
    border or a non-manifold edge, as its preparation (``gpu_arrays``) found them while the
    model lives; None where it was not prepared at that angle. The rest are the smooth faces
    whose contours the GPU draws (``vector.contour_gpu``)."""
    return _features.get(model, {}).get(float(crease_angle))


def _keep_features(model: Model, crease_angle: float, known: dict) -> None:
    """Keep ``feature_faces`` of ``model`` from the topology its preparation found."""
    welded, sharp = known.get("welded"), known.get(("sharp", float(crease_angle)))
    if welded is None or sharp is None:
        return  # flat normals: no face is smooth
    feature = np.empty(len(welded), bool)
    parallel.run(partial(_any_sharp, welded, sharp, feature), len(welded))
    _features.setdefault(model, {})[float(crease_angle)] = feature


def _any_sharp(welded: np.ndarray, sharp: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    corners = np.take(sharp, welded[lo:hi])
    np.logical_or(corners[:, 0], corners[:, 1], out=out[lo:hi])
    out[lo:hi] |= corners[:, 2]


def _prepare(model: Model, crease_angle: float | None, known: dict | None) -> tuple[np.ndarray, np.ndarray]:
    corner_vertex = model.faces.reshape(-1)
    soup = model.soup
    if soup and not _numbered_by_first_corner(corner_vertex, len(model.positions)):
        # a soup's faces chosen or reordered since: its corners apart again, as the file had them
        model = model.replaced(
            positions=model.positions[corner_vertex],
            faces=np.arange(len(corner_vertex), dtype=np.int32).reshape(-1, 3),
            soup=False,
        )
        corner_vertex = model.faces.reshape(-1)
    normals = None
    if crease_angle is None:
        key = _vertex_part_keys(model, corner_vertex)
        if soup or np.all(key[1:] > key[:-1]):
            chosen, inverse = None, np.arange(len(key), dtype=np.uint32)  # a triangle soup
        else:
            _, chosen, inverse = unique_first(key)
            inverse = inverse.astype(np.uint32)
        del key
    else:
        known = {} if known is None else known
        # the loader's checks found the bounds: the weld and the crease runs measure by them
        diagonal = diagonal_of(model.bounds)
        normals = corner_normals(model.positions, model.faces, crease_angle, known, model.soup, diagonal)
        normals = normals.reshape(-1, 3)
        key = _vertex_part_keys(model, corner_vertex)
        if soup or np.all(key[1:] > key[:-1]):
            # every corner a vertex of its own (a triangle soup): merged where they are the same
            chosen, inverse = _soup_vertices(model, normals, known.get("welded"))
        else:
            chosen, inverse = _split_vertices(key, normals)
        del key
    count = len(corner_vertex) if chosen is None else len(chosen)
    vertices = np.zeros(count, VERTEX)
    parallel.run(partial(_filled, model, corner_vertex, chosen, normals, vertices), count)
    return vertices, inverse


def _vertex_part_keys(model: Model, corner_vertex: np.ndarray) -> np.ndarray:
    """(3F,) int: each corner's vertex and part as one key, in (vertex, part) order. Where each
    vertex lies in one part (a vertex shared between parts is split), the vertex orders the
    keys alone, over a range that ``unique_first`` and ``dense_ranks`` count over instead of
    sorting."""
    parts = len(model.part_names)
    if parts < 2:
        return corner_vertex
    n = len(corner_vertex)
    corner_part = np.empty(n, np.int32)
    parallel.run(partial(_corner_parts, model.face_part, corner_part), n)
    # each vertex's part from any of its corners: where one differs, a vertex lies in two
    vertex_part = np.zeros(len(model.positions), np.int32)
    parallel.put(vertex_part, corner_vertex, corner_part)
    if all(parallel.run(partial(_parts_agree, vertex_part, corner_vertex, corner_part), n)):
        return corner_vertex
    key = corner_vertex.astype(np.int64) * parts
    key += corner_part
    return key


def _corner_parts(face_part: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]``: the parts of corners lo to hi (three a face), a block at a time."""
    for start in range(lo, hi, _BLOCK):
        stop = min(start + _BLOCK, hi)
        out[start:stop] = face_part[np.arange(start, stop) // 3]


def _parts_agree(
    vertex_part: np.ndarray, corner_vertex: np.ndarray, corner_part: np.ndarray, lo: int, hi: int
) -> bool:
    """Whether each corner from lo to hi lies in its vertex's part."""
    return bool(np.array_equal(vertex_part[corner_vertex[lo:hi]], corner_part[lo:hi]))


def _numbered_by_first_corner(corner_vertex: np.ndarray, vertices: int) -> bool:
    """Whether the corners (3F,) use every one of ``vertices`` vertices, each numbered after the
    vertices of the corners before its first: then a soup's welded vertices (numbered by first
    vertex) are numbered by first corner, as those of its corners apart would be."""
    if len(corner_vertex) == 0:
        return vertices == 0
    firsts = parallel.flatnonzero(parallel.rises(corner_vertex))
    return len(firsts) == vertices and bool(np.array_equal(corner_vertex[firsts], np.arange(vertices)))


def _filled(
    model: Model,
    corner_vertex: np.ndarray,
    chosen: np.ndarray | None,
    normals: np.ndarray | None,
    out: np.ndarray,
    lo: int,
    hi: int,
) -> None:
    """``out[lo:hi]`` (``VERTEX``): the fields of the corners ``chosen`` (None: every corner)
    from lo to hi. A block of vertices at a time: their gathered fields are as large as the
    vertices."""
    for start in range(lo, hi, _BLOCK):
        stop = min(start + _BLOCK, hi)
        corner = np.arange(start, stop) if chosen is None else chosen[start:stop]
        out["p"][start:stop] = np.take(model.positions, corner_vertex[corner], axis=0)
        if normals is not None:
            out["n"][start:stop] = np.take(normals, corner, axis=0)
        out["part"][start:stop] = model.face_part[corner // 3]


def _soup_vertices(
    model: Model, normals: np.ndarray, welded: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """The vertices of a triangle soup's corners: one for the corners of a welded vertex
    (``welded``, (F, 3), None: none welded) and a part whose position and normal are those of
    its first corner, bit for bit, so that each corner draws as its own vertex would; one of
    its own for every other corner (where a weld joined close positions, or a crease split
    the normals). Returns the corner of each vertex and each corner's vertex (uint32)."""
    n = len(normals)
    if welded is None:
        return None, np.arange(n, dtype=np.uint32)
    key = welded.reshape(-1)
    first = None
    if len(model.part_names) > 1:
        key = key.astype(np.int64) * len(model.part_names)
        key += np.repeat(model.face_part, 3)
    else:
        # the welded ids are numbered by their first vertex, here their first corner: a corner
        # is its id's first where the id passes every id before it
        first = parallel.flatnonzero(parallel.rises(key))
        inverse = key
        if int(key.max(initial=-1)) + 1 != len(first):
            first = None  # ids of vertices no corner uses lie between: numbered anew
    if first is None:
        _, first, inverse = unique_first(key)
    del key
    apart = np.zeros(n, bool)
    parallel.run(partial(_apart, model, normals, first, inverse, apart), n)
    own = np.flatnonzero(apart)
    vertex = inverse.astype(np.uint32)
    vertex[own] = np.arange(len(first), len(first) + len(own), dtype=np.uint32)
    return np.concatenate([first, own]), vertex


def _apart(
    model: Model,
    normals: np.ndarray,
    first: np.ndarray,
    inverse: np.ndarray,
    out: np.ndarray,
    lo: int,
    hi: int,
) -> None:
    """``out[lo:hi]``: the soup's corner differs from the first corner of its welded vertex and
    part (``first[inverse]``) in position or normal, bit for bit."""
    corner_vertex = model.faces.reshape(-1)
    bits = model.positions.view(np.uint32)
    normal_bits = normals.view(np.uint32)
    for start in range(lo, hi, _BLOCK):
        first_corner = first[inverse[start : min(start + _BLOCK, hi)]]
        mine = slice(start, start + len(first_corner))
        differs = np.take(normal_bits, first_corner, axis=0) != normal_bits[mine]
        differs |= np.take(bits, corner_vertex[first_corner], axis=0) != np.take(
            bits, corner_vertex[mine], axis=0
        )
        # a column at a time: NumPy reduces short rows slowly
        np.logical_or(differs[:, 0], differs[:, 1], out=out[mine])
        out[mine] |= differs[:, 2]


def _split_vertices(vertex_part: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct (vertex and part, quantized normal) pairs of the corners, in that order:
    a corner of each, and each corner's pair (its number among them, uint32).

    ``vertex_part`` (3F,) int orders the vertex and the part; the normals' three 16-bit
    components (``_normal_key``) order the rest. No sort of every corner: a vertex whose
    corners' normals are one, bit for bit (every vertex off a crease), is one pair, any of its
    corners found by a table; the corners of the other vertices are grouped by key (one sort
    of one key) and told apart by normal within each (``_pairs_by_normal``), each pair's
    last corner its own."""
    n = len(vertex_part)
    key = dense_ranks(vertex_part)
    keys = int(key.max(initial=-1)) + 1
    # a corner of each key, whichever thread wrote last: where the key's corners have one
    # normal, any of them draws its vertex alike; where a corner's normal differs from it,
    # the key is mixed, its corners sorted by normal
    some = np.empty(keys, np.int64)
    parallel.run(partial(_some_corner, key, some), n)
    mixed = np.zeros(keys, bool)
    parallel.run(partial(_mixed, normals.view(np.uint32), some, key, mixed), n)
    # the corners of the other keys, each key's together in corner order; their pairs found
    # among each key's corners (``_pairs_by_normal``)
    inside = parallel.chosen_at(mixed, key)
    inside = parallel.taken(inside, stable_argsort(parallel.taken(key, inside)))
    inside_key = parallel.taken(key, inside)
    rank, ends, distinct, firsts = _pairs_by_normal(inside, inside_key, _normal_key(normals, inside))
    # pairs a key: one, or its distinct normals
    count = np.ones(keys, np.int64)
    count[mixed] = 0
    count[inside_key[firsts]] = distinct
    offset = np.cumsum(count) - count
    inverse = np.empty(n, np.uint32)
    parallel.take(offset, key, inverse)
    at = parallel.taken(offset, inside_key)
    parallel.run(partial(_added, at, rank), len(at))
    parallel.put(inverse, inside, at)
    chosen = np.repeat(some, count)
    parallel.put(chosen, at, ends)
    return chosen, inverse


def _added(values: np.ndarray, more: np.ndarray, lo: int, hi: int) -> None:
    """``values[lo:hi] += more[lo:hi]``."""
    values[lo:hi] += more[lo:hi]


def _some_corner(key: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[key[i]] = i`` for the corners from lo to hi: each key's entry one of its corners
    (whole words written, so whichever thread's comes last, it is one of them)."""
    for start in range(lo, hi, _BLOCK):
        stop = min(start + _BLOCK, hi)
        out[key[start:stop]] = np.arange(start, stop)


def _mixed(bits: np.ndarray, some: np.ndarray, key: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[key[i]] = True`` where corner ``i``'s normal ``bits`` (N, 3), from lo to hi, differ
    from those of its key's corner ``some``: only True is written, by any thread."""
    for start in range(lo, hi, _BLOCK):
        rows = slice(start, min(start + _BLOCK, hi))
        differs = np.take(bits, some[key[rows]], axis=0) != bits[rows]
        found = differs[:, 0] | differs[:, 1]
        found |= differs[:, 2]
        out[key[rows][found]] = True


def _pairs_by_normal(
    corners: np.ndarray, key: np.ndarray, normal: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The pairs of ``corners`` (each key's together, in corner order) by their ``key`` and
    ``normal`` key (``_normal_key``): each corner's pair among its key's, numbered by normal;
    the last corner of each corner's pair; and each key's count of pairs and its first place.

    A key of d corners compares them d x d (its corners of equal normals, and the normals
    before each), those of one d together, a block at a time: no sort of the corners by
    normal. Keys of more corners than ``_TABLE_DEGREE`` are sorted by normal instead."""
    n = len(corners)
    # the keys in order: a key's first corner is the one that passes every key before it
    firsts = parallel.flatnonzero(parallel.rises(key))
    size = np.diff(np.r_[firsts, n])
    rank = np.empty(n, np.int64)
    ends = np.empty(n, np.int64)
    distinct = np.empty(len(firsts), np.int64)
    work = square_blocks(size, _PAIR_BLOCK, _TABLE_DEGREE)

    def tables(lo: int, hi: int) -> None:
        for d, chosen in work[lo:hi]:
            at = firsts[chosen][:, None] + np.arange(d)
            comparing = _compared_by_rows if len(chosen) * d >= _ROWS_FROM else _compared_by_table
            first, last, less = comparing(normal[at])
            rank[at] = less
            ends[at] = np.take_along_axis(corners[at], last, axis=1)
            distinct[chosen] = first.sum(axis=1)

    parallel.run(tables, len(work), min_block=1)
    big = np.flatnonzero(size > _TABLE_DEGREE)
    if len(big):
        at = ranges(firsts[big], size[big])
        group = np.repeat(np.arange(len(big)), size[big])
        order = np.lexsort((normal[at], group))  # stable: each pair's corners keep their order
        at, group = at[order], group[order]
        value = normal[at]
        new_group = np.r_[True, group[1:] != group[:-1]]
        new = new_group | np.r_[True, value[1:] != value[:-1]]
        pair = np.cumsum(new) - 1
        rank[at] = pair - np.maximum.accumulate(np.where(new_group, pair, 0))
        run_end = np.flatnonzero(np.r_[new[1:], True])
        ends[at] = corners[at[run_end]][pair]
        distinct[big] = np.add.reduceat(new.astype(np.int64), np.flatnonzero(new_group))
    return rank, ends, distinct, firsts


def _compared_by_table(value: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Of the normal keys ``value`` (n, d) of n keys' d corners each, (n, d) each: whether a
    corner's normal is its key's first of that normal; the last corner of it; how many of the
    key's normals are less than it. As one (n, d, d) table: few calls, for few keys."""
    d = value.shape[1]
    same = value[:, :, None] == value[:, None, :]
    first = ~(same & np.tri(d, d, -1, bool)).any(axis=2)
    less = ((value[:, None, :] < value[:, :, None]) & first[:, None, :]).sum(axis=2)
    last = d - 1 - np.argmax(same[:, :, ::-1], axis=2)
    return first, last, less


def _compared_by_rows(value: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``_compared_by_table``'s answers from each corner's normals as a row (d, n), compared with
    the others' a corner at a time: over many keys the table's reductions along its short rows
    cost NumPy some three times as much."""
    d, n = value.shape[1], value.shape[0]
    value = np.ascontiguousarray(value.T)
    first = np.empty((d, n), bool)
    last = np.empty((d, n), np.int64)
    for i in range(d):
        same = value == value[i]
        first[i] = ~same[:i].any(axis=0)
        last[i] = d - 1 - np.argmax(same[::-1], axis=0)
    less = np.empty((d, n), np.int64)
    for i in range(d):
        np.sum((value < value[i]) & first, axis=0, out=less[i])
    return first.T, last.T, less.T


def _normal_key(normals: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
    """(N,) int64: the unit normals (N, 3) float32 (their ``rows`` where given) quantized to 16
    bits a component (as ``np.round(normals * 32767)``), packed in their order: the keys sort
    as the rows do. A block of rows at a time, side by side."""
    n = len(normals) if rows is None else len(rows)
    key = np.zeros(n, np.int64)

    def packed(lo: int, hi: int) -> None:
        for start in range(lo, hi, _BLOCK):
            stop = min(start + _BLOCK, hi)
            block = normals[start:stop] if rows is None else np.take(normals, rows[start:stop], axis=0)
            for axis in range(3):
                quantized = np.round(block[:, axis] * 32767).astype(np.int64)
                quantized += _SHIFT
                quantized <<= 17 * (2 - axis)
                key[start:stop] |= quantized

    parallel.run(packed, n)
    return key
