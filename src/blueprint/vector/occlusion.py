"""Occlusion level of lines against peeled depth layers.

Each polyline is sampled along its screen projection about a pixel apart (its own vertices are
always samples). A sample's level is the number of peeled surfaces in front of it. The surface
of layer ``k`` at a pixel is known exactly, as a triangle of the model, so instead of comparing
against the layer's depth at the pixel centre (which is the depth *somewhere else* on a sloped
surface) the triangle's plane is evaluated on the sample's own view ray. A surface counts as in
front when it meets that ray nearer to the eye than the sample by more than a tolerance of
``tolerance`` pixel footprints at the sample's distance (the same measure in perspective and
orthographic views). The faces a line lies on never count.

Near an outline the pixel under a sample may show a surface that does not reach the sample's
ray at all (the plane of a triangle beside a silhouette, at a grazing angle, meets the ray far
in front). The level is therefore the minimum over the 3 x 3 pixels around the sample: the
pixels on the open side of an outline see past it. The price is that occluders narrower than
about two pixels hide nothing, and hidden lines reach up to a pixel further out from behind an
occluder's edge, both below the drawing's resolution.

Off silhouettes and borders a line's own surfaces surround it, so pixels that show no surface
at all (past the object's outline) are left out of that minimum: a hidden edge that ends on the
outline stays hidden to its end.

Two more passes clean what pixels cannot tell: :func:`verify_creases` drops mesh edges where
the surfaces to both sides of the line are one flat surface of one part (solids of one part
pressed together), and :func:`suppress_coincident` drops stretches that lie on a line of lower
level (the bottom outline of a plate under its top outline in a plan view). A polyline is then
cut where its level changes, halfway between the two samples that differ; stretches of one level
shorter than two pixels take their neighbours' level.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from blueprint.scene.model import Model

from .lines import BORDER, CREASE, SILHOUETTE, Polylines

__all__ = [
    "Pieces",
    "PixelLayers",
    "classify_samples",
    "probe_pixels",
    "face_planes",
    "sample_polylines",
    "split_by_level",
    "suppress_coincident",
    "verify_creases",
]

# Samples classified per NumPy pass (times 9 pixels times the layers at them).
_CHUNK = 1 << 15
_NEIGHBOURS = np.array([(dx, dy) for dy in (-1, 0, 1) for dx in (-1, 0, 1)], np.int64)


@dataclass(frozen=True)
class Samples:
    """Points along polylines.

    eye : (S, 3) float64, eye coordinates
    pixel : (S, 2) float64, pixel coordinates (x right, y down, origin top-left)
    faces : (S, 2) int64, faces of the segment each sample lies on
    kind : (S,) uint8, kind of the segment each sample lies on (``lines.SILHOUETTE``, ...)
    line : (S,) int64, polyline of each sample
    vertex : (S,) bool, True where the sample is a vertex of its polyline
    inside : (S,) bool, True where the sample lies inside the view volume
    """

    eye: np.ndarray
    pixel: np.ndarray
    faces: np.ndarray
    kind: np.ndarray
    line: np.ndarray
    vertex: np.ndarray
    inside: np.ndarray


@dataclass(frozen=True)
class Pieces:
    """2D polylines of one level each: piece ``i`` is ``points[offsets[i]:offsets[i + 1]]``."""

    points: np.ndarray
    offsets: np.ndarray
    part: np.ndarray
    level: np.ndarray

    def __len__(self) -> int:
        return len(self.offsets) - 1

    @classmethod
    def empty(cls) -> Pieces:
        return cls(np.zeros((0, 2)), np.zeros(1, np.int64), np.zeros(0, np.int32), np.zeros(0, np.int32))


@dataclass(frozen=True)
class PixelLayers:
    """Triangle IDs of the peeled layers at the pixels the occlusion tests look at.

    ``stacks[i, k]`` is the face of layer ``k`` at pixel ``pixels[i]`` (flat index
    ``y * width + x``, row 0 at the top), -1 where none; layers hold surfaces from the front,
    so the first ``count[i]`` are surfaces. ``pixels`` None stands for every pixel in order.
    """

    pixels: np.ndarray | None
    stacks: np.ndarray
    count: np.ndarray
    layers: int
    height: int
    width: int

    @classmethod
    def from_layers(cls, triangle: np.ndarray) -> PixelLayers:
        """Every pixel of (L, H, W) triangle layers."""
        layers, height, width = triangle.shape
        stacks = np.ascontiguousarray(triangle.reshape(layers, -1).T)
        return cls(None, stacks, (stacks >= 0).sum(axis=1), layers, height, width)

    def at(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(len(q), L) faces and (len(q),) surface counts at flat pixel indices ``q``, which
        must be among ``pixels``."""
        rows = q if self.pixels is None else np.take(self._rows, q)
        return np.take(self.stacks, rows, axis=0), self.count[rows]

    @functools.cached_property
    def _rows(self) -> np.ndarray:
        """Row of ``stacks`` for every flat pixel index (-1 where not kept): one gather a lookup."""
        rows = np.full(self.height * self.width, -1, np.int64)
        rows[self.pixels] = np.arange(len(self.pixels))
        return rows


def _flat(spot: np.ndarray, height: int, width: int) -> np.ndarray:
    """Flat indices of (N, 2) integer pixel positions, clamped to the image."""
    return np.clip(spot[..., 1], 0, height - 1) * width + np.clip(spot[..., 0], 0, width - 1)


def probe_pixels(samples: Samples, size: tuple[int, int], offset: float = 1.0) -> np.ndarray:
    """Sorted flat indices of every pixel that :func:`classify_samples` and
    :func:`verify_creases` look at for these samples: what a peel must keep of its layers."""
    width, height = size
    probed = np.zeros(height * width, bool)
    inside = np.flatnonzero(samples.inside)
    px = np.floor(samples.pixel[inside]).astype(np.int64)
    for step in _NEIGHBOURS:
        probed[_flat(px + step, height, width)] = True
    rows = np.flatnonzero(np.isin(samples.kind, (SILHOUETTE, BORDER, CREASE)) & samples.inside)
    rows, across = _across(samples, rows)
    for side in (1.0, -1.0):
        spot = np.floor(samples.pixel[rows] + side * offset * across).astype(np.int64)
        probed[_flat(spot, height, width)] = True
    return np.flatnonzero(probed)


def _across(samples: Samples, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows whose line has a screen direction there (from the neighbouring samples on the
    same line), and the unit vectors across it."""
    line, pixel = samples.line, samples.pixel
    if len(rows) == 0:
        return rows, np.zeros((0, 2))
    nxt = np.minimum(rows + 1, len(line) - 1)
    prv = np.maximum(rows - 1, 0)
    ahead = np.where((line[nxt] == line[rows])[:, None], pixel[nxt], pixel[rows])
    behind = np.where((line[prv] == line[rows])[:, None], pixel[prv], pixel[rows])
    tangent = ahead - behind
    length = np.linalg.norm(tangent, axis=1)
    good = length > 0
    rows, tangent = rows[good], tangent[good] / length[good, None]
    return rows, np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)


def _to_pixels(clip: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    w = clip[..., 3:4]
    ndc = clip[..., :2] / np.where(np.abs(w) > 0, w, 1.0)
    return np.stack([(ndc[..., 0] + 1.0) * 0.5 * size[0], (1.0 - ndc[..., 1]) * 0.5 * size[1]], -1)


def sample_polylines(
    lines: Polylines,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    spacing: float = 1.0,
) -> Samples:
    """Samples about ``spacing`` pixels apart along every segment, its vertices included.

    Points are interpolated in model space, so on screen they fall on the projected segment
    (a straight line in perspective as well), a little unevenly spaced.
    """
    points, offsets = lines.points, lines.offsets
    if len(points) == 0:
        z = np.zeros((0, 2))
        none = np.zeros(0, bool)
        return Samples(
            np.zeros((0, 3)),
            z,
            np.zeros((0, 2), np.int64),
            np.zeros(0, np.uint8),
            np.zeros(0, np.int64),
            none,
            none,
        )
    mvp = projection @ view
    homogeneous = np.concatenate([points, np.ones((len(points), 1))], axis=1)
    clip = homogeneous @ mvp.T
    pix = _to_pixels(clip, size)
    line_of_point = np.repeat(np.arange(len(lines)), np.diff(offsets))
    is_last = np.zeros(len(points), bool)
    is_last[offsets[1:] - 1] = True
    starts = np.flatnonzero(~is_last)  # segment j runs from point j to point j + 1
    # in front of the eye at both ends: the screen length is meaningful
    w = clip[:, 3]
    length = np.linalg.norm(pix[starts + 1] - pix[starts], axis=1)
    length = np.where((w[starts] > 0) & (w[starts + 1] > 0) & np.isfinite(length), length, 0.0)
    count = np.maximum(np.ceil(length / spacing), 1).astype(np.int64)
    count = np.minimum(count, 1 << 16)
    seg = np.repeat(starts, count)
    k = np.arange(len(seg)) - np.repeat(np.cumsum(count) - count, count)
    t = k / count[np.searchsorted(starts, seg)]
    model = points[seg] + t[:, None] * (points[seg + 1] - points[seg])
    faces = lines.faces[seg]
    kind = lines.kind[seg]
    vertex = k == 0
    # each polyline's last point, inserted after its last segment's samples
    lasts = offsets[1:] - 1
    model = np.concatenate([model, points[lasts]])
    faces = np.concatenate([faces, lines.faces[np.maximum(lasts - 1, 0)]])
    kind = np.concatenate([kind, lines.kind[np.maximum(lasts - 1, 0)]])
    vertex = np.concatenate([vertex, np.ones(len(lasts), bool)])
    line = np.concatenate([line_of_point[seg], np.arange(len(lines))])
    position = np.concatenate([seg + t, lasts.astype(np.float64)])
    order = np.lexsort((position, line))
    model, faces, vertex, line = model[order], faces[order], vertex[order], line[order]
    kind = kind[order]
    homogeneous = np.concatenate([model, np.ones((len(model), 1))], axis=1)
    eye = homogeneous @ view.T
    clip = eye @ projection.T
    inside = (
        (clip[:, 3] > 0)
        & (clip[:, 2] >= -clip[:, 3])
        & (clip[:, 2] <= clip[:, 3])
        & (np.abs(clip[:, 0]) <= clip[:, 3])
        & (np.abs(clip[:, 1]) <= clip[:, 3])
    )
    return Samples(eye[:, :3], _to_pixels(clip, size), faces, kind, line, vertex, inside)


def face_planes(model: Model, view: np.ndarray) -> np.ndarray:
    """(F + 1, 4) float64 eye-space planes ``n . x = c`` of every face (unit n), zero for
    degenerate faces and for the extra last row, which stands for "no face"."""
    tri = model.positions[model.faces].astype(np.float64)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normal, axis=1)
    good = length > 0
    normal[good] /= length[good, None]
    normal[~good] = 0.0
    rotation, shift = view[:3, :3], view[:3, 3]
    n_eye = normal @ rotation.T
    v0_eye = tri[:, 0] @ rotation.T + shift
    planes = np.zeros((len(tri) + 1, 4))
    planes[:-1, :3] = n_eye
    planes[:-1, 3] = np.einsum("ij,ij->i", n_eye, v0_eye)
    return planes


def classify_samples(
    samples: Samples,
    triangle: PixelLayers,
    planes: np.ndarray,
    ortho: bool,
    footprint: float,
    tolerance: float = 1.0,
) -> np.ndarray:
    """Occlusion level of every sample (-1 outside the view).

    Parameters
    ----------
    samples : Samples
    triangle : PixelLayers
        Face index of each peeled layer, -1 where none, at least at ``probe_pixels``.
    planes : (F + 1, 4) float64
        From :func:`face_planes`.
    ortho : bool
        Orthographic camera (rays along -z) or perspective (rays from the eye at the origin).
    footprint : float
        Size of a pixel at unit distance (perspective) or in model units (orthographic).
    tolerance : float
        Surfaces nearer than this many pixel footprints in depth do not count as in front.

    Returns
    -------
    (S,) int32
        Number of layers in front of each sample, the minimum over its 3 x 3 pixels.
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
    # float32 halves the memory traffic of the gathers; depths are compared at a relative
    # tolerance of ~1e-4 or coarser, far above float32 rounding
    planes = planes.astype(np.float32)
    limit = np.float32(tolerance * footprint)  # orthographic: model units; perspective: relative
    for start in range(0, len(inside), _CHUNK):
        idx = inside[start : start + _CHUNK]
        px = np.floor(samples.pixel[idx]).astype(np.int64)
        eye = samples.eye[idx].astype(np.float32)
        ex, ey, ez = eye[:, 0], eye[:, 1], eye[:, 2]
        own0, own1 = samples.faces[idx, 0], samples.faces[idx, 1]
        # off a contour the line's own surfaces surround it: a pixel showing no surface at all
        # only says that the pixel lies past the object's outline, not what is in front
        solid = ~np.isin(samples.kind[idx], (SILHOUETTE, BORDER))
        best = np.full(len(idx), np.iinfo(np.int32).max, np.int32)
        for dx, dy in _NEIGHBOURS.tolist():
            q = _flat(px + np.array([dx, dy]), height, width)
            front = np.zeros(len(idx), np.int32)
            stack, depth_count = triangle.at(q)
            for k in range(int(depth_count.max())):
                tri = stack[:, k]  # -1 (no surface) picks the all-zero last plane
                plane = np.take(planes, tri, axis=0)
                dot = plane[:, 0] * ex + plane[:, 1] * ey + plane[:, 2] * ez
                c = plane[:, 3]
                if ortho:
                    # the plane meets the ray x = eye + u (0, 0, 1) at u = (c - n . eye) / n_z
                    nz = plane[:, 2]
                    ahead = (c - dot) * np.sign(nz) > limit * np.abs(nz)
                else:
                    # the ray t * eye meets the plane at t = c / (n . eye); in front: 0 < t < 1 - limit
                    ahead = (c * dot > 0) & (np.abs(c) < np.abs(dot) * (1 - limit))
                ahead &= (tri != own0) & (tri != own1)
                front += ahead
            front[solid & (depth_count == 0)] = np.iinfo(np.int32).max
            np.minimum(best, front, out=best)
        best[best == np.iinfo(np.int32).max] = 0
        level[idx] = best
    return level


def _in_front(plane: np.ndarray, eye: np.ndarray, ortho: bool, limit: float) -> np.ndarray:
    """Whether planes (N, 4) meet the view rays of eye points (N, 3) in front of them."""
    dot = plane[:, 0] * eye[:, 0] + plane[:, 1] * eye[:, 1] + plane[:, 2] * eye[:, 2]
    c = plane[:, 3]
    if ortho:
        nz = plane[:, 2]
        return (c - dot) * np.sign(nz) > limit * np.abs(nz)
    return (c * dot > 0) & (np.abs(c) < np.abs(dot) * (1 - limit))


def verify_creases(
    samples: Samples,
    level: np.ndarray,
    triangle: PixelLayers,
    planes: np.ndarray,
    face_part: np.ndarray,
    ortho: bool,
    footprint: float,
    crease_angle: float = 30.0,
    tolerance: float = 1.0,
    offset: float = 1.0,
) -> np.ndarray:
    """Leave out samples of mesh edges (silhouettes, borders, creases) where the drawing shows no
    edge: the surfaces seen a pixel to either side of the line, at the line's depth, are one flat
    surface of one part.

    That happens where solids of one part touch: the box that is a lid sitting on the boxes that
    are walls has edges all round its bottom, but the lid's front face and the wall's front face
    below it continue one plane, so the union has no edge there (and the raster shows none).
    A side counts as "at the line's depth" through the same plane test as occlusion; a side that
    shows nothing, another part, a surface off the line's depth, or a normal turned by more than
    half the crease angle keeps the crease.
    """
    level = level.copy()
    rows = np.flatnonzero(np.isin(samples.kind, (SILHOUETTE, BORDER, CREASE)) & (level >= 0))
    layers, height, width = triangle.layers, triangle.height, triangle.width
    if len(rows) == 0 or layers == 0:
        return level
    pixel = samples.pixel
    # screen direction of the line at each sample, from its neighbours on the same line
    rows, across = _across(samples, rows)
    eye = samples.eye[rows].astype(np.float32)
    own0, own1 = samples.faces[rows, 0], samples.faces[rows, 1]
    planes32 = planes.astype(np.float32)
    limit = np.float32(tolerance * footprint)
    seen = []
    for side in (1.0, -1.0):
        q = _flat(np.floor(pixel[rows] + side * offset * across).astype(np.int64), height, width)
        stack, depth_count = triangle.at(q)
        front = np.zeros(len(rows), np.int64)
        for k in range(int(depth_count.max(initial=0))):
            tri = stack[:, k]
            ahead_k = _in_front(np.take(planes32, tri, axis=0), eye, ortho, limit)
            front += ahead_k & (tri != own0) & (tri != own1)
        index = np.minimum(front, layers - 1)
        tri = np.where(front < depth_count, stack[np.arange(len(rows)), index], -1)
        seen.append(tri)
    tri_a, tri_b = seen
    plane_a, plane_b = planes[tri_a], planes[tri_b]  # -1 picks the empty last row
    # normals turned towards the eye
    to_eye = np.broadcast_to(np.array([0.0, 0.0, 1.0]), eye.shape) if ortho else -samples.eye[rows]
    n_a = plane_a[:, :3] * np.where(np.einsum("ij,ij->i", plane_a[:, :3], to_eye) < 0, -1.0, 1.0)[:, None]
    n_b = plane_b[:, :3] * np.where(np.einsum("ij,ij->i", plane_b[:, :3], to_eye) < 0, -1.0, 1.0)[:, None]
    flat = np.einsum("ij,ij->i", n_a, n_b) > np.cos(np.radians(0.5 * crease_angle))
    # both side surfaces pass through the line's point (not in front of it, not behind it)
    point = samples.eye[rows]

    def through(plane):
        gap = np.einsum("ij,ij->i", plane[:, :3], point) - plane[:, 3]
        scale = 1.0 if ortho else np.linalg.norm(point, axis=1)
        return np.abs(gap) <= 2.0 * tolerance * footprint * scale

    same_part = face_part[np.maximum(tri_a, 0)] == face_part[np.maximum(tri_b, 0)]
    phantom = (tri_a >= 0) & (tri_b >= 0) & same_part & flat & through(plane_a) & through(plane_b)
    level[rows[phantom]] = -1
    return level


def _smooth(level: np.ndarray, line: np.ndarray, pixel: np.ndarray, min_run: float) -> np.ndarray:
    """Absorb runs of one level shorter than ``min_run`` pixels: flicker below the resolution.

    A short run between two runs of one level takes their level; a short run at the end of a
    polyline takes the level of the longer run beside it (the typical case: a hidden edge that
    ends on an outline, whose last pixel sees past the outline).
    """
    level = level.copy()
    n = len(level)
    if n < 2 or min_run <= 0:
        return level
    for _ in range(2):
        change = np.r_[True, (line[1:] != line[:-1]) | (level[1:] != level[:-1])]
        start = np.flatnonzero(change)
        end = np.r_[start[1:], n]  # exclusive
        if len(start) < 2:
            break
        # a run's length: from halfway to the previous sample to halfway to the next one
        step = np.r_[np.linalg.norm(np.diff(pixel, axis=0), axis=1), 0.0]
        step[np.r_[line[1:] != line[:-1], True]] = 0.0
        along = np.r_[0.0, np.cumsum(step)]
        lo = np.where(start > 0, 0.5 * (along[start - 1] + along[start]), along[start])
        hi = np.where(end < n, 0.5 * (along[end - 1] + along[end]), along[end - 1])
        hi = np.where(end < n, hi, along[end - 1])
        length = hi - lo
        run_line = line[start]
        run_level = level[start]
        has_prev = np.r_[False, run_line[1:] == run_line[:-1]]
        has_next = np.r_[run_line[:-1] == run_line[1:], False]
        prev_level = np.r_[-2, run_level[:-1]]
        next_level = np.r_[run_level[1:], -2]
        prev_len = np.r_[0.0, length[:-1]]
        next_len = np.r_[length[1:], 0.0]
        short = (length < min_run) & (run_level >= 0)
        inner = short & has_prev & has_next & (prev_level == next_level) & (prev_level >= 0)
        head = short & ~has_prev & has_next & (next_len > length) & (next_level >= 0)
        tail = short & has_prev & ~has_next & (prev_len > length) & (prev_level >= 0)
        target = np.where(inner | tail, prev_level, np.where(head, next_level, run_level))
        if not (inner | head | tail).any():
            break
        level = np.repeat(target, end - start).astype(level.dtype)
    return level


def suppress_coincident(
    samples: Samples,
    level: np.ndarray,
    distance: float = 0.5,
    angle: float = 10.0,
    min_run: float = 2.0,
) -> np.ndarray:
    """Leave out samples that lie on another line of lower level (or of the same level and an
    earlier polyline): within ``distance`` pixels across it and running within ``angle`` degrees
    of it. Hidden lines right under visible ones (the bottom outline of a plate under its top
    outline in a plan view) and lines drawn twice at one level come out once. Left-out samples
    get level -1; what remains of a line between left-out stretches must be ``min_run``
    pixels long.
    """
    level = level.copy()
    live = np.flatnonzero(level >= 0)
    if len(live) < 2:
        return level
    pixel, line = samples.pixel, samples.line
    # every sample stands for the stretch to the next sample of its line
    has_next = np.r_[line[1:] == line[:-1], False]
    forward = np.zeros_like(pixel)
    forward[has_next] = pixel[1:][has_next[:-1]] - pixel[:-1][has_next[:-1]]
    length = np.linalg.norm(forward, axis=1)
    unit = forward / np.where(length > 0, length, 1.0)[:, None]
    # a stretch that is hidden deeper or left out covers nothing
    covers = has_next & (length > 0) & (level >= 0) & (np.r_[level[1:], -1] >= 0)
    sin_limit = np.sin(np.radians(angle))
    rank = level.astype(np.int64) * (int(line.max()) + 1) + line
    # the direction of each sample's own line there (its last sample looks back)
    direction = np.where(has_next[:, None], unit, np.r_[unit[:1], unit[:-1]]).astype(np.float32)
    unit32, forward32 = unit.astype(np.float32), forward.astype(np.float32)
    inv_length2 = np.divide(1.0, length**2, out=np.zeros_like(length), where=length > 0).astype(np.float32)
    pixel32 = pixel.astype(np.float32)
    # a dense grid of 1-pixel cells, one cell of margin all round; the stretches sorted by cell
    origin = np.floor(pixel[live].min(axis=0)).astype(np.int64) - 1
    span = np.floor(pixel[live].max(axis=0)).astype(np.int64) - origin + 2
    source = np.flatnonzero(covers)

    def cell_of(rows):
        c = np.floor(pixel[rows]).astype(np.int64) - origin
        return np.clip(c[:, 1], 0, span[1] - 1) * span[0] + np.clip(c[:, 0], 0, span[0] - 1)

    src_key = cell_of(source)
    order = np.argsort(src_key, kind="stable")
    source = source[order]
    cell_count = np.bincount(src_key, minlength=int(span[0] * span[1]))
    cell_start = np.cumsum(cell_count) - cell_count
    key = cell_of(live)
    drop = np.zeros(len(live), bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            probe = key + dy * span[0] + dx  # the margin keeps probes inside the grid
            lo, count = cell_start[probe], cell_count[probe]
            for start in range(0, len(live), 1 << 16):
                c = count[start : start + (1 << 16)]
                total = int(c.sum())
                if total == 0:
                    continue
                index = np.repeat(np.arange(start, start + len(c)), c)
                within = np.arange(total) - np.repeat(np.cumsum(c) - c, c)
                other = np.take(source, np.repeat(lo[start : start + len(c)], c) + within)
                mine = np.take(live, index)
                ok = (np.take(rank, other) < np.take(rank, mine)) & (
                    np.take(line, other) != np.take(line, mine)
                )
                index, mine, other = index[ok], mine[ok], other[ok]
                # distance from the sample to the other stretch, and the angle between them
                rel = np.take(pixel32, mine, axis=0) - np.take(pixel32, other, axis=0)
                f = np.take(forward32, other, axis=0)
                t = np.clip((rel[:, 0] * f[:, 0] + rel[:, 1] * f[:, 1]) * np.take(inv_length2, other), 0, 1)
                gx, gy = rel[:, 0] - t * f[:, 0], rel[:, 1] - t * f[:, 1]
                d, u = np.take(direction, mine, axis=0), np.take(unit32, other, axis=0)
                turn = np.abs(d[:, 0] * u[:, 1] - d[:, 1] * u[:, 0])
                hit = (gx * gx + gy * gy <= distance * distance) & (turn <= sin_limit)
                drop[index[hit]] = True
    if not drop.any():
        return level
    level[live[drop]] = -1
    # short leftovers between left-out stretches go too
    n = len(level)
    change = np.r_[True, (line[1:] != line[:-1]) | ((level[1:] >= 0) != (level[:-1] >= 0))]
    start = np.flatnonzero(change)
    end = np.r_[start[1:], n]
    step = np.r_[np.linalg.norm(np.diff(pixel, axis=0), axis=1), 0.0]
    step[np.r_[line[1:] != line[:-1], True]] = 0.0
    along_line = np.r_[0.0, np.cumsum(step)]
    length = along_line[end - 1] - along_line[start] + 1.0
    kept = level[start] >= 0
    before = np.r_[False, (line[start[1:]] == line[start[1:] - 1])] & ~np.r_[True, kept[:-1]]
    after = np.r_[(line[end[:-1] - 1] == line[end[:-1]]), False] & ~np.r_[kept[1:], True]
    lone = kept & (length < min_run) & (before | after)
    level[np.repeat(lone, end - start)] = -1
    return level


def split_by_level(
    samples: Samples,
    level: np.ndarray,
    part: np.ndarray,
    max_level: int,
    min_run: float = 2.0,
    coincident: float = 0.5,
) -> Pieces:
    """Cut the sampled polylines into 2D pieces of one level each.

    A piece runs over consecutive samples of one polyline with one level; its ends are the
    midpoints towards the neighbouring samples of other levels (so pieces of different levels
    meet), and of its inner samples only the polyline's vertices are kept (the others lie on
    the straight segments between them). Samples outside the view or deeper than
    ``max_level`` are dropped, and so are samples on a line of lower level (see
    :func:`suppress_coincident`, within ``coincident`` pixels; 0 keeps them).
    """
    n = len(level)
    if n == 0:
        return Pieces.empty()
    level = _smooth(level, samples.line, samples.pixel, min_run)
    level = np.where(level <= max_level, level, -1)
    if coincident > 0:
        level = suppress_coincident(samples, level, coincident, min_run=min_run)
    line, pixel = samples.line, samples.pixel
    keep = (level >= 0) & (level <= max_level)
    # runs: consecutive samples of one line with one level
    change = np.r_[True, (line[1:] != line[:-1]) | (level[1:] != level[:-1])]
    run = np.cumsum(change) - 1
    run_start = np.flatnonzero(change)
    run_end = np.r_[run_start[1:], n]  # exclusive
    run_keep = keep[run_start]
    # a neighbour across a level change on the same line gives a midpoint end
    joined_before = np.r_[False, line[run_start[1:]] == line[run_start[1:] - 1]]
    joined_after = np.r_[line[run_end[:-1] - 1] == line[run_end[:-1]], False]
    # samples kept as points: vertices, and the first and last sample of every run
    is_point = samples.vertex.copy()
    is_point[run_start] = True
    is_point[run_end - 1] = True
    chosen = np.flatnonzero(is_point & run_keep[run])
    runs = np.flatnonzero(run_keep)
    before = runs[joined_before[runs]]
    after = runs[joined_after[runs]]
    mid_before = 0.5 * (pixel[run_start[before]] + pixel[run_start[before] - 1])
    mid_after = 0.5 * (pixel[run_end[after] - 1] + pixel[run_end[after]])
    # order all points by (run, position): midpoints before go first, after go last
    pts = np.concatenate([pixel[chosen], mid_before, mid_after])
    owner = np.concatenate([run[chosen], before, after])
    pos = np.concatenate([chosen.astype(np.float64), run_start[before] - 0.5, run_end[after] - 0.5])
    order = np.lexsort((pos, owner))
    pts, owner = pts[order], owner[order]
    # a piece needs two points
    per_run = np.bincount(owner, minlength=len(run_start))
    good = per_run >= 2
    point_keep = good[owner]
    pts, owner = pts[point_keep], owner[point_keep]
    pieces = np.flatnonzero(good)
    offsets = np.r_[0, np.cumsum(per_run[pieces])].astype(np.int64)
    return Pieces(
        pts,
        offsets,
        part[line[run_start[pieces]]].astype(np.int32),
        level[run_start[pieces]].astype(np.int32),
    )
