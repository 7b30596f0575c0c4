"""An independent ray-casting oracle for depth layers: no GL, float64, trimesh ray queries.

One ray per pixel centre is built through the inverse of ``projection @ view`` (pixel
``(col, row)`` with row 0 at the top of the image), every hit along it is found with trimesh's
ray-triangle intersector, hits are converted to window depth through the same matrices, sorted,
and hits closer than a tolerance (in eye depth) to the surface before them are merged into that
surface. The result has the layout of ``blueprint.Layers`` / the NPZ contract in DESIGN.md.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np
import trimesh
from trimesh.ray.ray_triangle import RayMeshIntersector, ray_triangle_id


def is_ortho(projection: np.ndarray) -> bool:
    """Orthographic projections keep w = 1 (last row 0 0 0 1); perspective ones have w = -z."""
    return bool(np.isclose(projection[3, 3], 1.0))


def depth_range(projection: np.ndarray) -> tuple[float, float]:
    """(near, far) eye depths of window depth 0 and 1, read off the projection matrix."""
    eye = window_to_eye_depth(np.array([0.0, 1.0]), projection)
    return float(eye[0]), float(eye[1])


def window_to_eye_depth(z: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """Window depth in [0, 1] to distance along the view axis (positive in front of the eye).

    From the projection matrix alone: ``ndc = clip_z / clip_w`` with ``clip_z = a * ze + b`` and
    ``clip_w = -ze`` (perspective) or ``1`` (orthographic), where ``a, b = P[2, 2], P[2, 3]``.
    """
    ndc = 2.0 * np.asarray(z, np.float64) - 1.0
    a, b = projection[2, 2], projection[2, 3]
    if is_ortho(projection):
        return -(ndc - b) / a
    return b / (ndc + a)


def pixel_ndc(width: int, height: int, offset: tuple[float, float] = (0.0, 0.0)):
    """(H, W) NDC x and y of the pixel centres (moved by ``offset`` pixels, +x right, +y down)."""
    x = (np.arange(width) + 0.5 + offset[0]) / width * 2.0 - 1.0
    y = 1.0 - (np.arange(height) + 0.5 + offset[1]) / height * 2.0
    return np.meshgrid(x, y)


def _unproject(inverse: np.ndarray, x: np.ndarray, y: np.ndarray, z: float) -> np.ndarray:
    clip = np.stack([x.ravel(), y.ravel(), np.full(x.size, z), np.ones(x.size)], axis=1)
    points = clip @ inverse.T
    return points[:, :3] / points[:, 3:4]


def pixel_rays(view, projection, width, height, offset=(0.0, 0.0)):
    """Model-space rays through the pixel centres: (origins (N, 3), unit directions (N, 3)).

    Perspective rays start at the eye; orthographic rays are parallel and start on the near
    plane. Ray ``i`` belongs to pixel ``(row, col) = divmod(i, width)``.
    """
    matrix = np.asarray(projection, np.float64) @ np.asarray(view, np.float64)
    inverse = np.linalg.inv(matrix)
    x, y = pixel_ndc(width, height, offset)
    far = _unproject(inverse, x, y, 1.0)
    if is_ortho(projection):
        origins = _unproject(inverse, x, y, -1.0)
    else:
        eye = np.linalg.inv(np.asarray(view, np.float64)) @ np.array([0.0, 0.0, 0.0, 1.0])
        origins = np.broadcast_to(eye[:3] / eye[3], far.shape).copy()
    directions = far - origins
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return origins, directions


def _clip(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    return np.column_stack([points, np.ones(len(points))]) @ matrix.T


def _all_hits(intersector: RayMeshIntersector, origins, directions):
    """Every (face, ray, location) where a ray meets a triangle. Not ``intersects_location``:
    that keeps one of the hits at the very same point, and loses coincident faces' IDs."""
    mesh = intersector.mesh
    return ray_triangle_id(
        mesh.triangles,
        origins,
        directions,
        triangles_normal=mesh.face_normals,
        tree=mesh.triangles_tree,
        multiple_hits=True,
    )


def _cast_model_space(positions, faces, view, projection, width, height, offset):
    """Cast the model-space rays of ``pixel_rays`` at the mesh as it is."""
    mesh = trimesh.Trimesh(positions, faces, process=False, validate=False)
    origins, directions = pixel_rays(view, projection, width, height, offset)
    face, ray, locations = _all_hits(RayMeshIntersector(mesh), origins, directions)
    if len(ray) == 0:
        return ray, face, np.zeros(0)
    clip = _clip(locations, projection @ view)
    return ray, face, 0.5 * clip[:, 2] / clip[:, 3] + 0.5


def _cast_ndc_space(positions, faces, view, projection, width, height, offset):
    """Cast the same rays after mapping mesh and rays to normalised device coordinates.

    ``projection @ view`` followed by the division by w is a projective map: with every vertex
    in front of the eye (w > 0) it keeps straight lines straight, triangles triangles and the
    order of points along a line, and it sends the perspective rays from the eye through the
    pixel centres to lines parallel to z at the pixels' NDC (x, y). So the hits (which triangle,
    in which order) are those of the model-space rays, and each hit's z is its NDC depth.
    The only gain is speed: trimesh's r-tree broad phase boxes each ray by its extent, which is
    a whole diagonal slab of the model for a slanted ray and a point in x, y for these.
    """
    intersector = _ndc_intersector(positions, faces, projection @ view)
    x, y = pixel_ndc(width, height, offset)
    origins = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, -2.0)])
    directions = np.broadcast_to([0.0, 0.0, 1.0], origins.shape)
    face, ray, locations = _all_hits(intersector, origins, directions)
    if len(ray) == 0:
        return ray, face, np.zeros(0)
    return ray, face, 0.5 * locations[:, 2] + 0.5


# the last few NDC meshes with their r-trees, so the shifted rays of ``cast_oracle`` reuse them
_INTERSECTORS: dict[bytes, RayMeshIntersector] = {}


def _ndc_intersector(positions, faces, matrix) -> RayMeshIntersector:
    digest = hashlib.blake2b(digest_size=16)
    for array in (positions, faces, matrix):
        digest.update(np.ascontiguousarray(array).tobytes())
    key = digest.digest()
    if key not in _INTERSECTORS:
        clip = _clip(positions, matrix)
        if (clip[np.unique(faces), 3] <= 0).any():
            raise ValueError("some vertices lie behind the eye; cast in model space instead")
        ndc = clip[:, :3] / np.where(clip[:, 3:4] > 0, clip[:, 3:4], 1.0)
        if len(_INTERSECTORS) >= 4:
            _INTERSECTORS.pop(next(iter(_INTERSECTORS)))
        _INTERSECTORS[key] = RayMeshIntersector(trimesh.Trimesh(ndc, faces, process=False, validate=False))
    return _INTERSECTORS[key]


@dataclass
class Hits:
    """Every hit of a ``raycast_layers`` run, merged ones included, one entry each.

    ``gap`` is the hit's distance (eye depth, fraction of the depth range) behind the last
    surface kept before it: for the hit that starts a surface, the distance to the surface in
    front (inf for the first); for a merged hit, the distance to the surface it joined.
    """

    layer: np.ndarray
    row: np.ndarray
    col: np.ndarray
    face: np.ndarray
    gap: np.ndarray


def raycast_layers(
    positions: np.ndarray,
    faces: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    width: int,
    height: int,
    max_layers: int = 64,
    merge_tol: float = 1e-5,
    *,
    offset: tuple[float, float] = (0.0, 0.0),
    space: str = "ndc",
    return_hits: bool = False,
):
    """Depth layers of a triangle mesh by ray casting, the oracle for ``blueprint.peel``.

    Parameters
    ----------
    positions : (V, 3) float
        Vertex positions in model coordinates.
    faces : (F, 3) int
        Vertex indices per triangle; the face index is the triangle ID.
    view, projection : (4, 4) float
        Model to eye to clip, OpenGL conventions, column vectors.
    width, height : int
        Image size in pixels.
    max_layers : int
        Surfaces kept per pixel at most.
    merge_tol : float
        Hits closer than this to the last surface kept, in eye depth as a fraction of the depth
        range (far - near), merge into that surface (coincident faces, touching parts, hits on
        a shared edge): the surface keeps the nearest hit's depth and face.
    offset : (float, float)
        Move every ray by this many pixels (x right, y down) from the pixel centre.
    space : {"ndc", "model"}
        Where the rays meet the triangles: the model-space rays themselves, or their images in
        normalised device coordinates (same hits, much faster broad phase; see
        ``_cast_ndc_space``).
    return_hits : bool
        Also return every hit (``Hits``), merged ones included, so that a caller can accept any
        face of a merged surface and see how close to the tolerance each merge was.

    Returns
    -------
    depth : (L, H, W) float32
        Window depth in [0, 1] of the k-th surface at each pixel, 1.0 where there is none.
    face : (L, H, W) int64
        Face index of that surface's nearest hit, -1 where there is none.
    hits : Hits
        Only with ``return_hits``; hits of surfaces beyond ``max_layers`` are left out.
    """
    positions = np.asarray(positions, np.float64)
    faces = np.asarray(faces, np.int64)
    view = np.asarray(view, np.float64)
    projection = np.asarray(projection, np.float64)
    cast = {"ndc": _cast_ndc_space, "model": _cast_model_space}[space]
    ray, face, z = cast(positions, faces, view, projection, width, height, offset)

    # the GL clips to 0 <= z <= 1 (the near and far planes)
    keep = (z >= 0.0) & (z <= 1.0)
    ray, face, z = ray[keep], face[keep], z[keep]
    if len(ray) == 0:
        empty = np.zeros(0, np.int64)
        nothing = (np.ones((0, height, width), np.float32), np.full((0, height, width), -1, np.int64))
        return (*nothing, Hits(empty, empty, empty, empty, np.zeros(0))) if return_hits else nothing
    near, far = depth_range(projection)
    eye = window_to_eye_depth(z, projection)
    order = np.lexsort((eye, ray))
    ray, face, z, eye = ray[order], face[order], z[order], eye[order]

    # dense (rays, hits) arrays, hits sorted front to back, inf as padding
    pixels = width * height
    counts = np.bincount(ray, minlength=pixels)
    rank = np.arange(len(ray)) - np.repeat(np.cumsum(counts) - counts, counts)
    slots = int(counts.max()) if len(ray) else 0
    eye_grid = np.full((pixels, slots), np.inf)
    eye_grid[ray, rank] = eye

    # greedy merge, as a peel does it: the next surface is the first hit farther than the
    # tolerance behind the last surface kept; hits within it belong to that surface
    tol = merge_tol * (far - near)
    layer_of_hit = np.empty((pixels, slots), np.int64)
    last = np.full(pixels, -np.inf)
    layers = np.zeros(pixels, np.int64)
    for j in range(slots):
        column = eye_grid[:, j]
        new = np.isfinite(column) & (column > last + tol)
        last = np.where(new, column, last)
        layers += new
        layer_of_hit[:, j] = layers - 1
    hit_layer = layer_of_hit[ray, rank]

    starts = np.r_[True, (ray[1:] != ray[:-1]) | (hit_layer[1:] != hit_layer[:-1])]
    first = np.flatnonzero(starts & (hit_layer < max_layers))
    count = int(min(layers.max(initial=0), max_layers))
    depth = np.ones((count, pixels), np.float32)
    front_face = np.full((count, pixels), -1, np.int64)
    depth[hit_layer[first], ray[first]] = z[first]
    front_face[hit_layer[first], ray[first]] = face[first]
    depth = depth.reshape(count, height, width)
    front_face = front_face.reshape(count, height, width)
    if not return_hits:
        return depth, front_face
    # each hit's distance behind the surface before the one it joined or started
    every = np.flatnonzero(starts)
    surface_eye = np.full((pixels, int(layers.max(initial=0)) + 1), -np.inf)
    surface_eye[ray[every], hit_layer[every] + 1] = eye[every]
    before = np.where(starts, surface_eye[ray, hit_layer], surface_eye[ray, hit_layer + 1])
    inside = hit_layer < max_layers
    row, col = np.divmod(ray[inside], width)
    hits = Hits(hit_layer[inside], row, col, face[inside], ((eye - before) / (far - near))[inside])
    return depth, front_face, hits


def layer_count(depth: np.ndarray) -> np.ndarray:
    """(H, W) number of surfaces at each pixel of an (L, H, W) depth stack."""
    return (depth < 1.0).sum(axis=0)


@dataclass
class Oracle:
    """Ray-cast layers at the pixel centres, with what a fair comparison needs to know.

    depth, face, hits : as ``raycast_layers`` returns them (``hits`` with ``return_hits``)
    boundary : (H, W) bool
        The layer count changes when the ray moves ``shift`` or ``snap`` px along x or y: a
        silhouette, a mesh border or the end of a surface passes within about ``shift`` px of
        the centre, or a feature smaller than ``shift`` (a fold of sub-pixel triangles) lies
        within ``snap`` of it, between the centre and the rays ``shift`` away.
    ambiguous : (H, W) bool
        Some hit lies between half and twice the merge tolerance behind the surface before it,
        so whether it is a surface of its own is decided by rounding.
    slope : (L, H, W) float64
        How fast each surface's eye depth changes per pixel (fraction of the depth range),
        from the shifted rays; ``inf`` where there is no surface.
    moved : list of (L, H, W) float32
        The window depths of the four rays ``shift`` px beside the centre, where they have the
        centre's number of surfaces (1.0 elsewhere): what a rasterizer sampling the surfaces
        that close to the centre may find at a step the count does not see.
    """

    depth: np.ndarray
    face: np.ndarray
    hits: Hits
    boundary: np.ndarray
    ambiguous: np.ndarray
    slope: np.ndarray
    projection: np.ndarray
    merge_tol: float
    moved: list = field(default_factory=list)


def cast_oracle(
    positions,
    faces,
    view,
    projection,
    width,
    height,
    *,
    shift=0.25,
    snap=1 / 16,
    merge_tol=1e-5,
    max_layers=64,
    space="ndc",
) -> Oracle:
    """``raycast_layers`` at the pixel centres and at four rays ``shift`` px beside them, and
    four ``snap`` px beside them for the boundary alone.

    ``snap`` is the rasteriser's vertex snapping at the spec's minimum GL_SUBPIXEL_BITS (4):
    an edge that close to a centre may cover it or not in a correct renderer. The rays a
    quarter pixel away do not see an edge that close when the whole feature is smaller than a
    quarter pixel: on dragon's top view (64², llvmpipe) the GPU drew two surfaces more than
    the rays at a pixel whose centre lay 4e-4 px outside a fold of two triangles of 0.01 px².
    """
    kwargs = dict(max_layers=max_layers, merge_tol=merge_tol, space=space)
    depth, face, hits = raycast_layers(
        positions, faces, view, projection, width, height, return_hits=True, **kwargs
    )
    near, far = depth_range(projection)
    eye = (window_to_eye_depth(depth, projection) - near) / (far - near)
    count = layer_count(depth)
    boundary = np.zeros((height, width), bool)
    slope = np.where(depth < 1.0, 0.0, np.inf)
    beside = []
    for offset in ((shift, 0), (-shift, 0), (0, shift), (0, -shift)):
        moved, _ = raycast_layers(positions, faces, view, projection, width, height, offset=offset, **kwargs)
        boundary |= layer_count(moved) != count
        beside.append(np.where(layer_count(moved) == count, _pad(moved[: len(depth)], len(depth), 1.0), 1.0))
        same = min(len(moved), len(depth))
        moved_eye = (window_to_eye_depth(moved[:same], projection) - near) / (far - near)
        change = np.abs(moved_eye - eye[:same]) / shift
        slope[:same] = np.maximum(slope[:same], np.where(depth[:same] < 1.0, change, np.inf))
    for offset in ((snap, 0), (-snap, 0), (0, snap), (0, -snap)):
        moved, _ = raycast_layers(positions, faces, view, projection, width, height, offset=offset, **kwargs)
        boundary |= layer_count(moved) != count
    ambiguous = np.zeros((height, width), bool)
    near_tol = (hits.gap > 0.5 * merge_tol) & (hits.gap < 2.0 * merge_tol)
    ambiguous[hits.row[near_tol], hits.col[near_tol]] = True
    return Oracle(
        depth, face, hits, boundary, ambiguous, slope, np.asarray(projection, np.float64), merge_tol, beside
    )


def accepted_faces(oracle: Oracle, triangle: np.ndarray) -> np.ndarray:
    """(L, H, W) bool: ``triangle[k, r, c]`` is one of the faces whose hits the oracle merged into
    surface ``k`` at pixel ``(r, c)`` (any of them is right where faces coincide)."""
    layers, height, width = triangle.shape
    faces = int(max(triangle.max(initial=0), oracle.hits.face.max(initial=0))) + 1
    h = oracle.hits
    inside = h.layer < layers
    known = ((h.layer[inside] * height + h.row[inside]) * width + h.col[inside]) * faces + h.face[inside]
    k, r, c = np.indices(triangle.shape)
    asked = ((k * height + r) * width + c) * faces + triangle
    return np.isin(asked, known) & (triangle >= 0)


@dataclass
class Comparison:
    """GPU layers against the oracle, pixel by pixel (see ``compare_layers``)."""

    covered: np.ndarray  # (H, W) either side has a surface
    excluded: np.ndarray  # (H, W) covered, but a boundary passes the pixel centre
    ambiguous: np.ndarray  # (H, W) the oracle's merge there was within a factor 2 of the tolerance
    count_ok: np.ndarray  # (H, W) same number of surfaces
    depth_ok: np.ndarray  # (H, W) every surface within tolerance
    error: np.ndarray  # (L, H, W) |eye depth difference| / depth range, 0 where either is absent
    allowed: np.ndarray  # (L, H, W) the tolerance
    gpu_count: np.ndarray  # (H, W) surfaces per pixel on the GPU
    oracle_count: np.ndarray  # (H, W) and from the rays
    gpu_layers: int
    oracle_layers: int

    @property
    def compared(self) -> np.ndarray:
        return self.covered & ~self.excluded

    @property
    def agree(self) -> np.ndarray:
        return self.compared & self.count_ok & self.depth_ok

    @property
    def fraction(self) -> float:
        return float(self.agree.sum() / max(self.compared.sum(), 1))

    def describe(self, limit: int = 5) -> str:
        bad = np.argwhere(self.compared & ~(self.count_ok & self.depth_ok))
        lines = [
            f"{self.agree.sum()} of {self.compared.sum()} compared pixels agree "
            f"({100 * self.fraction:.3f} %); "
            f"{self.covered.sum()} covered, {self.excluded.sum()} excluded; layers GPU {self.gpu_layers}, "
            f"oracle {self.oracle_layers}; {(self.compared & ~self.count_ok).sum()} differ in count, "
            f"{(self.compared & self.count_ok & ~self.depth_ok).sum()} in depth; largest depth error "
            f"{self.error.max(axis=0)[self.compared & self.count_ok].max(initial=0):.3g} of the depth "
            f"range where the counts agree; "
            f"{(self.compared & self.ambiguous & ~self.agree).sum()} of those that differ had hits "
            f"within a factor 2 of the merge tolerance"
        ]
        for r, c in bad[:limit]:
            if not self.count_ok[r, c]:
                lines.append(
                    f"  pixel (row {r}, col {c}): {self.gpu_count[r, c]} surfaces on the GPU, "
                    f"{self.oracle_count[r, c]} from the rays"
                )
                continue
            k = int(np.argmax(self.error[:, r, c] - self.allowed[:, r, c]))
            lines.append(
                f"  pixel (row {r}, col {c}): layer {k} is {self.error[k, r, c]:.3g} of the depth "
                f"range off, {self.allowed[k, r, c]:.3g} allowed"
            )
        return "\n".join(lines)


def _pad(stack: np.ndarray, layers: int, fill) -> np.ndarray:
    out = np.full((layers, *stack.shape[1:]), fill, stack.dtype)
    out[: len(stack)] = stack
    return out


def compare_layers(
    gpu_depth: np.ndarray, oracle: Oracle, *, abs_tol: float = 1e-5, px_tol: float = 1 / 16
) -> Comparison:
    """Compare a GPU depth stack with the oracle's at every covered pixel.

    A pixel agrees when both have the same number of surfaces and each GPU surface's eye depth
    is within ``abs_tol`` of the depth range plus ``px_tol`` pixels' worth of the surface's
    slope (per pixel, from the oracle's shifted rays). ``abs_tol`` = 1e-5 is ten times what
    float32 window depth costs on these cameras (flat surfaces agree to about 1e-6). The slope
    term is the rasterizer's geometry: GL snaps vertices to a sub-pixel grid (GL_SUBPIXEL_BITS,
    at least 4 by the spec, 8 on llvmpipe), so a correct renderer samples a surface within
    1/16 px of the true centre, and on a face seen at a grazing angle that moves its depth far
    more than rounding does (llvmpipe stays within 1/400 px). A renderer sampling half a pixel
    off is 8 times past that allowance and fails.
    """
    if gpu_depth.shape[1:] != oracle.depth.shape[1:]:
        raise ValueError(f"GPU layers {gpu_depth.shape} and oracle {oracle.depth.shape} differ in size")
    layers = max(len(gpu_depth), len(oracle.depth), 1)
    gpu = _pad(np.asarray(gpu_depth, np.float32), layers, 1.0)
    ora = _pad(oracle.depth, layers, 1.0)
    slope = _pad(oracle.slope, layers, np.inf)
    near, far = depth_range(oracle.projection)
    both = (gpu < 1.0) & (ora < 1.0)
    gpu_eye = window_to_eye_depth(gpu, oracle.projection)
    ora_eye = window_to_eye_depth(ora, oracle.projection)
    error = np.where(both, np.abs(gpu_eye - ora_eye) / (far - near), 0.0)
    allowed = abs_tol + np.where(np.isfinite(slope), slope, 0.0) * px_tol
    # A step that keeps the layer count (the rim of a pocket seen head-on, its walls edge-on)
    # within a quarter pixel of the centre: which side the centre falls on is the rasterizer's
    # vertex snapping, as at a boundary the count sees; the depth of a ray on the other side,
    # a quarter pixel away, is as right as the centre's. Only there: a quarter pixel away on a
    # smooth surface is 4 times ``px_tol``, so an offset renderer still fails.
    for moved in oracle.moved:
        other = _pad(np.asarray(moved, np.float32), layers, 1.0)
        step = np.where(
            both & (other < 1.0),
            np.abs(gpu_eye - window_to_eye_depth(other, oracle.projection)) / (far - near),
            np.inf,
        )
        error = np.where(step <= abs_tol, 0.0, error)
    count_gpu, count_ora = layer_count(gpu), layer_count(ora)
    covered = (count_gpu > 0) | (count_ora > 0)
    return Comparison(
        covered=covered,
        excluded=covered & oracle.boundary,
        ambiguous=oracle.ambiguous,
        count_ok=count_gpu == count_ora,
        gpu_count=count_gpu,
        oracle_count=count_ora,
        depth_ok=(error <= allowed).all(axis=0),
        error=error,
        allowed=allowed,
        gpu_layers=len(gpu_depth),
        oracle_layers=len(oracle.depth),
    )


def surfaces_in_front(positions, faces, points, toward_eye, start: float, merge: float) -> np.ndarray:
    """(N,) surfaces in front of each of ``points`` (N, 3): the rays from them towards the eye
    (``toward_eye``, (3,) for every point or (N, 3), any length), starting ``start`` along the
    ray (past the faces through the point itself), cross this many surfaces, hits closer than
    ``merge`` along the ray to the last surface counted being part of it (coincident faces).
    The occlusion level a drawing's line has at those points, ray cast in float64."""
    points = np.asarray(points, np.float64).reshape(-1, 3)
    direction = np.broadcast_to(np.asarray(toward_eye, np.float64), points.shape)
    direction = direction / np.linalg.norm(direction, axis=1, keepdims=True)
    origins = points + start * direction
    positions = np.asarray(positions, np.float64)
    mesh = trimesh.Trimesh(positions, np.asarray(faces), process=False, validate=False)
    _, ray, locations = _all_hits(RayMeshIntersector(mesh), origins, np.ascontiguousarray(direction))
    count = np.zeros(len(points), np.int64)
    if len(ray) == 0:
        return count
    t = np.einsum("ij,ij->i", locations - origins[ray], direction[ray])
    order = np.lexsort((t, ray))
    ray, t = ray[order], t[order]
    last = np.full(len(points), -np.inf)
    for r, at in zip(ray.tolist(), t.tolist(), strict=True):
        if at > last[r] + merge:
            count[r] += 1
            last[r] = at
    return count
