"""Object-space lines of a model for one view, joined into polylines.

Edges come from the CPU silhouette module (silhouettes for the view, borders, creases above an
angle) on a mesh welded within each part, plus two kinds that only exist between parts: *part
boundaries* (borders of one part that coincide with borders of another: a surface split into
parts) and *intersection lines* (where a triangle of one part cuts through a triangle of
another). Everything stays in model space here; the segments carry
the faces they lie on so that occlusion can tell a line's own surface from the ones in front.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import partial

import numpy as np

from blueprint import parallel
from blueprint.columns import column_max, column_min, column_ptp, cross, face_cross, row_norm
from blueprint.errors import InputError
from blueprint.scene.camera import clip_to_pixels, transform
from blueprint.scene.model import Model
from blueprint.scene.weld import connected_components_of
from blueprint.silhouette import (
    BORDER,
    CREASE,
    SILHOUETTE,
    Adjacency,
    EdgeSet,
    SmoothSurface,
    build_adjacency,
    classify_edges,
    mesh_sharp_edges,
    smooth_contours,
    smooth_surface,
    toward_eye,
)
from blueprint.sorting import renumbered, sorted_ranks, sorted_with_order, stable_argsort, unique_first

from .cache import ModelCache
from .chain import chain_order, pair_ends
from .cuts import gpu_cut_pairs
from .linework import BOUNDARY, INTERSECTION, SMOOTH

__all__ = [
    "BORDER",
    "CREASE",
    "INTERSECTION",
    "PART_BOUNDARY",
    "SILHOUETTE",
    "SMOOTH",
    "Polylines",
    "Segments",
    "adjacency",
    "edge_numbers",
    "edge_segments",
    "feature_segments",
    "intersection_segments",
    "join_polylines",
    "grazing_band",
    "model_segments",
    "smooth_contour_segments",
]

PART_BOUNDARY = BOUNDARY

# Smooth contours that run fewer pixels than this before they end at a feature leave the mesh's
# own silhouette in their faces: a stub between two gaps breaks a line into pieces, while the
# zigzag of a mesh's silhouette shows along long contours.
_MIN_CONTOUR_PX = 30.0
# A smooth face with a vertex normal within this many degrees of square with the view lies in
# the band where a noisy surface folds over its own contour (``grazing_band``); such faces hide
# a smooth contour only from farther in front than this many of their own sizes.
GRAZING_DEGREES = 12.0
GRAZING_REACH = 4.0
# Creases whose faces meet at less than this many degrees are tangent edges of smooth blends
# (a fillet's boundary): kind ``SMOOTH``.
SMOOTH_ANGLE = 5.0
# Faces whose normal is this close (a cosine) to square with the view direction are seen edge-on.
_EDGE_ON = 1e-9
# Faces this close (a cosine) to edge-on keep the mesh's silhouette edges instead of smooth
# contours: the vertex normals of a surface along the view round to either side.
_EDGE_ON_SMOOTH = 1e-6
# Endpoints closer than this fraction of the model's diagonal are one point when joining.
_JOIN_REL = 1e-6
# Points keyed at once by one thread when joining: their temporaries, not every point's.
_ROWS = 1 << 16
# Signed plane distances below this fraction of the diagonal count as zero (touching, not cutting).
_TOUCH_REL = 1e-7
# Cell entries of the intersection broad phase, per candidate triangle, before cells grow.
_CELLS_PER_TRIANGLE = 8
# Candidate triangle pairs examined per NumPy pass of the narrow phase (and triangle-part pairs
# of the broad phase).
_PAIR_CHUNK = 1 << 19
# Cost of placing a triangle among the parts' ends (six binary searches) in tests of it against
# one part's box.
_WORD_SEARCHES = 6
# Pairs of part boxes up to which all are tested at once.
_DENSE_PAIRS = 1 << 22
# Words of 64 parts ranked together when triangles are tested against words: their tables hold
# a word's bits at every rank of the block's parts.
_BLOCK_WORDS = 64

ADJACENCY = ModelCache()
# The smooth faces and vertex normals of each mesh, by crease angle (``smooth_surface``).
SURFACES = ModelCache()
# The sharp edges of each mesh, by crease angle (``_classified``).
SHARP = ModelCache()
INTERSECTIONS = ModelCache()


@dataclass(frozen=True)
class Segments:
    """Model-space line segments of one view.

    Attributes
    ----------
    points : (N, 2, 3) float64
        Endpoints in model coordinates.
    faces : (N, 2) int64
        Faces the segment lies on (``-1`` where there is only one): the surfaces that can never
        hide it.
    part : (N,) int32
        Part the segment is drawn with.
    kind : (N,) uint8
        ``SILHOUETTE``, ``BORDER``, ``CREASE``, ``PART_BOUNDARY``, ``SMOOTH`` or
        ``INTERSECTION``.
    edge : (N,) int64
        The model's edge the segment lies on (``edge_numbers``), -1 for intersections; for a
        smooth contour, which lies inside a face, the edge its first point lies on.
    edge_end : (N,) int64, optional
        The edge the segment's second point lies on, where that is another (smooth contours:
        the edge where the contour leaves the face); None: ``edge``.
    """

    points: np.ndarray
    faces: np.ndarray
    part: np.ndarray
    kind: np.ndarray
    edge: np.ndarray
    edge_end: np.ndarray | None = None

    def end_edges(self) -> np.ndarray:
        """(N,) int64: the edge each segment's second point lies on."""
        return self.edge if self.edge_end is None else self.edge_end

    @classmethod
    def empty(cls) -> Segments:
        return cls(
            np.zeros((0, 2, 3)),
            np.zeros((0, 2), np.int64),
            np.zeros(0, np.int32),
            np.zeros(0, np.uint8),
            np.zeros(0, np.int64),
        )

    def __len__(self) -> int:
        return len(self.points)

    def taken(self, rows: np.ndarray) -> Segments:
        """The segments ``rows``, their columns taken side by side on the pool."""
        names = [name for name in _SEGMENT_COLUMNS if getattr(self, name) is not None]
        taken = _columns_each(lambda name: getattr(self, name)[rows], names, len(rows))
        return Segments(**dict(zip(names, taken, strict=True)))

    @staticmethod
    def concatenate(items: list[Segments]) -> Segments:
        items = [s for s in items if len(s)] or [Segments.empty()]
        ends = any(s.edge_end is not None for s in items)
        # the columns joined side by side on the pool: a big assembly's are millions of rows
        columns = {
            "points": lambda s: s.points,
            "faces": lambda s: s.faces,
            "part": lambda s: s.part.astype(np.int32, copy=False),
            "kind": lambda s: s.kind.astype(np.uint8, copy=False),
            "edge": lambda s: s.edge.astype(np.int64, copy=False),
            **({"edge_end": lambda s: s.end_edges().astype(np.int64, copy=False)} if ends else {}),
        }
        joined = _columns_each(
            lambda name: np.concatenate([columns[name](s) for s in items]),
            list(columns),
            sum(len(s) for s in items),
        )
        return Segments(**dict(zip(columns, joined, strict=True)))


_SEGMENT_COLUMNS = ("points", "faces", "part", "kind", "edge", "edge_end")


def _columns_each(work: Callable, names: list[str], rows: int) -> list[np.ndarray]:
    """``work(name)`` for the columns ``names`` of ``rows`` rows, side by side on the pool
    where they are many (a thread's hand-over costs more than a few rows' copy)."""
    if rows < parallel.MIN_BLOCK:
        return [work(name) for name in names]
    return parallel.each(work, names)


@dataclass(frozen=True)
class Polylines:
    """Joined segments: polyline ``i`` is ``points[offsets[i]:offsets[i + 1]]``.

    ``faces[j]``, ``kind[j]`` and ``edge[j]`` belong to the segment from point ``j`` to point
    ``j + 1`` (the rows of each polyline's last point are unused); ``part`` is per polyline.
    """

    points: np.ndarray
    offsets: np.ndarray
    faces: np.ndarray
    part: np.ndarray
    kind: np.ndarray
    edge: np.ndarray

    def __len__(self) -> int:
        return len(self.offsets) - 1


def _diagonal(points: np.ndarray) -> float:
    if len(points) == 0:
        return 1.0
    return float(np.linalg.norm(column_ptp(points))) or 1.0


def adjacency(model: Model) -> Adjacency:
    """Adjacency of a model welded within each part only, computed once per mesh (``cache``).

    Parts never share edges: where two parts meet, each keeps its own edges there (a border
    of an open part, a crease of a solid), so a seam between parts is drawn, and the faces of
    two solids pressed together do not weld into non-manifold edges that would read as
    silhouettes. The welding runs once for all parts: every part is moved along x by a distinct
    multiple of a span larger than the model, so no two parts come within the weld tolerance,
    and moved back afterwards.
    """
    return ADJACENCY.get(model, lambda: _welded_adjacency(model))


def edge_numbers(model: Model) -> np.ndarray:
    """(E, 2) int64: the model's undirected edges as (lower, higher) welded vertex pairs, in
    their stable order; a line's source edge ``i`` is row ``i``.

    The one place the numbering is made: the adjacency of the model welded within each part
    (``adjacency``, cached per mesh), whose edges are the sorted unique pairs of welded
    vertices, themselves numbered in the order of the model's vertices. It numbers the flattened
    model that ``Model.faces`` and ``Model.positions`` give; that of a model kept as instances
    is made arithmetically, instance after instance (``instanced``), without flattening it.
    """
    if model.instances is not None:
        from .instanced import instanced_edge_numbers

        return instanced_edge_numbers(model)
    return adjacency(model).edges


def edge_segments(model: Model, edges: np.ndarray) -> np.ndarray:
    """(N, 2, 3) float64 model-space ends of the edges numbered ``edges`` (N,) int.

    Raises ``InputError`` naming the first index that is no edge of the model.
    """
    if model.instances is not None:
        from .instanced import instanced_edge_segments

        return instanced_edge_segments(model, edges)
    adj = adjacency(model)
    edges = np.asarray(edges, np.int64).reshape(-1)
    bad = (edges < 0) | (edges >= len(adj.edges))
    if bad.any():
        raise InputError(
            f"{model.source or 'model'}: edge {int(edges[np.argmax(bad)])} is no edge of the model "
            f"(it has {len(adj.edges)}: 0 to {len(adj.edges) - 1})"
        )
    return adj.positions[adj.edges[edges]]


def _welded_adjacency(model: Model) -> Adjacency:
    part = model.face_part
    if len(model.part_names) <= 1 or len(part) == 0 or np.all(part == part[0]):
        # the weld reads float32 positions and narrow indices as they are: its vertices, and
        # what they are welded into, are the same as from float64 copies
        return build_adjacency(model.positions, model.faces)
    positions = model.positions.astype(np.float64)
    faces = model.faces.astype(np.int64)
    part = part.astype(np.int64)
    diagonal = _diagonal(positions)
    if len(faces):  # the used vertices' diagonal: the model's bounds are their extremes
        diagonal = float(np.linalg.norm(np.diff(model.bounds, axis=0))) or 1.0
    span = 4.0 * (float(column_ptp(positions).max()) + diagonal)
    # one vertex per (vertex, part) in use, moved by its part's multiple of the span
    corner_part = np.repeat(part, 3)
    corner = faces.reshape(-1)
    part_of = np.zeros(len(positions), np.int64)
    part_of[corner] = corner_part
    if np.array_equal(part_of[corner], corner_part):
        # each vertex in one part: the vertex orders the keys alone, over a range that
        # renumbered counts over instead of sorting
        used, inverse = renumbered(corner)
        unique = used * len(model.part_names) + part_of[used]
    else:
        unique, inverse = renumbered(corner * len(model.part_names) + corner_part)
    moved = positions[unique // len(model.part_names)].copy()
    moved[:, 0] += (unique % len(model.part_names)) * span
    held = build_adjacency(moved, inverse.reshape(-1, 3), weld_tol=1e-6 * diagonal)
    vertex_part = np.zeros(len(held.positions), np.int64)
    vertex_part[held.faces.reshape(-1)] = np.repeat(part, 3)
    moved = held.positions.copy()
    moved[:, 0] -= vertex_part * span
    held = replace(held, positions=moved)
    return held


def feature_segments(
    model: Model,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    crease_angle: float = 30.0,
    smooth: bool = True,
) -> Segments:
    """Silhouettes, borders and creases of every part (from ``classify_edges``), each with
    its edge (``edge_numbers``).

    With ``smooth``, silhouettes where the surface is smooth are its smooth contours
    (``silhouette.smooth_contours``: the zero set of the interpolated ``n . v`` inside the
    faces, kind ``SILHOUETTE``, faces ``(face, -1)``, its source edges those it crosses); the
    mesh's own silhouette edges are kept where a face beside them is not smooth (on a crease,
    a border).

    An edge where a face seen edge-on meets one that is not is a silhouette too (the outline
    runs along it, whichever way the faces' facing rounds).

    Borders that coincide with a border of another part are part boundaries (a surface split
    into parts) and come out with that kind. Creases whose faces meet at less than
    ``SMOOTH_ANGLE`` (drawn where the crease angle is lower still) are tangent edges of smooth
    blends: kind ``SMOOTH``.

    A model kept as instances gives its lines from its unique meshes, placed per instance
    (``instanced``), never flattened.
    """
    if model.instances is not None:
        return _instanced_feature_segments(model, view, projection, size, crease_angle, smooth)
    adj = adjacency(model)
    width, height = size
    edges = _with_edge_on_outlines(
        adj, _classified(model, adj, view, projection, size, crease_angle), view, projection, size
    )
    face_part = model.face_part.astype(np.int64)
    part = face_part[np.maximum(edges.faces[:, 0], 0)]
    kind = edges.kind.copy()
    normals = adj.face_normals
    # an outline edge beside a face seen edge-on (a box's side in a plan view) is a silhouette
    # whichever side of zero that face's facing rounds to
    crease = np.flatnonzero(kind == CREASE)
    edge_on = _faces_edge_on(adj, view, projection, _EDGE_ON)
    kind[crease[edge_on[edges.faces[crease]].any(axis=1)]] = SILHOUETTE
    min_cos = np.cos(np.radians(SMOOTH_ANGLE))
    crease = np.flatnonzero(kind == CREASE)
    cos = np.einsum("ij,ij->i", normals[edges.faces[crease, 0]], normals[edges.faces[crease, 1]])
    kind[crease[cos >= min_cos]] = SMOOTH
    _mark_part_boundaries(kind, edges.segments3d, part, len(model.part_names), _diagonal(adj.positions))
    found = Segments(edges.segments3d, edges.faces, part.astype(np.int32), kind, edges.edges)
    if not smooth or len(adj.faces) == 0:
        return found
    return _with_smooth_contours(model, adj, edges, found, view, projection, size, crease_angle)


def _mark_part_boundaries(
    kind: np.ndarray, points: np.ndarray, part: np.ndarray, parts: int, diagonal: float
):
    """Set to ``PART_BOUNDARY`` in ``kind`` (N,) the borders whose ends (``points`` (N, 2, 3))
    are those of a border of another part (``part`` (N,)): a surface split into parts."""
    border = np.flatnonzero(kind == BORDER)
    if len(border) <= 1 or parts <= 1:
        return
    ends = points[border].reshape(-1, 3)
    ids = _point_ids(ends, _JOIN_REL * diagonal).reshape(-1, 2)
    key = np.sort(ids, axis=1) @ np.array([int(ids.max()) + 1, 1])
    order = np.lexsort((part[border], key))
    key_sorted, part_sorted = key[order], part[border][order]
    # a key held by more than one part: its first and last entries differ in part
    first = np.r_[True, key_sorted[1:] != key_sorted[:-1]]
    group = np.cumsum(first) - 1
    first_at = np.flatnonzero(first)
    last_at = np.r_[first_at[1:] - 1, len(key_sorted) - 1]
    shared = (part_sorted[first_at] != part_sorted[last_at])[group]
    kind[border[order[shared]]] = PART_BOUNDARY


def _instanced_feature_segments(model: Model, view, projection, size, crease_angle: float, smooth: bool):
    """``feature_segments`` of a model kept as instances: the lines of ``instanced_features``,
    part boundaries and smooth contours joined to the silhouettes as ``_with_smooth_contours``
    joins them."""
    from .instanced import instanced_features

    found = instanced_features(
        model,
        view,
        projection,
        size,
        crease_angle,
        smooth,
        SMOOTH_ANGLE,
        _EDGE_ON,
        _EDGE_ON_SMOOTH,
        _edge_on_outline_edges,
    )
    diagonal = float(np.linalg.norm(np.diff(model.bounds, axis=0))) or 1.0
    kind, faces = found["kind"], found["faces"]
    _mark_part_boundaries(kind, found["points"], found["part"], len(model.part_names), diagonal)
    edges = Segments(found["points"], faces, found["part"], kind, found["edge"])
    if not smooth:
        return edges
    points, pixels = found["contour_points"], found["contour_pixels"]
    short, _ = _short_runs(points, pixels, _MIN_CONTOUR_PX)
    exact = found["exact"] | np.isin(faces, found["contour_face"][short])
    replaced = found["silhouette"] & ~exact.any(axis=1) & (faces >= 0).all(axis=1)
    keep = ~short
    points, face, edge_pairs = points[keep], found["contour_face"][keep], found["contour_edges"][keep]
    part, vertices = found["contour_part"][keep], found["contour_vertices"][keep]
    vertex_points = found["contour_vertex_points"][keep]
    # open contour ends run on to the end of their edge where a kept silhouette starts
    bridge = np.zeros((0, 2, 3))
    bridge_face = bridge_part = bridge_edge = np.zeros(0, np.int64)
    kept = found["vertices"][found["silhouette"] & ~replaced].reshape(-1)
    if len(points) and len(kept):
        ends = points.reshape(-1, 3)
        ids = _point_ids(ends, _JOIN_REL * diagonal)
        open_end = np.flatnonzero(np.bincount(ids)[ids] == 1)
        pair = vertices.reshape(-1, 2)[open_end]
        on_kept = np.isin(pair, kept)
        second = ~on_kept[:, 0]
        joined = on_kept[np.arange(len(pair)), second.astype(np.int64)]
        open_end, second = open_end[joined], second[joined]
        end_points = vertex_points.reshape(-1, 2, 3)[open_end, second.astype(np.int64)]
        bridge = np.stack([ends[open_end], end_points], axis=1)
        bridge_face, bridge_part = face[open_end // 2], part[open_end // 2]
        bridge_edge = edge_pairs.reshape(-1)[open_end]
    contour_faces = np.concatenate([face, bridge_face])
    edge_pairs = np.concatenate([edge_pairs, np.stack([bridge_edge, bridge_edge], axis=1)])
    return Segments.concatenate(
        [
            edges.taken(parallel.flatnonzero(replaced, negated=True)),
            Segments(
                np.concatenate([points, bridge]),
                np.stack([contour_faces, np.full(len(contour_faces), -1)], axis=1),
                np.concatenate([part, bridge_part]).astype(np.int32),
                np.full(len(contour_faces), SILHOUETTE, np.uint8),
                edge_pairs[:, 0],
                edge_pairs[:, 1],
            ),
        ]
    )


def _with_edge_on_outlines(adj: Adjacency, edges: EdgeSet, view, projection, size) -> EdgeSet:
    """``edges`` (``classify_edges``' of ``adj``) with the two-face edges where a face seen
    edge-on meets one that is not, as silhouettes, in edge order, for the edge-on faces that
    have no such edge among ``edges`` yet. ``n . v`` is zero all over the edge-on face, so the
    outline runs along such an edge; where the faces meet at less than the crease angle and
    their facing rounds to one side (a fillet seen along its axis, where it meets the blend at
    its end) ``classify_edges`` finds nothing there, and the outline had a gap. A face that has
    one already (a sphere's face on its outline, between faces turned to and from the eye)
    projects onto it: its other edges would only draw the line again, in pieces."""
    edge, face = adj.edge_faces[:, 0], adj.edge_faces[:, 1]
    count = np.bincount(edge, minlength=len(adj.edges))
    start = np.cumsum(count) - count
    two = np.flatnonzero(count == 2)
    pair = np.stack([face[start[two]], face[start[two] + 1]], axis=1)
    edge_on = _faces_edge_on(adj, view, projection, _EDGE_ON)
    found = np.zeros(len(adj.edges), bool)
    found[edges.edges] = True
    chosen = _edge_on_outline_edges(edge_on, pair, found[two])
    # wholly in front of the eye, as no clipping is done here (a sample nearer than the near
    # plane falls outside the view and is left out)
    ends = adj.positions[adj.edges[two[chosen]]].reshape(-1, 3)
    clip = transform(ends, projection @ view)
    ahead = (clip[:, 3] > 0).reshape(-1, 2).all(axis=1)
    new, pair = two[chosen][ahead], pair[chosen][ahead]
    if len(new) == 0:
        return edges
    points = adj.positions[adj.edges[new]]
    pixels = clip_to_pixels(clip.reshape(-1, 2, 4)[ahead].reshape(-1, 4), size).reshape(-1, 2, 2)
    order = stable_argsort(np.r_[edges.edges, new])
    return EdgeSet(
        segments3d=np.concatenate([edges.segments3d, points])[order],
        segments2d=np.concatenate([edges.segments2d, pixels])[order],
        kind=np.r_[edges.kind, np.full(len(new), SILHOUETTE, np.uint8)][order],
        faces=np.concatenate([edges.faces, pair])[order],
        edges=np.r_[edges.edges, new][order],
    )


def _edge_on_outline_edges(edge_on: np.ndarray, pair: np.ndarray, found: np.ndarray) -> np.ndarray:
    """(..., E) bool: the two-face edges that become silhouettes (``_with_edge_on_outlines``),
    for one view or a block of instances of one mesh at once (the leading axes ``...``): those
    where a face seen edge-on meets one that is not, not found already, whose edge-on face has
    no such edge among those found.

    Parameters
    ----------
    edge_on : np.ndarray
        (..., F) bool, the faces seen edge-on.
    pair : np.ndarray
        (E, 2) int, the two faces of each two-face edge.
    found : np.ndarray
        (..., E) bool, those edges among the lines found already (silhouettes and creases,
        as ``classify_edges`` keeps them).
    """
    side = edge_on[..., pair]
    one_side = side[..., 0] != side[..., 1]
    flat_side = np.where(side[..., 0], pair[:, 0], pair[:, 1])
    outlined = np.zeros(edge_on.shape, bool)
    at = np.nonzero(one_side & found)
    outlined[(*at[:-1], flat_side[at])] = True
    return one_side & ~found & ~np.take_along_axis(outlined, flat_side, axis=-1)


def _with_smooth_contours(
    model, adj, edges, found: Segments, view, projection, size, crease_angle
) -> Segments:
    """``found``, the lines of ``classify_edges``' ``edges``, with the silhouettes where the
    surface is smooth replaced by its smooth contours (``feature_segments``)."""
    contours, _, replaced, _ = _contour_segments(
        model, adj, edges, found.kind, view, projection, size, crease_angle
    )
    return Segments.concatenate(
        [
            Segments(
                found.points[~replaced],
                found.faces[~replaced],
                found.part[~replaced],
                found.kind[~replaced],
                found.edge[~replaced],
            ),
            contours,
        ]
    )


def smooth_contour_segments(
    model: Model, view: np.ndarray, projection: np.ndarray, size: tuple[int, int], crease_angle: float = 30.0
) -> tuple[Segments, np.ndarray]:
    """The smooth contours of a model not kept as instances, for one view, as
    ``feature_segments`` draws them (with the bridges to the mesh silhouettes they meet), and
    (F,) bool: the faces whose own silhouettes they replace there (smooth, not seen edge-on,
    not on a contour run too short to stand for them unless it closes on itself)."""
    adj = adjacency(model)
    if len(adj.faces) == 0:
        return Segments.empty(), np.zeros(model.triangle_count, bool)
    width, height = size
    edges = _with_edge_on_outlines(
        adj, _classified(model, adj, view, projection, size, crease_angle), view, projection, size
    )
    contours, exact, _, loops = _contour_segments(
        model, adj, edges, edges.kind, view, projection, size, crease_angle
    )
    # a short contour closed on itself is a bump of the surface's noise seen at its edge: the
    # mesh's silhouette there would draw it again, as a speck
    contoured = ~exact
    contoured[loops] = True
    return contours, contoured


def grazing_band(model: Model, view: np.ndarray, projection: np.ndarray, crease_angle: float = 30.0):
    """(F + 1,) float32: for each face of a model not kept as instances where its smooth
    surface turns within ``GRAZING_DEGREES`` of the view (a smooth face, not seen edge-on,
    with a vertex normal that close to square with the view), the length of its longest edge;
    0 elsewhere and in the last row (no face). None for a model kept as instances.

    Near its contour a noisy smooth surface folds over itself: the contour of its
    interpolated normals lies a little behind the mesh's own rim, whose faces would hide it
    from the view. Those faces do not hide a smooth contour unless they lie farther in front of
    it than ``GRAZING_REACH`` of their own sizes (``occlusion.levels``)."""
    if model.instances is not None:
        return None
    adj = adjacency(model)
    band = np.zeros(len(adj.faces) + 1, np.float32)
    if len(adj.faces) == 0:
        return band
    surface = _surface(model, adj, crease_angle)
    toward = toward_eye(adj.positions, view, projection)
    facing = np.einsum("ij,ij->i", surface.normals, toward) / np.linalg.norm(toward, axis=1)
    grazing = (np.abs(facing) < np.sin(np.radians(GRAZING_DEGREES)))[adj.faces].any(axis=1)
    edge_on = _faces_edge_on(adj, view, projection)
    chosen = np.flatnonzero(grazing & surface.smooth & ~edge_on)
    corners = adj.positions[adj.faces[chosen]]
    band[chosen] = np.linalg.norm(corners - corners[:, [1, 2, 0]], axis=2).max(axis=1)
    return band


def _classified(model: Model, adj: Adjacency, view, projection, size, crease_angle: float) -> EdgeSet:
    """``classify_edges`` of ``model``'s adjacency ``adj`` for one view."""
    width, height = size
    sharp = _sharp(model, adj, crease_angle)
    return classify_edges(adj, view, projection, width, height, crease_angle, sharp=sharp)


def _sharp(model: Model, adj: Adjacency, crease_angle: float) -> np.ndarray:
    """The sharp edges of ``model``'s adjacency ``adj``, which no view changes, found once a
    mesh and angle (``SHARP``): the edges' classes and the smooth surface read them."""
    held = SHARP.get(model, dict)
    if crease_angle not in held:
        held[crease_angle] = mesh_sharp_edges(adj, crease_angle)
    return held[crease_angle]


def _surface(model: Model, adj: Adjacency, crease_angle: float) -> SmoothSurface:
    """The smooth surface of ``model`` (its adjacency ``adj``) at ``crease_angle``, made once a
    mesh and angle (``SURFACES``)."""
    surface = SURFACES.get(model, dict)
    if crease_angle not in surface:
        surface[crease_angle] = smooth_surface(adj, crease_angle, _sharp(model, adj, crease_angle))
    return surface[crease_angle]


def _faces_edge_on(
    adj: Adjacency, view: np.ndarray, projection: np.ndarray, within: float = _EDGE_ON_SMOOTH
) -> np.ndarray:
    """(F,) bool: the faces seen edge-on, within ``within`` (a cosine) of a right angle, by
    default within rounding of smooth contours'."""
    return _face_cosines(adj, view, projection) <= within


# The |cos| of the last view's faces (``_face_cosines``): its outlines, contours and grazing
# band each ask for them. The adjacency is held weakly, and the entry let go with it: the
# adjacency caches (``ADJACENCY``) decide how long a mesh's line work lives.
_COSINES: list = [None, b"", None]


def _forget_cosines(ref: weakref.ref) -> None:
    if _COSINES[0] is ref:  # (not a later view's entry)
        _COSINES[:] = [None, b"", None]


def _face_cosines(adj: Adjacency, view: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """(F,) float64: |cos| of the angle between each face's normal and the direction from its
    first corner to the eye; kept for the last view asked."""
    key = np.asarray(view, np.float64).tobytes() + np.asarray(projection, np.float64).tobytes()
    held, held_key, cosines = _COSINES
    if held is not None and held() is adj and held_key == key:
        return cosines
    camera_to_model = np.linalg.inv(view)
    normal = adj.face_normals
    if projection[3, 3] == 1.0:
        toward = np.broadcast_to(camera_to_model[:3, 2], normal.shape)
    else:
        toward = camera_to_model[:3, 3] - np.take(adj.positions, adj.faces[:, 0], axis=0)
    dot = np.einsum("ij,ij->i", normal, toward)
    cosines = np.abs(dot) / np.maximum(np.linalg.norm(toward, axis=1), 1e-300)
    _COSINES[:] = [weakref.ref(adj, _forget_cosines), key, cosines]
    return cosines


def _contour_segments(model, adj, edges, kind, view, projection, size, crease_angle):
    """The smooth contours and their bridges (``smooth_contour_segments``), (F,) bool: the
    faces that keep their mesh silhouettes, (E,) bool: the silhouette edges of ``edges`` (of
    ``kind`` as the drawing has them) that the contours replace, and the faces of the short
    contours left out that close on themselves."""
    surface = _surface(model, adj, crease_angle)
    # faces seen edge-on (a hole's wall along the view) have no contour to give: their
    # vertices' n . v rounds either way, so the mesh's outline edges stay there
    edge_on = _faces_edge_on(adj, view, projection)
    surface = replace(surface, smooth=surface.smooth & ~edge_on)
    contours = smooth_contours(adj, surface, view, projection, size)
    # where a contour runs only a few pixels before it meets a feature, the mesh's own
    # silhouette there stays: one line in one piece, not a stub between two gaps
    short, closed = _short_runs(contours.segments3d, contours.segments2d, _MIN_CONTOUR_PX)
    exact = ~surface.smooth
    exact[contours.faces[short]] = True
    loops = contours.faces[short & closed]
    contours = replace(
        contours,
        segments3d=contours.segments3d[~short],
        segments2d=contours.segments2d[~short],
        faces=contours.faces[~short],
        edges=contours.edges[~short],
    )
    # a silhouette edge whose faces are all smooth is replaced by the contour across them
    sides = edges.faces
    replaced = (edges.kind == SILHOUETTE) & (kind == SILHOUETTE)
    replaced &= ~exact[np.maximum(sides, 0)].any(axis=1) & (sides >= 0).all(axis=1)
    bridge, bridge_face, bridge_edge = _bridges(
        adj, contours, edges.edges[(edges.kind == SILHOUETTE) & ~replaced]
    )
    points = np.concatenate([contours.segments3d, bridge])
    faces = np.concatenate([contours.faces, bridge_face])
    edge_pairs = np.concatenate([contours.edges, np.stack([bridge_edge, bridge_edge], axis=1)])
    segments = Segments(
        points,
        np.stack([faces, np.full(len(faces), -1)], axis=1),
        model.face_part[faces].astype(np.int32),
        np.full(len(faces), SILHOUETTE, np.uint8),
        edge_pairs[:, 0],
        edge_pairs[:, 1],
    )
    return segments, exact, replaced, loops


def _bridges(adj: Adjacency, contours, kept: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments (K, 2, 3) from each open end of the ``contours`` (a ``ContourSet``) to the end
    of its edge where a ``kept`` mesh silhouette edge (adjacency edge numbers) starts, their
    faces (K,) and edges (K,): where a contour meets a feature, the outline runs on without a
    gap of a triangle."""
    none = np.zeros((0, 2, 3)), np.zeros(0, np.int64), np.zeros(0, np.int64)
    if len(contours.faces) == 0 or len(kept) == 0:
        return none
    ends = contours.segments3d.reshape(-1, 3)
    ids = _point_ids(ends, _JOIN_REL * _diagonal(adj.positions))
    open_end = np.flatnonzero(np.bincount(ids)[ids] == 1)
    on_kept = np.zeros(len(adj.positions), bool)
    on_kept[adj.edges[kept].reshape(-1)] = True
    edge = contours.edges.reshape(-1)[open_end]
    a, b = adj.edges[edge, 0], adj.edges[edge, 1]
    vertex = np.where(on_kept[a], a, b)
    joined = on_kept[vertex]
    open_end, edge, vertex = open_end[joined], edge[joined], vertex[joined]
    bridge = np.stack([ends[open_end], adj.positions[vertex]], axis=1)
    return bridge, contours.faces[open_end // 2], edge


def _short_runs(points: np.ndarray, pixels: np.ndarray, shortest: float) -> tuple[np.ndarray, np.ndarray]:
    """(N,) bool twice: the segments (model ``points`` (N, 2, 3), ``pixels`` (N, 2, 2)) in runs
    (those joined end to end) shorter than ``shortest`` pixels on screen, and those in runs
    that close on themselves (every end met by another)."""
    if len(points) == 0:
        return np.zeros(0, bool), np.zeros(0, bool)
    ids = _point_ids(points.reshape(-1, 3), _JOIN_REL * _diagonal(points.reshape(-1, 3))).reshape(-1, 2)
    run = connected_components_of(np.arange(int(ids.max()) + 1), ids[:, 0], ids[:, 1])[ids[:, 0]]
    length = np.bincount(run, np.linalg.norm(pixels[:, 1] - pixels[:, 0], axis=1))
    alone = (np.bincount(ids.reshape(-1)) == 1)[ids].any(axis=1)
    open_run = np.bincount(run, alone, minlength=len(length)) > 0
    return length[run] < shortest, ~open_run[run]


# -- intersections between parts ------------------------------------------------------------------


def _columns_max(values: np.ndarray) -> np.ndarray:
    """The largest of each row of (n, 3) (a reduction over a short axis is slow in NumPy)."""
    return np.maximum(np.maximum(values[:, 0], values[:, 1]), values[:, 2])


def _candidate_triangles(lo, hi, part, parts: int, slack: float) -> np.ndarray:
    """Triangles whose box meets the box of another part, widened by ``slack``: those that can
    meet another part's triangles (the box of a triangle lies in its own part's box, so it
    meets where the two parts' boxes overlap).

    The parts whose widened boxes overlap come from a uniform grid where they are many
    (``_overlapping_boxes``), so time and memory follow the triangles and the pairs of
    overlapping parts, not the parts squared; each part's triangles are then tested against
    its partners one by one or, where they are many, a word of 64 parts at a time
    (``_by_words``).
    """
    order = stable_argsort(part)
    bounds = np.searchsorted(part[order], np.arange(parts + 1))
    live = np.flatnonzero(bounds[1:] > bounds[:-1])
    keep = np.zeros(len(lo), bool)
    if len(live) < 2:
        return np.flatnonzero(keep)
    box_lo = np.full((parts, 3), np.inf)
    box_hi = np.full((parts, 3), -np.inf)
    # the triangles' boxes by part, an axis a row: a part's triangles are a run of each row
    lo, hi = np.take(lo.T, order, axis=1), np.take(hi.T, order, axis=1)
    box_lo[live] = np.minimum.reduceat(lo, bounds[live], axis=1).T
    box_hi[live] = np.maximum.reduceat(hi, bounds[live], axis=1).T
    near_lo, near_hi = box_lo - slack, box_hi + slack
    # where a triangle of p meets q's widened box, the widened boxes of p and q overlap (rounding
    # is monotonic): the pairs of those are all the partners there are
    a, b = _overlapping_boxes(near_lo[live], near_hi[live])
    p, q = live[np.r_[a, b]], live[np.r_[b, a]]
    words = (parts + 63) // 64
    part_word = unique_first(p * words + q // 64)[0]
    dense = _by_words(np.bincount(p, minlength=parts), np.bincount(part_word // words, minlength=parts))
    sparse = ~dense[p]
    _meet_parts(keep, lo, hi, bounds, p[sparse], q[sparse], near_lo, near_hi)
    part_word = part_word[dense[part_word // words]]
    _meet_words(keep, lo, hi, bounds, part_word // words, part_word % words, near_lo, near_hi, live)
    found = np.zeros(len(order), bool)
    found[order] = keep
    return np.flatnonzero(found)


def _overlapping_boxes(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i, j), i < j, of the boxes (n, 3) that overlap or touch: every pair tested at once
    where there are few boxes (a grid of few boxes that overlap much holds each many times),
    else through a uniform grid (``_candidate_pairs``)."""
    if len(lo) ** 2 > _DENSE_PAIRS:
        return _candidate_pairs(lo, hi, np.arange(len(lo)), 0.0)
    hit = (lo[:, None, 0] <= hi[None, :, 0]) & (hi[:, None, 0] >= lo[None, :, 0])
    for axis in (1, 2):
        hit &= (lo[:, None, axis] <= hi[None, :, axis]) & (hi[:, None, axis] >= lo[None, :, axis])
    i, j = np.nonzero(hit)
    upper = i < j
    return i[upper], j[upper]


def _by_words(partners: np.ndarray, words: np.ndarray) -> np.ndarray:
    """(parts,) bool: the parts whose triangles are cheaper to test against the ``words`` of 64
    parts that hold their ``partners`` than against each partner: a test against a word costs
    about what a test against a box does, plus ``_WORD_SEARCHES`` tests a triangle for finding
    its place among the parts' ends."""
    return partners > _WORD_SEARCHES + words


def _spans(first: np.ndarray, count: np.ndarray, weight=1):
    """The runs ``first[k] + range(count[k])`` of indices, concatenated in blocks of about
    ``_PAIR_CHUNK`` indices (each of run ``k`` counting ``weight[k]``): yields ``(k, index)``
    per block, ``k`` the run each index comes from."""
    size = count * weight
    block = (np.cumsum(size) - size) // _PAIR_CHUNK
    cuts = np.r_[0, np.flatnonzero(np.diff(block)) + 1, len(count)]
    for start, stop in zip(cuts[:-1], cuts[1:], strict=True):
        m = count[start:stop]
        k = np.repeat(np.arange(start, stop), m)
        yield k, np.repeat(first[start:stop], m) + (np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m))


def _meet_parts(keep, lo, hi, bounds, p, q, near_lo, near_hi) -> None:
    """Mark in ``keep`` the triangles of part ``p[k]`` whose box meets the box ``near_lo``,
    ``near_hi`` of part ``q[k]``, for every k; triangles by part, part ``p``'s from
    ``bounds[p]`` to ``bounds[p + 1]``, their boxes' ends ``lo``, ``hi`` (3, n) an axis a row."""
    near_lo, near_hi = np.ascontiguousarray(near_lo.T), np.ascontiguousarray(near_hi.T)
    for k, t in _spans(bounds[p], bounds[p + 1] - bounds[p]):
        other = q[k]
        meets = lo[0].take(t) <= near_hi[0].take(other)
        for axis in range(3):
            if axis:
                meets &= lo[axis].take(t) <= near_hi[axis].take(other)
            meets &= hi[axis].take(t) >= near_lo[axis].take(other)
        keep[t[meets]] = True


def _meet_words(keep, lo, hi, bounds, p, w, near_lo, near_hi, live) -> None:
    """Mark in ``keep`` the triangles of part ``p[k]`` whose box meets the box ``near_lo``,
    ``near_hi`` of a part of word ``w[k]`` (parts ``64 w`` to ``64 w + 63``) but its own; ``p``
    ascending, ``live`` the parts that hold triangles, the rest as in ``_meet_parts``.

    Along an axis, the parts whose widened box starts at or below a triangle's high end are
    the first of the parts ranked by start, those ending at or above its low end the last of
    the parts ranked by end: a search a triangle and end gives the rank, and a table a word of
    the union of its parts' bits up to (or from) each rank the word's parts met. Words go in
    blocks of ``_BLOCK_WORDS``, ranked among the block's parts, so that the tables stay small.
    """
    if len(w) == 0:
        return
    used = np.flatnonzero(np.bincount(w))
    slot_of = np.zeros(used[-1] + 1, np.int64)
    slot_of[used] = np.arange(len(used))
    # the (part, word) pairs by block, parts still ascending within one
    block_of = slot_of[w] // _BLOCK_WORDS
    by_block = stable_argsort(block_of)
    cuts = np.searchsorted(block_of[by_block], np.arange(-(-len(used) // _BLOCK_WORDS) + 1))
    live_word = live // 64
    for block in range(len(cuts) - 1):
        block_words = used[block * _BLOCK_WORDS : (block + 1) * _BLOCK_WORDS]
        members = live[
            np.searchsorted(live_word, block_words[0]) : np.searchsorted(live_word, block_words[-1] + 1)
        ]
        members = members[np.isin(members // 64, block_words)]
        slot = slot_of[members // 64] - block * _BLOCK_WORDS
        bit = np.left_shift(np.uint64(1), (members % 64).astype(np.uint64))
        width = len(members) + 1
        axes = []
        for axis in range(3):
            ranked = []
            for ends, side in ((near_lo[members, axis], 1), (near_hi[members, axis], 0)):
                by_end = np.argsort(ends)
                rank = np.empty(len(members), np.int64)
                rank[by_end] = np.arange(len(members))
                table = np.zeros((len(block_words), width), np.uint64)
                # bits summed, not or-ed: a word's bits are distinct
                if side:
                    table[slot, rank + 1] = bit
                    table = np.cumsum(table, axis=1)
                else:
                    table[slot, rank] = bit
                    table = np.cumsum(table[:, ::-1], axis=1)[:, ::-1]
                ranked.append((ends[by_end], table.ravel()))
            axes.append(ranked)
        chosen = by_block[cuts[block] : cuts[block + 1]]
        pairs_p, pairs_w = p[chosen], slot_of[w[chosen]] - block * _BLOCK_WORDS
        first = np.flatnonzero(np.diff(pairs_p, prepend=-1))
        owners, words = pairs_p[first], np.diff(np.r_[first, len(pairs_p)])
        # per (part, word): where the word's table starts, and the bits left once its own is out
        start = pairs_w * width
        own = np.where(block_words[pairs_w] == pairs_p // 64, pairs_p % 64, 64).astype(np.uint64)
        others = ~np.left_shift(np.uint64(1), own, where=own < 64, out=np.zeros(len(own), np.uint64))
        for k, t in _spans(bounds[owners], bounds[owners + 1] - bounds[owners], words):
            # each triangle once a word of its part's
            m = words[k]
            pair = np.repeat(first[k], m) + (np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m))
            at, met = start[pair], others[pair]
            for axis, ((starts, below), (stops, above)) in enumerate(axes):
                met &= below[at + np.repeat(np.searchsorted(starts, hi[axis, t], side="right"), m)]
                met &= above[at + np.repeat(np.searchsorted(stops, lo[axis, t], side="left"), m)]
            keep[np.repeat(t, m)[met != 0]] = True


@dataclass(frozen=True)
class CellGrid:
    """Boxes entered in the cells of a uniform grid (``cell_grid``), for pairing across parts.

    ``first`` (n, 3) is each box's first cell; entry ``e`` (sorted by cell, then part) puts box
    ``owner[e]`` in cell ``key[e]``; its partners from other parts are the entries from
    ``group_end[e]`` (the end of its part's run in the cell) to ``cell_end[e]``.
    """

    first: np.ndarray
    key: np.ndarray
    owner: np.ndarray
    group_end: np.ndarray
    cell_end: np.ndarray
    base: np.ndarray
    dims: np.ndarray

    def cell_key(self, x, y, z):
        return _cell_key(self.base, self.dims, x, y, z)

    def cells(self, entries: np.ndarray) -> np.ndarray:
        """(len(entries), 3) cell coordinates of entries."""
        rest, x = np.divmod(self.key[entries], self.dims[0])
        z, y = np.divmod(rest, self.dims[1])
        return np.stack([x, y, z], axis=1) + self.base


def _cell_key(base, dims, x, y, z):
    return ((z - base[2]) * dims[1] + (y - base[1])) * dims[0] + (x - base[0])


def cell_grid(lo, hi, part, slack: float) -> CellGrid:
    """Each box (``lo`` <= ``hi``) entered in every cell it touches, the entries sorted by cell
    and then part.

    Cells start at the median box size and double while the entries would exceed a fixed
    multiple of the box count.
    """
    n = len(lo)
    origin = column_min(lo)
    extent = (column_max(hi) - origin).max() or 1.0
    cell = max(float(np.median(_columns_max(hi - lo))), extent / 4096)
    low, high = lo - slack - origin, hi + slack - origin
    while True:
        first = np.floor(low / cell).astype(np.int64)
        last = np.floor(high / cell).astype(np.int64)
        span = last - first + 1
        entries = span[:, 0] * span[:, 1] * span[:, 2]
        if entries.sum() <= _CELLS_PER_TRIANGLE * n + 4096 or cell >= extent:
            break
        cell *= 2.0
    owner = np.repeat(np.arange(n), entries)
    rank = np.arange(len(owner)) - np.repeat(np.cumsum(entries) - entries, entries)
    base = column_min(first)
    dims = column_max(last) + 2 - base
    # entry (dx, dy, dz) of a box is its first cell's key plus that step: per-box values
    # repeated, two divisions an entry
    across, dx = np.divmod(rank, np.repeat(span[:, 0], entries))
    dz, dy = np.divmod(across, np.repeat(span[:, 1], entries))
    step = (dz * dims[1] + dy) * dims[0] + dx
    key = np.repeat(_cell_key(base, dims, first[:, 0], first[:, 1], first[:, 2]), entries) + step
    # entries by cell, then by part: an entry's partners from other parts are the rest of its
    # cell after its own part's run, so only pairs across parts are ever generated
    parts = int(part.max()) + 1
    if float(np.prod(dims.astype(np.float64))) * parts < 2.0**62:
        order = stable_argsort(key * parts + part[owner])
    else:
        order = np.lexsort((part[owner], key))
    key, owner = key[order], owner[order]
    entry_part = part[owner]
    new_cell = np.r_[True, key[1:] != key[:-1]]
    new_group = new_cell | np.r_[True, entry_part[1:] != entry_part[:-1]]
    cell_start = np.flatnonzero(new_cell)
    group_start = np.flatnonzero(new_group)
    cell_end = np.r_[cell_start[1:], len(key)][np.cumsum(new_cell) - 1]
    group_end = np.r_[group_start[1:], len(key)][np.cumsum(new_group) - 1]
    return CellGrid(first, key, owner, group_end, cell_end, base, dims)


def _candidate_pairs(lo, hi, part, slack: float):
    """Pairs (i, j) of triangles of different parts whose boxes overlap, through a uniform grid
    (``cell_grid``).

    A pair is reported only in the cell at the componentwise maximum of the two boxes' first
    cells, which both touch, so no pair comes out twice; pairs come in the order of their
    first entry in the grid, then of the second.
    """
    if len(lo) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    grid = cell_grid(lo, hi, part, slack)
    key, owner, group_end, first = grid.key, grid.owner, grid.group_end, grid.first
    partners = grid.cell_end - group_end
    lo_axis = [np.ascontiguousarray(lo[:, a]) for a in range(3)]
    hi_axis = [np.ascontiguousarray(hi[:, a] + slack) for a in range(3)]
    first_axis = [np.ascontiguousarray(first[:, a]) for a in range(3)]
    pairs_i, pairs_j = [], []
    batch = (np.cumsum(partners) - partners) // _PAIR_CHUNK
    bounds = np.r_[0, np.flatnonzero(np.diff(batch)) + 1, len(partners)]
    for lo_b, hi_b in zip(bounds[:-1], bounds[1:], strict=True):
        m = partners[lo_b:hi_b]
        busy = np.flatnonzero(m)
        if len(busy) == 0:
            continue
        m, entry = m[busy], lo_b + busy
        ia = np.repeat(entry, m)
        ib = np.repeat(group_end[entry], m) + (np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m))
        j = np.take(owner, ib)
        # boxes overlap (axis by axis, keeping survivors; an entry's own side of its pairs is a
        # repeat, not a gather), then report a pair only in the first cell both boxes touch
        mine = owner[entry]
        keep = (np.repeat(lo_axis[0][mine], m) <= np.take(hi_axis[0], j)) & (
            np.take(lo_axis[0], j) <= np.repeat(hi_axis[0][mine], m)
        )
        ia, j = ia[keep], j[keep]
        i = np.take(owner, ia)
        for axis in (1, 2):
            keep = (np.take(lo_axis[axis], i) <= np.take(hi_axis[axis], j)) & (
                np.take(lo_axis[axis], j) <= np.take(hi_axis[axis], i)
            )
            i, j, ia = i[keep], j[keep], ia[keep]
        top = [np.maximum(np.take(first_axis[a], i), np.take(first_axis[a], j)) for a in range(3)]
        keep = grid.cell_key(*top) == key[ia]
        pairs_i.append(i[keep])
        pairs_j.append(j[keep])
    if not pairs_i:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(pairs_i), np.concatenate(pairs_j)


def _plane_cut(tri: np.ndarray, dist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two points where triangles (M, 3, 3) meet a plane, given vertex distances (M, 3).

    Callers guarantee a proper cut: signs are not all equal and at most one distance is zero,
    so exactly two of the three edge crossings and vertex touches exist.
    """
    cand = []
    valid = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        da, db = dist[:, a], dist[:, b]
        cross = da * db < 0.0
        t = np.divide(da, da - db, out=np.zeros_like(da), where=cross)
        cand.append(tri[:, a] + t[:, None] * (tri[:, b] - tri[:, a]))
        valid.append(cross)
    for a in range(3):
        cand.append(tri[:, a])
        valid.append(dist[:, a] == 0.0)
    cand = np.stack(cand, axis=1)
    valid = np.stack(valid, axis=1)
    pick = np.argsort(~valid, axis=1, kind="stable")[:, :2]
    rows = np.arange(len(tri))[:, None]
    both = cand[rows, pick]
    return both[:, 0], both[:, 1]


def _unit_normals(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals of triangles (M, 3, 3) and whether they have one (non-zero area)."""
    normal = face_cross(tri)
    length = row_norm(normal)
    return normal / np.where(length > 0, length, 1.0)[:, None], length > 0


def _triangle_pairs_cut(ta: np.ndarray, tb: np.ndarray, eps: float, normals=None):
    """Intersection segments of triangle pairs (M, 3, 3) that properly cut through each other.

    Returns the (K, 2, 3) segments and the (K,) indices of the pairs that produced them. Pairs
    that are coplanar, only touch (a vertex or an edge lying in the other's plane) or miss give
    nothing: their contact lines are mesh edges, drawn as such where they are features.
    ``normals``: ``_unit_normals`` of the triangles of A and of B, where the caller has them.
    """

    def proper(d):
        zeros = (d == 0.0).sum(axis=1)
        return (zeros <= 1) & ~(d >= 0.0).all(axis=1) & ~(d <= 0.0).all(axis=1)

    def plane_distances(tri, other, normal):
        dist = np.einsum("mij,mj->mi", tri - other[:, :1], normal)
        dist[np.abs(dist) <= eps] = 0.0
        return dist

    nb, ok_b = normals[1] if normals else _unit_normals(tb)
    # A's vertices against B's plane first: most pairs end there
    da = plane_distances(ta, tb, nb)
    idx = np.flatnonzero(ok_b & proper(da))
    na, ok_a = (normals[0][0][idx], normals[0][1][idx]) if normals else _unit_normals(ta[idx])
    db = plane_distances(tb[idx], ta[idx], na)
    keep = ok_a & proper(db)
    idx, na, db, nb, da = idx[keep], na[keep], db[keep], nb[idx][keep], da[idx][keep]
    if len(idx) == 0:
        return np.zeros((0, 2, 3)), idx
    a0, a1 = _plane_cut(ta[idx], da)
    b0, b1 = _plane_cut(tb[idx], db)
    direction = cross(na, nb)
    sa0, sa1 = np.einsum("mi,mi->m", a0, direction), np.einsum("mi,mi->m", a1, direction)
    sb0, sb1 = np.einsum("mi,mi->m", b0, direction), np.einsum("mi,mi->m", b1, direction)
    swap = sa1 < sa0
    a0, a1 = np.where(swap[:, None], a1, a0), np.where(swap[:, None], a0, a1)
    sa0, sa1 = np.minimum(sa0, sa1), np.maximum(sa0, sa1)
    lo = np.maximum(sa0, np.minimum(sb0, sb1))
    hi = np.minimum(sa1, np.maximum(sb0, sb1))
    span = sa1 - sa0
    dlen = np.linalg.norm(direction, axis=1)
    keep = (hi - lo) > eps * np.maximum(dlen, 1e-300)
    keep &= span > 0
    t0 = np.where(keep, (lo - sa0) / np.where(span > 0, span, 1.0), 0.0)
    t1 = np.where(keep, (hi - sa0) / np.where(span > 0, span, 1.0), 0.0)
    p0 = a0 + t0[:, None] * (a1 - a0)
    p1 = a0 + t1[:, None] * (a1 - a0)
    segments = np.stack([p0, p1], axis=1)[keep]
    return segments, idx[keep]


def intersection_segments(model: Model, renderer=None) -> Segments:
    """Lines where triangles of different parts cut through each other (view-independent), in
    the order of their two faces (the lower first).

    Broad phase: part boxes limit the triangles to those near another part, a uniform grid pairs
    triangles of different parts with overlapping boxes. Narrow phase: the exact segment of two
    triangles, from each one's crossing of the other's plane, vectorised over pairs. With a
    ``renderer`` (``LayerRenderer``), one compute pass makes the pairs and leaves only those
    that may cut (``cuts.gpu_cut_pairs``): the same lines, bit for bit. Cached per mesh
    (``cache``).
    """
    if model.instances is not None:
        from .instanced import instanced_intersections

        eps = _TOUCH_REL * (float(np.linalg.norm(np.diff(model.bounds, axis=0))) or 1.0)
        points, faces, part = instanced_intersections(
            model, eps, (_overlapping_boxes, triangle_cuts), renderer
        )
        return Segments(
            points, faces, part, np.full(len(part), INTERSECTION, np.uint8), np.full(len(part), -1, np.int64)
        )
    return INTERSECTIONS.get(model, lambda: _intersections(model, renderer))


def _intersections(model: Model, renderer) -> Segments:
    parts = len(model.part_names)
    if parts <= 1 or len(model.faces) == 0:
        return Segments.empty()
    eps = _TOUCH_REL * _diagonal(model.positions.astype(np.float64))
    part = model.face_part.astype(np.int64)
    points, a, b = triangle_cuts(model.corners(), part, row_norm(model.corner_cross()) > 0, eps, renderer)
    if len(a) == 0:
        return Segments.empty()
    # in the order of their faces, the lower first: the order a model kept as instances finds
    # them in, so both draw one drawing (joining and sampling follow the order)
    a, b = np.minimum(a, b), np.maximum(a, b)
    order = np.lexsort((b, a))
    points, a, b = points[order], a[order], b[order]
    return Segments(
        points,
        np.stack([a, b], axis=1),
        np.minimum(part[a], part[b]).astype(np.int32),
        np.full(len(a), INTERSECTION, np.uint8),
        np.full(len(a), -1, np.int64),
    )


def triangle_cuts(tri: np.ndarray, part: np.ndarray, solid: np.ndarray, eps: float, renderer=None):
    """Where triangles of different parts cut through each other (``intersection_segments``).

    Parameters
    ----------
    tri : (F, 3, 3) float64
        The triangles' corners.
    part : (F,) int64
        The part of each triangle; only triangles of different parts are paired.
    solid : (F,) bool
        The triangles with an area (the others cut nothing).
    eps : float
        Plane distances below this count as zero (touching, not cutting).
    renderer : LayerRenderer, optional
        Makes the candidate pairs on the GPU (``cuts.gpu_cut_pairs``).

    Returns
    -------
    points : (K, 2, 3) float64
        The segments.
    a, b : (K,) int64
        The two triangles each segment lies on.
    """
    none = np.zeros((0, 2, 3)), np.zeros(0, np.int64), np.zeros(0, np.int64)
    if len(tri) == 0:
        return none
    lo = np.minimum(np.minimum(tri[:, 0], tri[:, 1]), tri[:, 2])
    hi = np.maximum(np.maximum(tri[:, 0], tri[:, 1]), tri[:, 2])
    candidates = _candidate_triangles(lo, hi, part, int(part.max()) + 1, eps)
    candidates = candidates[solid[candidates]]
    lo, hi, part_c = lo[candidates], hi[candidates], part[candidates]
    pairs = shared = None
    if renderer is not None and len(candidates) > 1:
        shared = _unit_normals(tri[candidates])
        grid = cell_grid(lo, hi, part_c, eps)
        pairs = gpu_cut_pairs(renderer, grid, tri[candidates], *shared, hi + eps, eps)
    if pairs is None:
        pairs = _candidate_pairs(lo, hi, part_c, eps)
        # normals once a triangle where there are more pairs than triangles, else a pair
        if shared is None and len(pairs[0]) > len(candidates):
            shared = _unit_normals(tri[candidates])
    ci, cj = pairs
    i, j = candidates[ci], candidates[cj]
    found, fa, fb = [], [], []
    for start in range(0, len(i), _PAIR_CHUNK):
        a, b = i[start : start + _PAIR_CHUNK], j[start : start + _PAIR_CHUNK]
        normals = None
        if shared is not None:
            ca, cb = ci[start : start + _PAIR_CHUNK], cj[start : start + _PAIR_CHUNK]
            normals = (shared[0][ca], shared[1][ca]), (shared[0][cb], shared[1][cb])
        segments, which = _triangle_pairs_cut(tri[a], tri[b], eps, normals)
        found.append(segments)
        fa.append(a[which])
        fb.append(b[which])
    if not found or not sum(len(s) for s in found):
        return none
    return np.concatenate(found), np.concatenate(fa), np.concatenate(fb)


def model_segments(
    model: Model,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    crease_angle: float = 30.0,
    intersections: bool = True,
    renderer=None,
) -> Segments:
    """All lines of a model for one view: features, part boundaries and intersection lines
    (found with ``renderer``'s help where given, see ``intersection_segments``)."""
    found = [feature_segments(model, view, projection, size, crease_angle)]
    if intersections:
        found.append(intersection_segments(model, renderer))
    return Segments.concatenate(found)


# -- joining ----------------------------------------------------------------------------------------


def _point_ids(points: np.ndarray, quantum: float) -> np.ndarray:
    """Ids of points equal after rounding to ``quantum``: each point's rank among the distinct
    rounded points (one packed integer key per point, as ``np.unique``'s inverse)."""
    if len(points) == 0:
        return np.zeros(0, np.int64)
    low = column_min(points)
    # rounding is monotonic: the largest rounded point is the largest point rounded
    span = np.round((column_max(points) - low) / quantum).astype(np.int64) + 1
    if float(span[0]) * float(span[1]) * float(span[2]) < 2.0**62:
        key = np.empty(len(points), np.int64)
        parallel.run(partial(_point_keys, points, low, quantum, span, key), len(points))
        return sorted_ranks(*sorted_with_order(key, overwrite=True))
    q = np.round((points - low) / quantum).astype(np.int64)
    return np.unique(q, axis=0, return_inverse=True)[1].reshape(-1)


def _point_keys(
    points: np.ndarray, low: np.ndarray, quantum: float, span: np.ndarray, out: np.ndarray, lo: int, hi: int
) -> None:
    """``out[lo:hi]``: the points' rounded coordinates packed into one integer (``span`` of
    them on each axis), a block of points at a time."""
    for start in range(lo, hi, _ROWS):
        stop = min(start + _ROWS, hi)
        q = np.round((points[start:stop] - low) / quantum).astype(np.int64)
        out[start:stop] = (q[:, 2] * span[1] + q[:, 1]) * span[0] + q[:, 0]


def join_polylines(segments: Segments, turn: float = 30.0) -> Polylines:
    """Drop repeated segments and chain the rest into polylines, part by part (the pieces of
    one occlusion level are cut where the kind changes, ``occlusion.split_by_level``).

    A chain continues through an endpoint shared by exactly two segments of the same part, and
    through a junction of more along the straightest pair of segments there that turn by at
    most ``turn`` degrees (a line running on past a vertex where other edges meet it stays one
    line); it stops at ends, at the rest of a junction and at part changes. Closed loops come
    out closed (first point repeated last).
    """
    n = len(segments)
    if n == 0:
        return Polylines(
            np.zeros((0, 3)),
            np.zeros(1, np.int64),
            np.zeros((0, 2), np.int64),
            np.zeros(0, np.int32),
            np.zeros(0, np.uint8),
            np.zeros(0, np.int64),
        )
    points = segments.points.reshape(-1, 3)
    quantum = _JOIN_REL * _diagonal(points)
    pid = _point_ids(points, quantum).reshape(n, 2)
    # the same segment twice (an edge that is both a crease and a part boundary, ...): keep one
    lo, hi = np.minimum(pid[:, 0], pid[:, 1]), np.maximum(pid[:, 0], pid[:, 1])
    proper = np.flatnonzero(lo != hi)
    first = unique_first(lo[proper] * (int(pid.max()) + 1) + hi[proper])[1]
    chosen = np.zeros(len(proper), bool)
    chosen[first] = True  # marked, not sorted: the kept segments stay in their order
    keep = proper[chosen]
    seg_part = segments.part[keep].astype(np.int64)
    pid = pid[keep]
    # nodes: a point within one part, numbered by point then part; the sort's order is the one
    # ``pair_ends`` walks the nodes in
    ordered, by_node = sorted_with_order(pid.reshape(-1) * (int(seg_part.max()) + 1) + np.repeat(seg_part, 2))
    node = sorted_ranks(ordered, by_node)
    # half-end h = 2 s + e is segment s's end e (0: start, 1: end); a segment leaves its end
    # as its start leaves backwards
    ahead = np.empty((len(keep), 3))
    parallel.run(partial(_unit_steps, segments.points, keep, ahead), len(keep))
    partner = pair_ends(node, partial(_leaving, ahead), np.cos(np.radians(turn)), by_node)
    # the points' and nodes' numbers go before the walk and the output (a big assembly's
    # millions of segments: their arrays are most of the joining's peak)
    del pid, lo, hi, proper, chosen, first, seg_part, ordered, by_node, node, ahead
    seg, rev, lengths = chain_order(partner)
    del partner
    # the segments' rows in the input, gathered once for the output
    source = keep[seg]
    # points of chain c: the first segment's start, then every segment's end
    chain_start = np.cumsum(lengths) - lengths
    out_len = lengths + 1
    offsets = np.r_[0, np.cumsum(out_len)]
    out_points = np.empty((offsets[-1], 3))
    out_faces = np.full((offsets[-1], 2), -1, np.int64)
    out_kind = np.zeros(offsets[-1], np.uint8)
    out_edge = np.full(offsets[-1], -1, np.int64)
    chain_of = np.repeat(np.arange(len(lengths)), lengths)
    slot = offsets[chain_of] + (np.arange(len(seg)) - chain_start[chain_of])
    flat_points = segments.points.reshape(-1, 3)
    out = out_points, out_faces, out_kind, out_edge
    parallel.run(partial(_joined_rows, segments, source, rev, slot, out), len(seg))
    last = chain_start + lengths - 1
    out_points[offsets[1:] - 1] = flat_points[2 * source[last] + 1 - rev[last]]
    return Polylines(
        out_points,
        offsets.astype(np.int64),
        out_faces,
        segments.part[source[chain_start]].astype(np.int32),
        out_kind,
        out_edge,
    )


def _leaving(ahead: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The unit directions in which the half-ends ``h`` leave their nodes: their segments'
    ``ahead``, backwards for a segment's end."""
    direction = ahead[h >> 1]
    return np.where((h & 1)[:, None] == 1, -direction, direction)


def _unit_steps(points: np.ndarray, keep: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]``: the unit direction of each segment ``keep[lo:hi]`` of ``points`` (K, 2, 3)
    from its first point to its second."""
    at = keep[lo:hi]
    step = points[at, 1] - points[at, 0]
    step /= np.maximum(row_norm(step), 1e-300)[:, None]
    out[lo:hi] = step


def _joined_rows(
    segments: Segments,
    source: np.ndarray,
    rev: np.ndarray,
    slot: np.ndarray,
    out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    lo: int,
    hi: int,
) -> None:
    """The rows ``slot[lo:hi]`` of the joined polylines' points, faces, kinds and edges
    (``out``): the first point, faces, kind and edge of the segments ``source[lo:hi]`` as
    walked (``rev``: backwards)."""
    points, faces, kind, edge = out
    at, back, rows = source[lo:hi], rev[lo:hi], slot[lo:hi]
    # a segment walked backwards starts at its second point, and on its second point's edge
    points[rows] = segments.points.reshape(-1, 3)[2 * at + back]
    faces[rows] = segments.faces[at]
    kind[rows] = segments.kind[at]
    on = segments.edge[at]
    if segments.edge_end is not None:
        on = np.where(back, segments.edge_end[at], on)
    edge[rows] = on
