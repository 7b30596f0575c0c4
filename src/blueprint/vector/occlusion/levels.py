"""Occlusion level of each sample: how many peeled surfaces lie in front of it.

The surface of layer ``k`` at a pixel is known exactly, as a triangle of the model, so instead
of comparing against the layer's depth at the pixel centre (which is the depth *somewhere else*
on a sloped surface) the triangle's plane is evaluated on the sample's own view ray. A surface
counts as in front when it meets that ray nearer to the eye than the sample by more than the
depth tolerance in eye depth: the capture's (``render.gbuffer.depth_tolerance``), a small
fraction of the model, so parts that nearly touch (a tab in a slot) hide each other's lines
as exactly as the layers tell them apart. The faces a line lies on never count.

Near an outline the pixel under a sample may show a surface that does not reach the sample's
ray at all (the plane of a triangle beside a silhouette, at a grazing angle, meets the ray far
in front). The level is therefore the minimum over the 2 x 2 pixels whose centres surround the
sample (``pixels.around``): one of them lies on the open side of an outline through it and sees
past. The price is that occluders narrower than about a pixel hide nothing, and visible lines
run on up to a pixel's diagonal behind an occluder's edge, both below the drawing's resolution.

Off silhouettes and borders a line's own surfaces surround it, so pixels that show no surface
at all (past the object's outline) are left out of that minimum: a hidden edge that ends on the
outline stays hidden to its end.

:func:`verify_creases` then drops mesh edges where the surfaces to both sides of the line are
one flat surface of the line's own part, which pixels alone cannot tell from an edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint import parallel
from blueprint.columns import row_norm
from blueprint.scene.model import Model

from ..cache import ModelCache
from ..lines import BORDER, CREASE, GRAZING_REACH, SILHOUETTE, SMOOTH
from .pixels import NEIGHBOURS, PixelLayers, across_line, around, flat_index
from .samples import Samples

__all__ = ["DepthTest", "classify_samples", "contour_rows", "drop_phantoms", "face_planes", "verify_creases"]

# Model-space face normals and corners, per mesh (see ``face_planes``).
PLANES = ModelCache()
# Samples classified per NumPy pass (times 9 pixels times the layers at them).
_CHUNK = 1 << 15


@dataclass(frozen=True)
class DepthTest:
    """When a surface counts as in front of a sample, on the sample's view ray.

    ortho : bool, orthographic camera (rays along -z) or perspective (rays from the eye at the
        origin)
    footprint : float, size of a pixel at unit distance (perspective) or in model units
        (orthographic): ``Camera.pixel_angle``
    tolerance : float, surfaces nearer than this in eye depth (model units) do not count as in
        front: ``render.gbuffer.depth_tolerance``, the capture's
    band : (F + 1,) float32, optional, ``lines.grazing_band``: the faces where a smooth surface
        folds over its own contour, with their sizes; such a face counts as in front of a
        smooth contour's sample (a silhouette inside one face) only from ``GRAZING_REACH``
        of its sizes in front
    """

    ortho: bool
    footprint: float
    tolerance: float
    band: np.ndarray | None = None

    def contour_samples(self, samples: Samples, rows: np.ndarray) -> np.ndarray:
        """(N,) bool: which of the samples ``rows`` the band's rule applies to (none without a
        band): those of smooth contours, silhouettes inside one face."""
        if self.band is None:
            return np.zeros(len(rows), bool)
        return contour_rows(samples, rows)

    def side_limit(self, eye: np.ndarray) -> np.ndarray:
        """(N,) float32: a pixel's footprint in eye depth at eye points (N, 3), the depth within
        which :func:`verify_creases` takes a surface beside a line as at the line's depth (the
        surfaces a pixel away on a curved surface lie off the line's tangent plane by about
        that)."""
        if self.ortho:
            return np.full(len(eye), self.footprint, np.float32)
        return (self.footprint * -eye[:, 2]).astype(np.float32)


def contour_rows(samples: Samples, rows: np.ndarray) -> np.ndarray:
    """(N,) bool: which of the samples ``rows`` lie on smooth contours, silhouettes inside one
    face."""
    return (samples.kind[rows] == SILHOUETTE) & (samples.faces[rows, 1] < 0)


def face_planes(model: Model, view: np.ndarray) -> np.ndarray:
    """(F + 1, 4) float64 eye-space planes ``n . x = c`` of every face (unit n), zero for
    degenerate faces and for the extra last row, which stands for "no face". The model-space
    normals and corners do not depend on the view: computed once per mesh (``PLANES``); a
    model kept as instances moves its meshes' planes instead (``instanced``)."""
    if model.instances is not None:
        from ..instanced import instanced_face_planes

        return instanced_face_planes(model, view)
    normal, corner = PLANES.get(model, lambda: _model_planes(model))
    rotation, shift = view[:3, :3], view[:3, 3]
    n_eye = normal @ rotation.T
    v0_eye = corner @ rotation.T + shift
    planes = np.zeros((len(normal) + 1, 4))
    planes[:-1, :3] = n_eye
    planes[:-1, 3] = np.einsum("ij,ij->i", n_eye, v0_eye)
    return planes


def _model_planes(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """(F, 3) unit normals (zero for degenerate faces) and (F, 3) first corners, float64."""
    cross = model.corner_cross()
    length = row_norm(cross)
    good = length > 0
    normal = np.zeros_like(cross)
    normal[good] = cross[good] / length[good, None]
    return normal, np.ascontiguousarray(model.corners()[:, 0])


def classify_samples(
    samples: Samples,
    triangle: PixelLayers,
    planes: np.ndarray,
    test: DepthTest,
) -> np.ndarray:
    """Occlusion level of every sample (-1 outside the view).

    Parameters
    ----------
    samples : Samples
    triangle : PixelLayers
        Face index of each peeled layer, -1 where none, at least at ``probe_pixels``.
    planes : (F + 1, 4) float64
        From :func:`face_planes`.
    test : DepthTest
        The camera's kind, its pixel footprint and the depth tolerance.

    Returns
    -------
    (S,) int32
        Number of layers in front of each sample, the minimum over its 2 x 2 pixels.
    """
    layers, height, width = triangle.layers, triangle.height, triangle.width
    count = len(samples.line)
    level = np.full(count, -1, np.int32)
    inside = np.flatnonzero(samples.inside)
    if count == 0 or len(inside) == 0:
        return level
    if layers == 0:
        level[inside] = 0
        return level
    # float32 halves the memory traffic of the gathers; the depth tolerance is far above its
    # rounding (``depth_tolerance`` holds eight steps of the farthest eye depth)
    planes = planes.astype(np.float32)
    ortho, limit = test.ortho, np.float32(test.tolerance)
    reach = None if test.band is None else (test.band * np.float32(GRAZING_REACH)).astype(np.float32)
    for start in range(0, len(inside), _CHUNK):
        idx = inside[start : start + _CHUNK]
        px = around(samples.pixel[idx])
        eye = samples.eye[idx].astype(np.float32)
        own0, own1 = samples.faces[idx, 0], samples.faces[idx, 1]
        contour = test.contour_samples(samples, idx)
        # off a contour the line's own surfaces surround it: a pixel showing no surface at all
        # only says that the pixel lies past the object's outline, not what is in front
        solid = ~np.isin(samples.kind[idx], (SILHOUETTE, BORDER))
        best = np.full(len(idx), np.iinfo(np.int32).max, np.int32)
        for dx, dy in NEIGHBOURS.tolist():
            q = flat_index(px + np.array([dx, dy]), height, width)
            front = np.zeros(len(idx), np.int32)
            stack, depth_count = triangle.at(q)
            for k in range(int(depth_count.max())):
                tri = stack[:, k]  # -1 (no surface) picks the all-zero last plane
                within = limit
                if reach is not None:
                    within = np.where(contour, np.maximum(reach[tri], limit), limit)
                ahead = _in_front(np.take(planes, tri, axis=0), eye, ortho, within)
                ahead &= (tri != own0) & (tri != own1)
                front += ahead
            front[solid & (depth_count == 0)] = np.iinfo(np.int32).max
            np.minimum(best, front, out=best)
        best[best == np.iinfo(np.int32).max] = 0
        level[idx] = best
    return level


def _in_front(plane: np.ndarray, eye: np.ndarray, ortho: bool, limit) -> np.ndarray:
    """Whether planes (N, 4) meet the view rays of eye points (N, 3) in front of them by more
    than ``limit`` in eye depth (a scalar or (N,))."""
    dot = plane[:, 0] * eye[:, 0] + plane[:, 1] * eye[:, 1] + plane[:, 2] * eye[:, 2]
    c = plane[:, 3]
    if ortho:
        # the plane meets the ray x = eye + u (0, 0, 1) at u = (c - n . eye) / n_z
        nz = plane[:, 2]
        return (c - dot) * np.sign(nz) > limit * np.abs(nz)
    # the ray t * eye meets the plane at t = c / (n . eye), (1 - t) times the eye depth -eye_z
    # in front: 0 < t < 1 - limit / -eye_z
    return (c * dot > 0) & (np.abs(c) < np.abs(dot) * (1 - limit / -eye[:, 2]))


def verify_creases(
    samples: Samples,
    level: np.ndarray,
    triangle: PixelLayers,
    planes: np.ndarray,
    face_part: np.ndarray,
    test: DepthTest,
    crease_angle: float = 30.0,
    offset: float = 1.0,
) -> np.ndarray:
    """Leave out samples of mesh edges (silhouettes, borders, creases) where the drawing shows no
    edge: the surfaces seen a pixel to either side of the line, at the line's depth, are one flat
    surface of the line's own part.

    That happens where solids of one part touch: the box that is a lid sitting on the boxes that
    are walls has edges all round its bottom, but the lid's front face and the wall's front face
    below it continue one plane, so the union has no edge there (and the raster shows none).
    A side counts as "at the line's depth" through the same plane test as occlusion; a side that
    shows nothing, another part, a surface off the line's depth, or a normal turned by more than
    half the crease angle keeps the crease.
    """
    level = level.copy()
    rows = np.flatnonzero(np.isin(samples.kind, (SILHOUETTE, BORDER, CREASE, SMOOTH)) & (level >= 0))
    layers, height, width = triangle.layers, triangle.height, triangle.width
    if len(rows) == 0 or layers == 0:
        return level
    pixel = samples.pixel
    # screen direction of the line at each sample, from its neighbours on the same line
    rows, across = across_line(samples, rows)
    eye = samples.eye[rows].astype(np.float32)
    own0, own1 = samples.faces[rows, 0], samples.faces[rows, 1]
    planes32 = planes.astype(np.float32)
    ortho, limit = test.ortho, test.side_limit(eye)
    seen = []
    for side in (1.0, -1.0):
        q = flat_index(np.floor(pixel[rows] + side * offset * across).astype(np.int64), height, width)
        stack, depth_count = triangle.at(q)
        front = np.zeros(len(rows), np.int64)
        for k in range(int(depth_count.max(initial=0))):
            tri = stack[:, k]
            ahead_k = _in_front(np.take(planes32, tri, axis=0), eye, ortho, limit)
            front += ahead_k & (tri != own0) & (tri != own1)
        index = np.minimum(front, layers - 1)
        tri = np.where(front < depth_count, stack[np.arange(len(rows)), index], -1)
        seen.append(tri)
    return drop_phantoms(samples, level, rows, *seen, planes, face_part, test, crease_angle)


def drop_phantoms(
    samples: Samples,
    level: np.ndarray,
    rows: np.ndarray,
    tri_a: np.ndarray,
    tri_b: np.ndarray,
    planes: np.ndarray,
    face_part: np.ndarray,
    test: DepthTest,
    crease_angle: float = 30.0,
) -> np.ndarray:
    """The second half of :func:`verify_creases`, given the faces ``tri_a`` and ``tri_b`` seen
    at the line's depth to either side of the samples ``rows`` (-1 where none): their levels
    set to -1 where both are one flat surface of the line's own part through the line's point."""
    level = level.copy()
    cos_limit = np.cos(np.radians(0.5 * crease_angle))

    def drop(lo: int, hi: int) -> None:
        b = slice(lo, hi)
        found = _phantoms(samples, rows[b], tri_a[b], tri_b[b], planes, face_part, test, cos_limit)
        level[found] = -1

    # a block of samples a thread, each writing its own samples' levels, a step at a time
    parallel.run(parallel.stepped(drop), len(rows))
    return level


def _phantoms(samples, rows, tri_a, tri_b, planes, face_part, test: DepthTest, cos_limit) -> np.ndarray:
    """Those of the samples ``rows`` that ``drop_phantoms`` leaves out (``cos_limit`` the cosine
    of half the crease angle)."""
    ortho = test.ortho
    # only samples with a face of the line's part to either side can be phantoms: another
    # part's face covering both sides (a panel a fraction of a pixel in front of a slot's edge)
    # hides the line, it does not continue its surface
    part_a, part_b = face_part[np.maximum(tri_a, 0)], face_part[np.maximum(tri_b, 0)]
    own_part = face_part[np.maximum(samples.faces[rows, 0], 0)]
    maybe = np.flatnonzero((tri_a >= 0) & (tri_b >= 0) & (part_a == part_b) & (part_a == own_part))
    rows, tri_a, tri_b = rows[maybe], tri_a[maybe], tri_b[maybe]
    point = samples.eye[rows]
    plane_a, plane_b = planes[tri_a], planes[tri_b]
    # normals turned towards the eye
    to_eye = np.broadcast_to(np.array([0.0, 0.0, 1.0]), point.shape) if ortho else -point
    n_a = plane_a[:, :3] * np.where(np.einsum("ij,ij->i", plane_a[:, :3], to_eye) < 0, -1.0, 1.0)[:, None]
    n_b = plane_b[:, :3] * np.where(np.einsum("ij,ij->i", plane_b[:, :3], to_eye) < 0, -1.0, 1.0)[:, None]
    flat = np.flatnonzero(np.einsum("ij,ij->i", n_a, n_b) > cos_limit)
    # both side surfaces pass through the line's point (not in front of it, not behind it),
    # asked of the flat ones alone
    rows, point, plane_a, plane_b = rows[flat], point[flat], plane_a[flat], plane_b[flat]
    scale = 1.0 if ortho else row_norm(point)

    def through(plane):
        gap = np.einsum("ij,ij->i", plane[:, :3], point) - plane[:, 3]
        return np.abs(gap) <= 2.0 * test.footprint * scale

    return rows[through(plane_a) & through(plane_b)]
