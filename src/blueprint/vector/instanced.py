"""The lines of a model kept as instances (``Model.instances``), found without flattening it.

What does not depend on the view is found once per unique mesh, cached by the mesh's content:
its adjacency (welded on its own), the edges that are borders and creases, the smooth faces and
vertex normals of its smooth contours, and the planes of its faces. Each instance then places
them: the view moved into the mesh's frame (the eye or the view direction through the inverse
of the instance's transform) gives every face's facing and every vertex's ``n . v`` for a block
of instances at once (one matrix product), from which the silhouettes (edge-on outlines among
them) and smooth contours of each instance follow as ``lines.feature_segments`` finds them on a
flat model; the segments are then placed by the instances' transforms. Intersection lines
between parts are found once for each pair of meshes that touch in one relative placement and
placed at every pair of instances placed so.

Edge numbers (``lines.edge_numbers``) of a model kept as instances are its flattened scene's,
made arithmetically: instance after instance, each instance's mesh's own edges (its adjacency's
sorted welded vertex pairs) moved by the welded vertices of the instances before it. The lines
are those of the flattened scene, welded a part at a time, wherever no two instances of one part
share a vertex and the transforms keep angles (rotations, mirrors, uniform scales); a mesh's
creases are its own (the picture's per-mesh preparation takes them so too).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

import numpy as np

from blueprint import parallel
from blueprint.columns import row_norm
from blueprint.errors import InputError
from blueprint.scene.camera import transform
from blueprint.scene.instances import Instances
from blueprint.scene.model import Model
from blueprint.silhouette import Adjacency, build_adjacency, smooth_surface
from blueprint.silhouette.contours import _EDGE_ON as _VERTEX_EDGE_ON
from blueprint.silhouette.contours import _edge_keys
from blueprint.silhouette.edges import _first_two_faces, _projected, near_kept, sharp_edges
from blueprint.sorting import grouped, stable_argsort

from .cache import ModelCache
from .linework import BORDER, CREASE, SILHOUETTE, SMOOTH

__all__ = [
    "face_parts",
    "instanced_edge_numbers",
    "instanced_edge_segments",
    "instanced_face_planes",
    "instanced_features",
    "instanced_intersections",
]

# Rows (faces, edges or vertices times instances) of one block's arrays.
_ROWS = 1 << 16
# Relative transforms between two instances equal to this many digits (of the model's size for
# their translations) are one placement: the intersection lines of one pair serve the other.
_PLACEMENT_DIGITS = 9

# Each unique mesh's view-independent line work, by its content.
MESH_LINES = ModelCache(entries=4096)
INTERSECTIONS = ModelCache()


@dataclass(frozen=True, eq=False)
class _MeshLines:
    """A unique mesh's adjacency and what its lines need of it in every view.

    count, f0, f1 : (E,) faces of each edge and its first two (``edges._first_two_faces``)
    two : (T,) the edges of two faces, ``pair`` (T, 2) their faces
    normal_ok : (F,) bool, faces with a normal
    planes : (F, 4) float64, ``(n, -n . p0)`` of every face (unit n, zero where none): its
        facing towards a point ``(e, 1)`` or a direction ``(d, 0)`` is one product
    vertex_planes : (V, 4) float64, the same of the vertex normals (per crease angle, below)
    many : (K,) edges of three faces or more, ``many_start`` (K + 1,) where each one's
        incidences start in ``many_face``
    by_angle : dict, per crease angle: (static kind (E,) uint8, smooth crease (E,) bool,
        SmoothSurface, vertex planes (V, 4))
    """

    adj: Adjacency
    count: np.ndarray
    f0: np.ndarray
    f1: np.ndarray
    two: np.ndarray
    pair: np.ndarray
    normal_ok: np.ndarray
    planes: np.ndarray
    many: np.ndarray
    many_start: np.ndarray
    many_face: np.ndarray
    keys: np.ndarray
    by_angle: dict

    def at_angle(self, crease_angle: float, smooth_angle: float):
        """(static kind, smooth creases, surface, vertex planes) at ``crease_angle``."""
        if crease_angle not in self.by_angle:
            adj = self.adj
            sharp = sharp_edges(adj, self.count, self.f0, self.f1, self.normal_ok, crease_angle)
            static = np.zeros(len(adj.edges), np.uint8)
            static[sharp] = CREASE
            static[self.count == 1] = BORDER
            normals = adj.face_normals
            cos = np.einsum("ij,ij->i", normals[self.f0], normals[np.maximum(self.f1, 0)])
            smooth_crease = (self.f1 >= 0) & (cos >= np.cos(np.radians(smooth_angle)))
            surface = smooth_surface(adj, crease_angle, sharp)
            vertex_planes = np.c_[surface.normals, -np.einsum("ij,ij->i", surface.normals, adj.positions)]
            self.by_angle[crease_angle] = (static, smooth_crease, surface, vertex_planes)
        return self.by_angle[crease_angle]


def _mesh_lines(inst: Instances, m: int) -> _MeshLines:
    positions, faces = inst.mesh_arrays(m)
    key = Model(positions, faces, np.zeros(len(faces), np.int32), ("mesh",))
    return MESH_LINES.get(key, lambda: _build_mesh_lines(positions, faces))


def _build_mesh_lines(positions: np.ndarray, faces: np.ndarray) -> _MeshLines:
    adj = build_adjacency(positions.astype(np.float64), faces.astype(np.int64))
    count, f0, f1 = _first_two_faces(adj)
    normals = adj.face_normals
    normal_ok = row_norm(normals) > 0
    planes = np.c_[normals, -np.einsum("ij,ij->i", normals, adj.positions[adj.faces[:, 0]])]
    many = np.flatnonzero(count >= 3)
    starts = np.cumsum(count) - count
    many_start = np.r_[0, np.cumsum(count[many])]
    incidences = np.repeat(starts[many], count[many]) + (
        np.arange(int(many_start[-1])) - np.repeat(many_start[:-1], count[many])
    )
    many_face = adj.edge_faces[incidences, 1]
    two = np.flatnonzero(count == 2)
    pair = np.stack([f0[two], f1[two]], axis=1)
    return _MeshLines(
        adj, count, f0, f1, two, pair, normal_ok, planes, many, many_start, many_face, _edge_keys(adj), {}
    )


def _mesh_lines_all(model: Model) -> list[_MeshLines]:
    """Every unique mesh's ``_MeshLines``, held by the model."""
    if "mesh_lines" not in model._cache:
        inst = model.instances
        model._cache["mesh_lines"] = [_mesh_lines(inst, m) for m in range(inst.mesh_count)]
    return model._cache["mesh_lines"]


def _starts(counts: np.ndarray) -> np.ndarray:
    """(N + 1,) int64: where each of ``counts`` (N,) starts, their total last."""
    return np.r_[0, np.cumsum(counts)].astype(np.int64)


def _numbering(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """(N + 1,) each instance's first welded vertex and first edge in the flattened numbering."""
    meshes = _mesh_lines_all(model)
    mesh = model.instances.mesh
    vertices = np.array([len(m.adj.positions) for m in meshes], np.int64)
    edges = np.array([len(m.adj.edges) for m in meshes], np.int64)
    return _starts(vertices[mesh]), _starts(edges[mesh])


def _blocks(members: np.ndarray, rows: int):
    step = max(1, _ROWS // max(rows, 1))
    for first in range(0, len(members), step):
        yield members[first : first + step]


def _moved(linear: np.ndarray, points: np.ndarray, in_order: bool = False) -> np.ndarray:
    """``linear @ point`` for (..., 3, 3) matrices and (..., 3) points, broadcast, in
    whole-array products instead of einsum's slow small-axis loop, to the same float64 values
    as ``einsum("...ij,...j->...i")``: einsum adds the first product and the last before the
    middle one, and adds them first to last (``in_order``) where ``linear`` is a transposed
    view."""
    x, y, z = points[..., 0:1], points[..., 1:2], points[..., 2:3]
    if in_order:
        out = (linear[..., 0] * x + linear[..., 1] * y) + linear[..., 2] * z
    else:
        out = (linear[..., 0] * x + linear[..., 2] * z) + linear[..., 1] * y
    # einsum's sums start at +0, which leaves no -0
    return np.add(out, 0.0, out=out)


def _dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(...,) the dot products of (..., 3) rows, the same float64 values as
    ``einsum("...i,...i->...")`` (see ``_moved``)."""
    out = (a[..., 0] * b[..., 0] + a[..., 2] * b[..., 2]) + a[..., 1] * b[..., 1]
    return np.add(out, 0.0, out=out)


def _placed(points: np.ndarray, transforms: np.ndarray) -> np.ndarray:
    """Points (K, ..., 3) placed each by its transform (K, 4, 4)."""
    shape = points.shape
    flat = points.reshape(len(points), int(np.prod(shape[1:-1], dtype=np.int64)), 3)
    out = _moved(transforms[:, None, :3, :3], flat) + transforms[:, None, :3, 3]
    return out.reshape(shape)


def _view_in_meshes(inst: Instances, view: np.ndarray, projection: np.ndarray):
    """(N, 4) the eye ``(e, 1)`` (perspective) or the direction towards it ``(d, 0)``
    (orthographic) in each instance's mesh frame, and (N,) the sign of each transform's
    determinant (-1: a mirror, whose faces turn the other way once placed)."""
    camera_to_model = np.linalg.inv(np.asarray(view, np.float64))
    linear = inst.transform[:, :3, :3]
    det = np.linalg.det(linear)
    flat = np.abs(det) <= 1e-300
    inverse = np.linalg.inv(np.where(flat[:, None, None], np.eye(3), linear))
    q = np.zeros((len(inst.mesh), 4))
    if projection[3, 3] == 1.0:
        q[:, :3] = np.einsum("nij,j->ni", inverse, camera_to_model[:3, 2])
    else:
        q[:, :3] = np.einsum("nij,nj->ni", inverse, camera_to_model[:3, 3] - inst.transform[:, :3, 3])
        q[:, 3] = 1.0
    # a transform that flattens its mesh leaves faces of no area: no facing, no line of it
    sign = np.where(flat, 0.0, np.sign(det))
    return q, sign


def _toward_length(q: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(B, P) length of the vector from each of ``points`` (P, 3) to the eye ``q`` (B, 4) (the
    direction's length where ``q[:, 3]`` is 0)."""
    eye = q[:, :3]
    square = np.einsum("bi,bi->b", eye, eye)[:, None] + q[:, 3:] * (
        np.einsum("pi,pi->p", points, points)[None] - 2.0 * eye @ points.T
    )
    return np.sqrt(np.maximum(square, 0.0))


@dataclass(frozen=True)
class _Tests:
    """One view's camera and the flat path's tests of its lines, as ``lines`` gives them
    (``instanced_features``)."""

    view: np.ndarray
    projection: np.ndarray
    size: tuple[int, int]
    smooth: bool
    edge_on_cos: float
    edge_on_smooth_cos: float
    outlines: Callable


@dataclass
class _Found:
    """What the blocks of one view collect, instance and local numbers with each row."""

    edge_inst: list
    outline: list
    edge: list
    edge_kind: list
    edge_sides: list
    edge_points: list
    edge_vertices: list
    side_exact: list
    edge_on: list
    smooth_crease: list
    contour_inst: list
    contour_face: list
    contour_edges: list
    contour_points: list
    contour_vertices: list
    contour_vertex_points: list


class _Placed:
    """The line segments one drawing has placed so far, the running count told to ``weigh``
    (which refuses, by raising, a count the memory budget does not hold) as each block is
    placed, from any of the pool's threads."""

    def __init__(self, weigh: Callable[[int], None]) -> None:
        self.weigh, self.count, self._lock = weigh, 0, threading.Lock()

    def add(self, count: int) -> None:
        with self._lock:
            self.count += count
            total = self.count
        self.weigh(total)


_PLACING: ContextVar[_Placed | None] = ContextVar("placing", default=None)


@contextmanager
def placing_weighed(weigh: Callable[[int], None]) -> Iterator[None]:
    """Within, the segments this module places (``instanced_features``' blocks, the
    intersections before they are placed at every pair) are counted, and ``weigh`` is told
    the count so far as each block comes, before the next is held beside it."""
    token = _PLACING.set(_Placed(weigh))
    try:
        yield
    finally:
        _PLACING.reset(token)


def instanced_features(
    model: Model,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    crease_angle: float,
    smooth: bool,
    smooth_angle: float,
    edge_on_cos: float,
    edge_on_smooth_cos: float,
    outlines: Callable,
):
    """The arrays ``lines.feature_segments`` builds its segments from, for a model kept as
    instances: a dict of the edges' model-space ``points`` (N, 2, 3), ``faces`` (N, 2) in the
    flattened numbering, ``part``, ``kind`` (edge-on creases made silhouettes, near-flat ones
    ``SMOOTH``), ``edge`` (flattened numbering), ``silhouette`` (N,) bool (silhouettes of
    ``classify_edges``' own and the edge-on outlines of ``lines._with_edge_on_outlines``, whose
    rule ``outlines`` is, ``lines._edge_on_outline_edges``), ``vertices`` (N, 2) (their
    flattened welded vertices),
    ``exact`` (N, 2) bool (side faces where the mesh's own silhouette stays), and the smooth
    contours' ``contour_points`` (K, 2, 3), ``contour_pixels`` (K, 2, 2), ``contour_face``
    (K,), ``contour_part``, ``contour_edges`` (K, 2), ``contour_vertices`` (K, 2, 2) (the
    flattened welded vertices of each end's edge) and ``contour_vertex_points`` (K, 2, 2, 3);
    everything in the order of the flattened scene."""
    inst = model.instances
    meshes = _mesh_lines_all(model)
    first_vertex, first_edge = _numbering(model)
    first_face = _starts(inst.instance_faces())
    q_all, sign_all = _view_in_meshes(inst, view, projection)
    tests = _Tests(view, projection, size, smooth, edge_on_cos, edge_on_smooth_cos, outlines)
    tasks = []
    for m, members in inst.by_mesh():
        ml = meshes[m]
        if len(ml.adj.faces) == 0:
            continue
        at_angle = ml.at_angle(crease_angle, smooth_angle)
        rows = max(len(ml.adj.edges), len(ml.adj.faces), len(ml.adj.positions))
        tasks += [(ml, block, at_angle) for block in _blocks(members, rows)]

    placed = _PLACING.get()

    def features(task) -> _Found:
        ml, block, at_angle = task
        found = _Found(*([] for _ in range(16)))
        _block_features(ml, block, q_all[block], sign_all[block], at_angle, tests, inst, found)
        if placed is not None:
            placed.add(sum(len(e) for e in found.edge) + sum(len(f) for f in found.contour_face))
        return found

    # the blocks side by side, what each found joined in the blocks' order
    found = _Found(*([] for _ in range(16)))
    for one in parallel.each(features, tasks):
        for name in _Found.__dataclass_fields__:
            getattr(found, name).extend(getattr(one, name))
    return _assembled(found, inst, first_vertex, first_edge, first_face, view, projection, size)


def _block_features(ml: _MeshLines, block, q, sign, at_angle: tuple, tests: _Tests, inst, found: _Found):
    # the mesh's lines at the crease angle (``_MeshLines.at_angle``)
    static, smooth_crease, surface, vertex_planes = at_angle
    adj = ml.adj
    raw = (ml.planes @ q.T).T * sign[:, None]  # (B, F) facing, placed
    ok = ml.normal_ok[None] & (sign[:, None] != 0)
    front = (raw > 0.0) & ok
    back = ~front & ok
    cos = np.abs(raw) / np.maximum(_toward_length(q, adj.positions[adj.faces[:, 0]]), 1e-300)
    f0, f1 = ml.f0, np.maximum(ml.f1, 0)
    two = ml.count == 2
    silhouette = ((front[:, f0] | front[:, f1]) & (back[:, f0] | back[:, f1])) & two[None]
    first_front = np.where(front[:, f0], f0, f1)
    first_back = np.where(back[:, f0], f0, f1)
    if len(ml.many):
        fr, bk = front[:, ml.many_face], back[:, ml.many_face]
        cut = ml.many_start[:-1]
        any_front = np.logical_or.reduceat(fr, cut, axis=1)
        any_back = np.logical_or.reduceat(bk, cut, axis=1)
        silhouette[:, ml.many] = any_front & any_back
        none = len(adj.faces)
        first_front[:, ml.many] = np.minimum.reduceat(np.where(fr, ml.many_face, none), cut, axis=1)
        first_back[:, ml.many] = np.minimum.reduceat(np.where(bk, ml.many_face, none), cut, axis=1)
    b, e = np.nonzero(silhouette | (static != 0)[None])
    is_sil = silhouette[b, e]
    kind = np.where(is_sil, SILHOUETTE, static[e]).astype(np.uint8)
    sides = np.stack([ml.f0[e], np.where(kind == BORDER, -1, ml.f1[e])], axis=1)
    sides[is_sil] = np.stack([first_front[b[is_sil], e[is_sil]], first_back[b[is_sil], e[is_sil]]], axis=1)
    # every vertex placed once an instance (the same products as a line's ends placed one by
    # one): the edges' ends and the contours' vertices are gathered from them
    placed = _placed(
        np.broadcast_to(adj.positions, (len(block), *adj.positions.shape)), inst.transform[block]
    )
    points = placed[b[:, None], adj.edges[e]]
    edge_on = cos <= tests.edge_on_cos
    nb, ne, new_points = _outline_edges(ml, edge_on, (b, e, points), inst.transform[block], tests)
    b, e = np.r_[b, nb], np.r_[e, ne]
    kind = np.r_[kind, np.full(len(ne), SILHOUETTE, np.uint8)]
    sides = np.concatenate([sides, np.stack([ml.f0[ne], ml.f1[ne]], axis=1)])
    found.outline.append(np.arange(len(e)) >= len(points))
    found.edge_inst.append(block[b])
    found.edge.append(e)
    found.edge_kind.append(kind)
    found.edge_sides.append(sides)
    found.edge_points.append(np.concatenate([points, new_points]))
    found.edge_vertices.append(adj.edges[e])
    found.edge_on.append(edge_on[b[:, None], np.maximum(sides, 0)] & (sides >= 0))
    found.smooth_crease.append(smooth_crease[e])
    if not tests.smooth:
        found.side_exact.append(np.ones(sides.shape, bool))
        return
    smooth_faces = surface.smooth[None] & (cos > tests.edge_on_smooth_cos)
    found.side_exact.append(~smooth_faces[b[:, None], np.maximum(sides, 0)])
    g = (vertex_planes @ q.T).T * sign[:, None]  # (B, V) n . v at the vertices, placed
    near = _VERTEX_EDGE_ON * _toward_length(q, adj.positions)
    corners = (g > near)[:, adj.faces]  # (B, F, 3)
    cb, cf = np.nonzero(smooth_faces & corners.any(axis=2) & ~corners.all(axis=2))
    corners = corners[cb, cf]
    changes = corners != corners[:, [1, 2, 0]]
    ends, edges, vertices = [], [], []
    for k in (np.argmax(changes, axis=1), 2 - np.argmax(changes[:, ::-1], axis=1)):
        a = adj.faces[cf, k]
        c = adj.faces[cf, (k + 1) % 3]
        lo, hi = np.minimum(a, c), np.maximum(a, c)
        t = g[cb, lo] / (g[cb, lo] - g[cb, hi])
        ends.append(adj.positions[lo] + t[:, None] * (adj.positions[hi] - adj.positions[lo]))
        edges.append(np.searchsorted(ml.keys, lo * len(adj.positions) + hi))
        vertices.append(np.stack([lo, hi], axis=1))
    which = block[cb]
    vertices = np.stack(vertices, axis=1)  # (K, 2 ends, 2 vertices)
    found.contour_inst.append(which)
    found.contour_face.append(cf)
    found.contour_edges.append(np.stack(edges, axis=1))
    found.contour_points.append(_placed(np.stack(ends, axis=1), inst.transform[which]))
    found.contour_vertices.append(vertices)
    found.contour_vertex_points.append(placed[cb[:, None, None], vertices])


def _outline_edges(ml: _MeshLines, edge_on: np.ndarray, lines: tuple, transforms: np.ndarray, tests: _Tests):
    """The block's edges that the flat path's rule makes silhouettes (``tests.outlines``, as
    ``lines._with_edge_on_outlines`` applies it): (K,) rows of the block, (K,) edges and (K, 2,
    3) their placed ends, those wholly in front of the eye. ``edge_on`` (B, F): the faces seen
    edge-on in each instance (``transforms`` (B, 4, 4)); ``lines``: the rows, edges and placed
    ends (N, 2, 3) of the block's silhouettes, borders and creases."""
    none = np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 2, 3))
    # only the edges beside a face seen edge-on in some instance of the block can change
    touched = edge_on.any(axis=0)[ml.pair].any(axis=1)
    if not touched.any():
        return none
    pair, two = ml.pair[touched], ml.two[touched]
    column = np.full(len(ml.adj.edges), -1)
    column[two] = np.arange(len(two))
    # found as the flat path finds them: where the near plane leaves a piece of them
    b, e, points = lines
    beside = column[e] >= 0
    kept = near_kept(points[beside], tests.view, tests.projection)[1]
    found = np.zeros((len(edge_on), len(two)), bool)
    found[b[beside][kept], column[e[beside][kept]]] = True
    rows, k = np.nonzero(tests.outlines(edge_on, pair, found))
    edges = two[k]
    placed = _placed(ml.adj.positions[ml.adj.edges[edges]], transforms[rows])
    ahead = (transform(placed, tests.projection @ tests.view)[..., 3] > 0).all(axis=1)
    return rows[ahead], edges[ahead], placed[ahead]


def _joined(items: list, shape: tuple, dtype) -> np.ndarray:
    """The blocks' pieces ``items`` in one array (rows of ``shape`` and ``dtype`` where there are
    none), the list emptied: the pieces are not held beside the whole."""
    joined = np.concatenate(items) if items else np.zeros((0, *shape), dtype)
    items.clear()
    return joined


def _gathered(columns: dict[str, tuple[list, tuple, type]], rows: np.ndarray) -> dict[str, np.ndarray]:
    """Each column's pieces (with the shape of a row and the type of an empty one) joined and
    its ``rows`` taken, the columns side by side on the pool."""
    names = list(columns)
    return dict(zip(names, parallel.each(lambda name: _joined(*columns[name])[rows], names), strict=True))


def _assembled(found: _Found, inst: Instances, first_vertex, first_edge, first_face, view, projection, size):
    which = _joined(found.edge_inst, (), np.int64)
    edge = first_edge[which] + _joined(found.edge, (), np.int64)
    order = stable_argsort(edge)
    ordered = _gathered(
        {"points": (found.edge_points, (2, 3), np.float64), "outline": (found.outline, (), bool)}, order
    )
    points, outline = ordered["points"], ordered["outline"]
    # the edge-on outlines are wholly in front of the eye and kept whole, as the flat path keeps
    # them; the other lines are clipped to the near plane
    inside = np.flatnonzero(~outline)
    clipped, kept = near_kept(points[inside] if len(inside) < len(points) else points, view, projection)
    kept = inside[kept]
    keep = outline.copy()
    keep[kept] = True
    keep = np.flatnonzero(keep)
    if clipped is not points:  # (the same array where nothing was clipped)
        points[kept] = clipped
        points = points[keep]
    # every other row of the kept edges gathered once, in their order
    rows = order[keep]
    which = which[rows]
    edges = _gathered(
        {
            "sides": (found.edge_sides, (2,), np.int64),
            "kind": (found.edge_kind, (), np.uint8),
            "edge_on": (found.edge_on, (2,), bool),
            "smooth": (found.smooth_crease, (), bool),
            "vertices": (found.edge_vertices, (2,), np.int64),
            "exact": (found.side_exact, (2,), bool),
        },
        rows,
    )
    sides, kind = edges["sides"], edges["kind"]
    silhouette = kind == SILHOUETTE
    # an outline edge beside a face seen edge-on is a silhouette whichever way it rounds
    kind[(kind == CREASE) & edges["edge_on"].any(axis=1)] = SILHOUETTE
    kind[(kind == CREASE) & edges["smooth"]] = SMOOTH
    out = {
        "points": points,
        "faces": np.where(sides >= 0, first_face[which][:, None] + sides, -1),
        "part": inst.part[which].astype(np.int32),
        "kind": kind,
        "edge": edge[rows],
        "silhouette": silhouette,
        "vertices": first_vertex[which][:, None] + edges["vertices"],
        "exact": edges["exact"],
    }
    which = _joined(found.contour_inst, (), np.int64)
    face = first_face[which] + _joined(found.contour_face, (), np.int64)
    order = stable_argsort(face)
    points, pixels, keep = _projected(
        _joined(found.contour_points, (2, 3), np.float64)[order], view, projection, size
    )
    rows = order[keep]
    which = which[rows]
    contours = _gathered(
        {
            "edges": (found.contour_edges, (2,), np.int64),
            "vertices": (found.contour_vertices, (2, 2), np.int64),
            "vertex_points": (found.contour_vertex_points, (2, 2, 3), np.float64),
        },
        rows,
    )
    out.update(
        contour_points=points,
        contour_pixels=pixels,
        contour_face=face[rows],
        contour_part=inst.part[which].astype(np.int32),
        contour_edges=first_edge[which][:, None] + contours["edges"],
        contour_vertices=first_vertex[which][:, None, None] + contours["vertices"],
        contour_vertex_points=contours["vertex_points"],
    )
    return out


# -- edges by number ------------------------------------------------------------------------------


def instanced_edge_numbers(model: Model) -> np.ndarray:
    """(E, 2) int64: ``lines.edge_numbers`` of a model kept as instances (module docstring)."""
    inst = model.instances
    meshes = _mesh_lines_all(model)
    first_vertex, first_edge = _numbering(model)
    out = np.empty((int(first_edge[-1]), 2), np.int64)
    for m, members in inst.by_mesh():
        edges = meshes[m].adj.edges
        for block in _blocks(members, len(edges)):
            rows = first_edge[block][:, None] + np.arange(len(edges))
            out[rows] = edges[None] + first_vertex[block][:, None, None]
    return out


def instanced_edge_segments(model: Model, edges: np.ndarray) -> np.ndarray:
    """(N, 2, 3) float64 ends of the edges numbered ``edges`` (N,) of a model kept as instances;
    ``InputError`` naming the first number that is no edge."""
    inst = model.instances
    meshes = _mesh_lines_all(model)
    _, first_edge = _numbering(model)
    total = int(first_edge[-1])
    edges = np.asarray(edges, np.int64).reshape(-1)
    bad = (edges < 0) | (edges >= total)
    if bad.any():
        raise InputError(
            f"{model.source or 'model'}: edge {int(edges[np.argmax(bad)])} is no edge of the model "
            f"(it has {total}: 0 to {total - 1})"
        )
    which = np.searchsorted(first_edge, edges, side="right") - 1
    local = edges - first_edge[which]
    out = np.empty((len(edges), 2, 3))
    for m in np.unique(inst.mesh[which]).tolist():
        rows = np.flatnonzero(inst.mesh[which] == m)
        adj = meshes[m].adj
        out[rows] = _placed(adj.positions[adj.edges[local[rows]]], inst.transform[which[rows]])
    return out


# -- occlusion ------------------------------------------------------------------------------------


def face_parts(model: Model) -> np.ndarray:
    """(F,) int32: the part of every drawn face, ``Model.face_part`` without flattening a model
    kept as instances."""
    if model.instances is None:
        return model.face_part
    inst = model.instances
    return np.repeat(inst.part, inst.instance_faces()).astype(np.int32)


def instanced_face_planes(model: Model, view: np.ndarray) -> np.ndarray:
    """``occlusion.face_planes`` of a model kept as instances: every instance's faces' planes
    in eye space, from its mesh's planes through the view and its transform."""
    inst = model.instances
    first_face = _starts(inst.instance_faces())
    planes = np.zeros((int(first_face[-1]) + 1, 4))
    view = np.asarray(view, np.float64)
    tasks = []
    for m, members in inst.by_mesh():
        vertices, faces = inst.mesh_arrays(m)
        if not len(faces):
            continue
        corners = vertices[faces]
        cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        good = row_norm(cross) > 0
        tasks += [(corners, cross, good, block) for block in _blocks(members, len(faces))]

    def place(task) -> None:
        # each block writes its own instances' rows
        corners, cross, good, block = task
        moved = view[None] @ inst.transform[block]  # (B, 4, 4)
        linear = moved[:, :3, :3]
        # normals move by the cofactors: they stay square to the moved faces, mirrors too
        cofactor = np.linalg.det(linear)[:, None, None] * np.linalg.inv(
            np.where((np.abs(np.linalg.det(linear)) > 1e-300)[:, None, None], linear, np.eye(3))
        ).transpose(0, 2, 1)
        normal = _moved(cofactor[:, None], cross[None], in_order=True)
        length = np.linalg.norm(normal, axis=2)
        normal = np.where(
            (length > 0)[..., None] & good[None, :, None],
            normal / np.maximum(length, 1e-300)[..., None],
            0.0,
        )
        corner = _moved(linear[:, None], corners[None, :, 0]) + moved[:, None, :3, 3]
        rows = first_face[block][:, None] + np.arange(len(corners))
        planes[rows, :3] = normal
        planes[rows, 3] = _dot3(normal, corner)

    parallel.each(place, tasks)
    return planes


# -- intersections ----------------------------------------------------------------------------------


def _near_box(corners: np.ndarray, transforms: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(R, F) bool: the triangles (F, 3, 3) of a mesh whose box, placed by each of ``transforms``
    (R, 4, 4), may meet the box ``lo``, ``hi`` (R, 3): the box moved into the mesh's frame
    (the box around its moved corners) against the triangles' own boxes."""
    pick = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T  # (8, 3)
    box = np.where(pick[None] == 0, lo[:, None], hi[:, None])  # (R, 8, 3)
    back = np.linalg.inv(transforms)
    moved = np.einsum("rij,rkj->rki", back[:, :3, :3], box) + back[:, None, :3, 3]
    box_lo, box_hi = moved.min(axis=1), moved.max(axis=1)
    tri_lo, tri_hi = corners.min(axis=1), corners.max(axis=1)
    near = np.ones((len(lo), len(corners)), bool)
    for axis in range(3):
        near &= (tri_hi[None, :, axis] >= box_lo[:, None, axis]) & (
            tri_lo[None, :, axis] <= box_hi[:, None, axis]
        )
    return near


def instanced_intersections(model: Model, eps: float, phases, renderer=None):
    """``lines.intersection_segments``' lines of a model kept as instances, cached by its
    content: (K, 2, 3) points, (K, 2) flattened faces, (K,) parts. ``phases``: the flat
    path's broad phase over boxes and its cut of triangles (``lines._overlapping_boxes``,
    ``lines.triangle_cuts``), given by ``lines`` (which imports this module)."""
    return INTERSECTIONS.get(model, lambda: _intersections(model, eps, phases, renderer))


def _intersections(model: Model, eps: float, phases, renderer):
    _overlapping_boxes, triangle_cuts = phases
    inst = model.instances
    none = np.zeros((0, 2, 3)), np.zeros((0, 2), np.int64), np.zeros(0, np.int32)
    boxes = model.instance_boxes()
    lo, hi = boxes[:, 0] - eps, boxes[:, 1] + eps
    live = np.flatnonzero(np.isfinite(lo).all(axis=1))
    i, j = _overlapping_boxes(lo[live], hi[live])
    i, j = live[i], live[j]
    apart = inst.part[i] != inst.part[j]
    i, j = i[apart], j[apart]
    if len(i) == 0:
        return none
    # pairs placed alike (one mesh's instance seen from the other's frame): one computation
    size = float(np.linalg.norm(np.diff(model.bounds, axis=0))) or 1.0
    relative = np.linalg.inv(inst.transform[i]) @ inst.transform[j]
    scale = np.ones(16)
    scale[[3, 7, 11]] = 1.0 / size  # the translations, relative to the model's size
    key = np.round(relative.reshape(-1, 16) * scale, _PLACEMENT_DIGITS)
    key = np.c_[inst.mesh[i], inst.mesh[j], key]
    _, first, group = np.unique(key, axis=0, return_index=True, return_inverse=True)
    group = group.reshape(-1)
    ri, rj = i[first], j[first]
    # each pair's two instances' triangles near the other's box, the pairs moved apart
    span = 4.0 * size + 4.0 * float(np.abs(model.bounds).max())
    me = np.r_[ri, rj]
    other = np.r_[rj, ri]
    pair_part = np.r_[2 * np.arange(len(ri)), 2 * np.arange(len(ri)) + 1]
    tri, part, local = [], [], []
    for m, sides in grouped(inst.mesh[me]):
        vertices, faces = inst.mesh_arrays(m)
        corners = vertices[faces]
        near = _near_box(corners, inst.transform[me[sides]], lo[other[sides]], hi[other[sides]])
        side, face = np.nonzero(near)
        placed = _placed(corners[face], inst.transform[me[sides[side]]])
        # the placed triangles' own boxes against the other's: the moved box held more
        held = other[sides[side]]
        # a corner at a time: NumPy reduces short rows slowly
        high = np.maximum(np.maximum(placed[:, 0], placed[:, 1]), placed[:, 2]) >= lo[held]
        low = np.minimum(np.minimum(placed[:, 0], placed[:, 1]), placed[:, 2]) <= hi[held]
        meets = high[:, 0] & high[:, 1] & high[:, 2] & low[:, 0] & low[:, 1] & low[:, 2]
        side, face, placed = side[meets], face[meets], placed[meets]
        placed[..., 0] += ((pair_part[sides[side]] // 2) * span)[:, None]
        tri.append(placed)
        part.append(pair_part[sides[side]])
        local.append(face)
    tri = np.concatenate(tri)
    part = np.concatenate(part)
    local = np.concatenate(local)
    origin = part // 2
    solid = row_norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])) > 0
    points, ta, tb = triangle_cuts(tri, part, solid, eps, renderer)
    if len(ta) == 0:
        return none
    k = origin[ta]
    points[..., 0] -= (k * span)[:, None]
    # the first triangle on the pair's first instance, the second on its other
    swap = part[ta] % 2 == 1
    la, lb = np.where(swap, local[tb], local[ta]), np.where(swap, local[ta], local[tb])
    # into the frame of the pair's first instance, then placed at every pair of its group
    back = np.linalg.inv(inst.transform[ri[k]])
    points = _placed(points, back)
    members = stable_argsort(group)
    counts = np.bincount(group, minlength=len(ri))
    member_start = np.r_[0, np.cumsum(counts)]
    seg_order = stable_argsort(k)
    # every (segment, pair of its group) once
    repeat = counts[k[seg_order]]
    placed = _PLACING.get()
    if placed is not None:
        placed.add(int(repeat.sum()))
    seg = np.repeat(seg_order, repeat)
    within = np.arange(len(seg)) - np.repeat(np.cumsum(repeat) - repeat, repeat)
    pair = members[member_start[k[seg]] + within]
    first_face = _starts(inst.instance_faces())
    pa, pb = i[pair], j[pair]
    faces = np.stack([first_face[pa] + la[seg], first_face[pb] + lb[seg]], axis=1)
    order = _by_faces(faces, int(first_face[-1]))
    seg, pa, faces = seg[order], pa[order], faces[order]
    part_out = np.minimum(inst.part[pa], inst.part[pb[order]]).astype(np.int32)
    placed = np.empty((len(seg), 2, 3))

    def place(lo: int, hi: int) -> None:
        placed[lo:hi] = _placed(points[seg[lo:hi]], inst.transform[pa[lo:hi]])

    parallel.run(place, len(seg))
    return placed, faces, part_out


def _by_faces(faces: np.ndarray, count: int) -> np.ndarray:
    """The order of the rows of ``faces`` (K, 2) (each of ``count`` faces) by their first face,
    then their second, rows alike in their order: ``np.lexsort`` of the two, by the thread
    pool's sort of one key where the pairs fit one."""
    if float(count) * float(count) >= 2.0**62:
        return np.lexsort((faces[:, 1], faces[:, 0]))
    return stable_argsort(faces[:, 0] * count + faces[:, 1])
