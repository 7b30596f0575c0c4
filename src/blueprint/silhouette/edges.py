"""Per-view edge classification: the per-frame stage of the object-space silhouette method.

Every face is tested for facing the camera, every edge is compared against its faces (the
brute-force extraction of the paper's CPU baseline), and the kept edges are clipped against
the near plane and projected to pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint import parallel
from blueprint.columns import column_max, column_min
from blueprint.scene.camera import clip_to_pixels, transform
from blueprint.scene.normals import noise_creases

from .mesh import Adjacency

__all__ = ["BORDER", "CREASE", "SILHOUETTE", "EdgeSet", "classify_edges", "feature_vertices", "sharp_edges"]

SILHOUETTE = 1
BORDER = 2
CREASE = 3

# Clipped segments keep w >= this, so the perspective divide never meets w <= 0 even for
# projections whose near plane does not bound w away from zero.
_MIN_W = 1e-12
# Rows whose dot products ``_row_dots`` makes at a time.
_DOT_ROWS = 1 << 13


@dataclass(frozen=True)
class EdgeSet:
    """Classified feature edges of one view.

    Attributes
    ----------
    segments3d : np.ndarray
        (N, 2, 3) float64 model-space endpoints, after clipping to the near plane.
    segments2d : np.ndarray
        (N, 2, 2) float64 pixel coordinates: x right, y down, origin at the top-left corner
        of the image, pixel centres at +0.5.
    kind : np.ndarray
        (N,) uint8, one of `SILHOUETTE`, `BORDER`, `CREASE`.
    faces : np.ndarray
        (N, 2) int64 faces beside each edge: (front-facing, back-facing) for silhouettes,
        (face, -1) for borders, both faces in index order for creases.
    edges : np.ndarray
        (N,) int64 index of each edge in the adjacency's ``edges``.
    """

    segments3d: np.ndarray
    segments2d: np.ndarray
    kind: np.ndarray
    faces: np.ndarray
    edges: np.ndarray


def _check_matrix(name: str, matrix: np.ndarray) -> np.ndarray:
    matrix = np.asarray(matrix, dtype=np.float64)
    if matrix.shape != (4, 4) or not np.isfinite(matrix).all():
        raise ValueError(f"{name} must be a finite (4, 4) matrix, got shape {matrix.shape}")
    return matrix


def _front_facing(adj: Adjacency, view: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """(F,) bool: True where a face's normal points towards the camera."""
    camera_to_model = np.linalg.inv(view)
    if projection[3, 3] == 1.0:
        # Orthographic: every face sees the same direction, the camera's +z axis (it looks
        # down -z), so facing does not depend on where the face is.
        facing = adj.face_normals @ camera_to_model[:3, 2]
    else:
        eye = camera_to_model[:3, 3]
        facing = np.einsum("ij,ij->i", adj.face_normals, eye - adj.positions[adj.faces[:, 0]])
    return facing > 0.0


def _clip(clip: np.ndarray, model: np.ndarray, dist: np.ndarray) -> tuple[np.ndarray, ...]:
    """Clip segments to ``dist >= 0``, `dist` (N, 2) being linear in clip coordinates.

    Clip coordinates are an affine function of model coordinates (the divide comes later),
    so the same parameter moves both endpoint arrays consistently. Returns the kept rows'
    clip (M, 2, 4) and model (M, 2, 3) endpoints and the indices (M,) of the kept rows: the
    arrays given where no endpoint lies outside (most drawings' every segment).
    """
    if not (dist < 0.0).any():
        return clip, model, np.arange(len(clip))
    keep = np.flatnonzero((dist >= 0.0).any(axis=1))
    clip, model, dist = clip[keep].copy(), model[keep].copy(), dist[keep]
    for end in (0, 1):
        out = dist[:, end] < 0.0
        t = dist[out, end] / (dist[out, end] - dist[out, 1 - end])
        inside_clip, inside_model = clip[out, 1 - end], model[out, 1 - end]
        clip[out, end] += t[:, None] * (inside_clip - clip[out, end])
        model[out, end] += t[:, None] * (inside_model - model[out, end])
    return clip, model, keep


def classify_edges(
    adj: Adjacency,
    view: np.ndarray,
    projection: np.ndarray,
    width: int,
    height: int,
    crease_angle: float = 30.0,
    sharp: np.ndarray | None = None,
) -> EdgeSet:
    """Find the silhouette, border and crease edges of a mesh for one camera.

    A silhouette edge has both a front- and a back-facing face among its faces (this covers
    non-manifold edges too); faces with a zero normal count as neither. A border edge has
    exactly one face. A crease is a two-face edge that is not a silhouette and whose face
    normals differ by more than `crease_angle`. Each edge gets at most one kind, in that
    order of priority.

    Parameters
    ----------
    adj : Adjacency
        Output of :func:`blueprint.silhouette.build_adjacency`.
    view, projection : np.ndarray
        (4, 4) float model-to-eye and eye-to-clip matrices, OpenGL conventions, acting on
        column vectors. ``projection[3, 3] == 1`` marks an orthographic projection.
    width, height : int
        Image size in pixels.
    crease_angle : float
        Dihedral threshold in degrees, in [0, 180].
    sharp : (E,) bool, optional
        ``sharp_edges`` of ``adj`` at ``crease_angle``, where the caller keeps them for every
        view (they do not depend on it); found here otherwise.

    Returns
    -------
    EdgeSet
        The classified edges in edge-index order, clipped to the near plane (and to w > 0);
        edges wholly on the camera's side of the near plane are dropped.
    """
    view = _check_matrix("view", view)
    projection = _check_matrix("projection", projection)
    if int(width) != width or int(height) != height or width <= 0 or height <= 0:
        raise ValueError(f"width and height must be positive integers, got {width}x{height}")
    if not 0.0 <= crease_angle <= 180.0:
        raise ValueError(f"crease_angle must be in [0, 180] degrees, got {crease_angle}")

    normals = adj.face_normals
    normal_ok = (normals[:, 0] != 0) | (normals[:, 1] != 0) | (normals[:, 2] != 0)
    front = _front_facing(adj, view, projection) & normal_ok
    count, f0, f1 = _first_two_faces(adj)
    # The lowest-index front and back face of every edge; "no face" stays at len(faces).
    first_front = _first_face_of(adj, front, count, f0, f1)
    first_back = _first_face_of(adj, ~front & normal_ok, count, f0, f1)
    silhouette = (first_front < len(adj.faces)) & (first_back < len(adj.faces))
    border = count == 1
    if sharp is None:
        sharp = sharp_edges(adj, count, f0, f1, normal_ok, crease_angle)
    crease = sharp & ~silhouette

    kind = np.zeros(len(adj.edges), dtype=np.uint8)
    kind[crease] = CREASE
    kind[border] = BORDER
    kind[silhouette] = SILHOUETTE
    side_faces = np.stack([f0, np.where(border, -1, f1)], axis=1)
    side_faces[silhouette] = np.stack([first_front, first_back], axis=1)[silhouette]

    chosen = np.flatnonzero(kind)
    model, pixels, keep = _projected(adj.positions[adj.edges[chosen]], view, projection, (width, height))
    chosen = chosen[keep]
    return EdgeSet(
        segments3d=model, segments2d=pixels, kind=kind[chosen], faces=side_faces[chosen], edges=chosen
    )


def feature_vertices(
    adj: Adjacency, crease_angle: float = 30.0, sharp: np.ndarray | None = None
) -> np.ndarray:
    """(V,) bool: the vertices on a crease (``sharp_edges``, silhouette or not: ``sharp`` where
    the caller has them, ``mesh_sharp_edges``), a border, a non-manifold edge or a degenerate
    face: where the surface is not smooth."""
    normals = adj.face_normals
    normal_ok = (normals[:, 0] != 0) | (normals[:, 1] != 0) | (normals[:, 2] != 0)
    count, f0, f1 = _first_two_faces(adj)
    if sharp is None:
        sharp = sharp_edges(adj, count, f0, f1, normal_ok, crease_angle)
    apart = sharp | (count != 2)
    feature = np.zeros(len(adj.positions), bool)
    feature[adj.edges[apart].reshape(-1)] = True
    feature[adj.faces[~normal_ok].reshape(-1)] = True
    return feature


def _first_two_faces(adj: Adjacency) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(E,) the number of faces of every edge, and its first two faces (-1 where it has fewer)."""
    edge, face = adj.edge_faces[:, 0], adj.edge_faces[:, 1]
    count = np.bincount(edge, minlength=len(adj.edges))
    # Incidences are sorted by edge then face, so each edge's first two faces sit at its start.
    at = np.cumsum(count)
    at -= count
    f0 = face[np.minimum(at, len(face) - 1, out=at)]
    f0[count < 1] = -1
    at = np.cumsum(count, out=at)
    at -= count
    at += 1
    f1 = face[np.minimum(at, len(face) - 1, out=at)]
    f1[count < 2] = -1
    return count, f0, f1


def _first_face_of(adj: Adjacency, chosen: np.ndarray, count, f0, f1) -> np.ndarray:
    """``_first_face`` from an edge's first two faces (``_first_two_faces``: ``count``, ``f0``,
    ``f1``), which decide it for every edge of at most two faces; the incidences are read
    only where some edge has more."""
    none = len(adj.faces)
    first = np.where((count >= 2) & chosen[f1], f1, none)
    first = np.where((count >= 1) & chosen[f0], f0, first)
    many = np.flatnonzero(count > 2)
    if len(many):
        first[many] = _first_face(adj, chosen)[many]
    return first


def _first_face(adj: Adjacency, chosen: np.ndarray) -> np.ndarray:
    """(E,) the lowest-index face of every edge among the ``chosen`` faces (F,) bool; "no
    face" is len(faces)."""
    edge, face = adj.edge_faces[:, 0], adj.edge_faces[:, 1]
    first = np.full(len(adj.edges), len(adj.faces), dtype=np.int64)
    # incidences run by edge, then face: an edge's first chosen one is its lowest
    picked = chosen[face]
    e, f = edge[picked], face[picked]
    lead = np.r_[True, e[1:] != e[:-1]] if len(e) else np.zeros(0, bool)
    first[e[lead]] = f[lead]
    return first


def _creases(adj, count, f0, f1, normal_ok, silhouette, crease_angle: float) -> np.ndarray:
    """(E,) bool: two-face edges, no silhouette, whose faces' normals differ by more than
    ``crease_angle`` degrees, runs of noise left out (``sharp_edges``)."""
    return sharp_edges(adj, count, f0, f1, normal_ok, crease_angle) & ~silhouette


def mesh_sharp_edges(adj: Adjacency, crease_angle: float = 30.0) -> np.ndarray:
    """(E,) bool: ``sharp_edges`` of ``adj``, which no view changes: what ``classify_edges``
    takes as ``sharp`` from a caller that keeps them for every view."""
    normals = adj.face_normals
    normal_ok = (normals[:, 0] != 0) | (normals[:, 1] != 0) | (normals[:, 2] != 0)
    return sharp_edges(adj, *_first_two_faces(adj), normal_ok, crease_angle)


def sharp_edges(adj, count, f0, f1, normal_ok, crease_angle: float) -> np.ndarray:
    """(E,) bool: two-face edges whose faces' normals differ by more than ``crease_angle``
    degrees, silhouettes or not, but for runs of a scan's noise, as the raster drawing's
    normals take them (``scene.normals.noise_creases``)."""
    normals = adj.face_normals
    sharp = np.flatnonzero(count == 2)
    both_ok = normal_ok[f0[sharp]] & normal_ok[f1[sharp]]
    cos_angle = _row_dots(normals, f0[sharp], normals, f1[sharp])
    limit = np.cos(np.radians(crease_angle))
    # runs are found among every edge that is not smooth, those beside a degenerate face too
    apart = ~(both_ok & (cos_angle >= limit))
    creased, sharp = (both_ok & (cos_angle < limit))[apart], sharp[apart]
    anchored = np.zeros(len(adj.positions), bool)
    anchored[adj.edges[count != 2].ravel()] = True
    ends = adj.positions[adj.edges[sharp]]
    length = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    crease = np.zeros(len(adj.edges), dtype=bool)
    crease[sharp] = creased & ~noise_creases(adj.edges[sharp], anchored, length, _size(adj))
    return crease


def _row_dots(a: np.ndarray, at_a: np.ndarray | None, b: np.ndarray, at_b: np.ndarray) -> np.ndarray:
    """(N,) float64: ``np.einsum("ij,ij->i", a[at_a], b[at_b])`` of (M, 3) float64 arrays
    ``a`` and ``b`` at (N,) int rows (``at_a`` None: ``a``'s first N rows), the same values,
    a block of rows at a time over threads: the rows taken stay in the cache, and none are
    held for every row."""
    out = np.empty(len(at_b))

    def dots(lo: int, hi: int) -> None:
        for start in range(lo, hi, _DOT_ROWS):
            stop = min(start + _DOT_ROWS, hi)
            # NumPy takes rows faster than it indexes them
            left = a[start:stop] if at_a is None else np.take(a, at_a[start:stop], axis=0)
            out[start:stop] = np.einsum("ij,ij->i", left, np.take(b, at_b[start:stop], axis=0))

    parallel.run(dots, len(out))
    return out


def _size(adj) -> float:
    """The diagonal of the bounding box of the vertices the faces use (1 where it is 0)."""
    used = np.zeros(len(adj.positions), bool)
    used[adj.faces.reshape(-1)] = True
    points = adj.positions if used.all() else adj.positions[used]
    if len(points) == 0:
        return 1.0
    return float(np.linalg.norm(column_max(points) - column_min(points))) or 1.0


def _projected(model: np.ndarray, view, projection, size) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments (N, 2, 3) clipped to the near plane (and to w > 0) and projected: the kept
    model endpoints (M, 2, 3), their pixels (M, 2, 2) and the indices (M,) of the kept rows."""
    clip, model, kept = near_clipped(model, view, projection)
    return model, clip_to_pixels(clip, size), kept


def near_clipped(model: np.ndarray, view, projection) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``_projected`` without the pixels, for callers that make them later or not at all: the
    kept segments' clip coordinates (M, 2, 4), model endpoints (M, 2, 3) and rows (M,)."""
    return _near(transform(model, projection @ view), model)


def near_kept(model: np.ndarray, view, projection) -> tuple[np.ndarray, np.ndarray]:
    """``near_clipped``'s kept model endpoints (M, 2, 3) and rows (M,), for callers that need
    no clip coordinates: the segments taken a step of rows at a time on the pool, so that
    those of millions of segments are never all held; ``model`` itself where none reaches
    past the near plane (most drawings)."""
    matrix = projection @ view

    def steps(lo: int, hi: int) -> list[tuple[int, np.ndarray, np.ndarray]]:
        found = []
        for start in range(lo, hi, parallel.STEP):
            piece = model[start : min(start + parallel.STEP, hi)]
            _, kept_model, kept = _near(transform(piece, matrix), piece)
            if kept_model is not piece:
                found.append((start, kept_model, kept + start))
        return found

    clipped = [step for block in parallel.run(steps, len(model)) for step in block]
    if not clipped:
        return model, np.arange(len(model))
    models, rows, done = [], [], 0
    for start, kept_model, kept in clipped:
        models += [model[done:start], kept_model]
        rows += [np.arange(done, start), kept]
        done = min(start + parallel.STEP, len(model))
    return np.concatenate([*models, model[done:]]), np.concatenate([*rows, np.arange(done, len(model))])


def _near(clip: np.ndarray, model: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Segments of clip coordinates ``clip`` (N, 2, 4) and model endpoints ``model`` clipped to
    the near plane and to w > 0 (``near_clipped``)."""
    # Near plane of an OpenGL frustum: z_clip >= -w_clip; then keep the divide safe.
    clip, model, keep = _clip(clip, model, clip[..., 2] + clip[..., 3])
    clip, model, kept = _clip(clip, model, clip[..., 3] - _MIN_W)
    return clip, model, keep[kept]
