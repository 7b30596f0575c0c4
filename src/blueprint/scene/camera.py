"""Cameras: named views, auto-fit to a model, OpenGL view and projection matrices, and the
projection of model points to pixels.

``fit_camera`` is the one way a drawing gets its camera from a view name and an image size;
``to_pixels`` (``Camera.to_pixels``) the one way a point finds its pixel, and ``transform`` with
``clip_to_pixels`` its two steps, for code that works between them (clipping at the near plane,
lighting in eye space).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import TypeVar

import numpy as np

from blueprint import parallel
from blueprint.columns import column_max, column_min
from blueprint.errors import InputError
from blueprint.scene.model import Model

# (azimuth, elevation) in degrees; azimuth turns from the front towards the right.
VIEWS: dict[str, tuple[float, float]] = {
    "iso": (45.0, math.degrees(math.atan(1 / math.sqrt(2)))),
    "front": (0.0, 0.0),
    "back": (180.0, 0.0),
    "left": (-90.0, 0.0),
    "right": (90.0, 0.0),
    "top": (0.0, 90.0),
    "bottom": (0.0, -90.0),
}

# right, up and front axes of a Y-up and a Z-up model (right x up = front)
_BASES = {
    "y": (np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0])),
    "z": (np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, -1.0, 0])),
}


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of two 3-vectors, the same products and differences, without its general
    machinery, which every new camera of a turntable's frames pays twice."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def transform(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Points through a matrix acting on column vectors, as homogeneous points of w = 1.

    Parameters
    ----------
    points : np.ndarray
        (..., 3) points.
    matrix : np.ndarray
        (4, 4): ``view`` (model to eye), ``projection`` (eye to clip) or their product.

    Returns
    -------
    np.ndarray
        (..., 4) float64 transformed points (clip coordinates through a projection).
    """
    points = np.asarray(points, np.float64)
    matrix = np.asarray(matrix, np.float64)
    # w = 1 added as the matrix's last column, not as a column of ones: no (..., 4) copy of
    # the points, and a product of three terms, not four (the same sums)
    out = points @ matrix[:, :3].T
    out += matrix[:, 3]
    return out


def clip_to_pixels(
    clip: np.ndarray, size: tuple[int, int], *, depth: bool = False, origin: str = "top"
) -> np.ndarray:
    """Clip coordinates to pixels of a picture ``size`` (width, height) pixels large.

    Pixels run x right from the left edge and y down from the top edge (row 0 at the top, as the
    drawings have them; ``origin="bottom"``: y up from the bottom edge, OpenGL's window
    coordinates), a pixel's centre at +0.5. The perspective divide takes w = 1 where w is 0 (or
    not a number), so points in the eye's plane stay finite; points behind the eye (w < 0) come
    out mirrored, for callers that drop them.

    Parameters
    ----------
    clip : np.ndarray
        (..., 4) clip coordinates.
    size : tuple[int, int]
        Width and height in pixels.
    depth : bool
        Also return each point's NDC z (-1 at the near plane, 1 at the far one).
    origin : str
        ``"top"`` or ``"bottom"``: the edge that y counts from.

    Returns
    -------
    np.ndarray
        (..., 2) float64 pixels x, y; with ``depth``, (..., 3): x, y and NDC z.
    """
    if origin not in ("top", "bottom"):
        raise ValueError(f"origin must be 'top' or 'bottom', got {origin!r}")
    clip = np.asarray(clip, np.float64)
    w = clip[..., 3]
    w = np.where(np.abs(w) > 0, w, 1.0)
    width, height = size
    # each coordinate worked in place and written once (the sums of the formulas, in their
    # order: (x / w + 1) * 0.5 * width), where temporaries of every point cost more
    x, y = np.empty(w.shape), np.empty(w.shape)
    np.divide(clip[..., 0], w, out=x)
    x += 1.0
    x *= 0.5
    x *= width
    np.divide(clip[..., 1], w, out=y)
    if origin == "top":
        np.subtract(1.0, y, out=y)
    else:
        y += 1.0
    y *= 0.5
    y *= height
    out = np.empty((*clip.shape[:-1], 3 if depth else 2))
    out[..., 0] = x
    out[..., 1] = y
    if depth:
        np.divide(clip[..., 2], w, out=out[..., 2])
    return out


def to_pixels(
    points: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    *,
    depth: bool = False,
) -> np.ndarray:
    """(..., 3) model points to (..., 2) float64 pixels (with ``depth``, (..., 3) with NDC z)
    seen through ``view`` and ``projection`` ((4, 4), OpenGL conventions, column vectors) on a
    picture of ``size`` (width, height) pixels: ``transform`` by their product, then
    ``clip_to_pixels`` (x right, y down from the top-left corner)."""
    mvp = np.asarray(projection, np.float64) @ np.asarray(view, np.float64)
    return clip_to_pixels(transform(points, mvp), size, depth=depth)


@dataclass(frozen=True)
class Camera:
    """A pinhole (perspective) or orthographic camera.

    ``fov`` is the vertical field of view in degrees (perspective); ``height`` the full height of
    the view volume in model units (orthographic). ``aspect`` is width / height.
    """

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float]
    near: float
    far: float
    aspect: float = 1.0
    fov: float = 30.0
    ortho: bool = False
    height: float = 1.0
    name: str = "custom"

    def view_matrix(self) -> np.ndarray:
        """(4, 4) float64: model to eye coordinates (camera looks down -Z)."""
        return self._held("_view", self._view_matrix).copy()

    def projection_matrix(self) -> np.ndarray:
        """(4, 4) float64: eye to clip coordinates, OpenGL conventions (z in [-1, 1])."""
        return self._held("_projection", self._projection_matrix).copy()

    def _held(self, name: str, make) -> np.ndarray:
        # a frame asks for each matrix several times (a pass a layer's uniforms, the capture's),
        # and NumPy's cross products cost a GPU-bound frame more than its draws
        held = self.__dict__.get(name)
        if held is None:
            held = make()
            object.__setattr__(self, name, held)
        return held

    def _view_matrix(self) -> np.ndarray:
        eye, target, up = (np.asarray(v, np.float64) for v in (self.eye, self.target, self.up))
        f = target - eye
        # np.linalg.norm of a vector is this, after checks costing more than the sum
        f /= np.sqrt(f.dot(f))
        s = _cross(f, up)
        s /= np.sqrt(s.dot(s))
        u = _cross(s, f)
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = s, u, -f
        m[:3, 3] = -m[:3, :3] @ eye
        return m

    def _projection_matrix(self) -> np.ndarray:
        n, f = self.near, self.far
        m = np.zeros((4, 4))
        if self.ortho:
            top = self.height / 2
            right = top * self.aspect
            m[0, 0], m[1, 1] = 1 / right, 1 / top
            m[2, 2], m[2, 3] = -2 / (f - n), -(f + n) / (f - n)
            m[3, 3] = 1
        else:
            t = 1 / math.tan(math.radians(self.fov) / 2)
            m[0, 0], m[1, 1] = t / self.aspect, t
            m[2, 2], m[2, 3] = -(f + n) / (f - n), -2 * f * n / (f - n)
            m[3, 2] = -1
        return m

    def to_pixels(self, points: np.ndarray, size: tuple[int, int], *, depth: bool = False) -> np.ndarray:
        """(..., 3) model points to (..., 2) float64 pixels of a picture of ``size`` (width,
        height): x right, y down from the top-left corner; with ``depth``, (..., 3) with NDC z.
        See ``to_pixels``."""
        return to_pixels(points, self.view_matrix(), self.projection_matrix(), size, depth=depth)

    def pixel_angle(self, height_px: int) -> float:
        """Size of one pixel at unit distance (perspective) or in model units (orthographic)."""
        if self.ortho:
            return self.height / height_px
        return 2 * math.tan(math.radians(self.fov) / 2) / height_px

    @classmethod
    def fit(
        cls,
        points: np.ndarray,
        view: str = "iso",
        *,
        azimuth: float | None = None,
        elevation: float | None = None,
        fov: float = 30.0,
        ortho: bool = False,
        aspect: float = 1.0,
        margin: float = 0.05,
        up: str = "y",
    ) -> Camera:
        """Aim at ``points`` (N, 3) from a named view and move back until all of them fit
        (or ``BoxedPoints``, points in groups of known boxes: the same camera, read from the
        groups that may hold the extreme points alone).

        ``azimuth`` / ``elevation`` (degrees) override the named view's angles. ``margin`` is
        the fraction of the image kept free at each side.
        """
        if view not in VIEWS:
            raise InputError(f"unknown view {view!r} (choose {', '.join(VIEWS)})")
        for label, value in (("azimuth", azimuth), ("elevation", elevation)):
            if value is not None and not math.isfinite(value):
                raise InputError(f"{label} must be a finite number of degrees, got {value}")
        if not 0 < fov < 180:
            raise InputError(f"field of view must be between 0 and 180 degrees, got {fov}")
        if not 0 <= margin < 0.5:
            raise InputError(f"margin must be in [0, 0.5), got {margin}")
        az, el = VIEWS[view]
        az = az if azimuth is None else azimuth
        el = el if elevation is None else elevation
        right, up_axis, front = _BASES[up]
        a, e = math.radians(az), math.radians(max(-90.0, min(90.0, el)))
        direction = math.cos(e) * (math.cos(a) * front + math.sin(a) * right) + math.sin(e) * up_axis
        if abs(math.cos(e)) < 1e-6:
            # straight down or up: keep the front of the model at the bottom of the image
            turned = math.cos(a) * front + math.sin(a) * right
            up_vec = -turned if e > 0 else turned
        else:
            up_vec = up_axis
        cam_z = direction / np.linalg.norm(direction)
        cam_x = np.cross(up_vec, cam_z)
        cam_x /= np.linalg.norm(cam_x)
        cam_y = np.cross(cam_z, cam_x)

        lo, hi, most = _reader(points)
        center = (lo + hi) / 2
        extent = float(np.linalg.norm(hi - lo)) or 1.0
        basis = np.stack([cam_x, cam_y, cam_z], axis=1)

        # the points in the camera's axes: the lowest (negated) and highest of each
        ends = most(
            lambda b: _signed_ends((b - center) @ basis),
            lambda corners: _signed_ends_of_boxes((corners - center) @ basis),
            extent,
        )
        low, high = -ends[:3], ends[3:]
        # re-centre on the projected extents so the drawing sits in the middle of the image
        middle = (high[:2] + low[:2]) / 2
        origin, center = center, center + cam_x * middle[0] + cam_y * middle[1]
        half = np.maximum(high[:2] - middle, middle - low[:2])
        z_low, z_high = float(low[2]), float(high[2])
        fill = 1 - 2 * margin
        if ortho:
            height = max(2 * half[1], 2 * half[0] / aspect) / fill
            height = height if height > 0 else extent
            distance = z_high + extent
        else:
            tan_y = math.tan(math.radians(fov) / 2) * fill
            tan_x = tan_y * aspect
            distance = float(
                most(
                    lambda b: _reach(b, origin, middle, basis, tan_x, tan_y).max(keepdims=True),
                    lambda corners: _reach(corners, origin, middle, basis, tan_x, tan_y).max(
                        axis=1, keepdims=True
                    ),
                    extent * (2 + 2 / tan_x + 2 / tan_y),
                )[0]
            )
            distance = max(distance, z_high + extent * 1e-3)
            height = 1.0
        pad = extent * 0.02
        near = max(distance - z_high - pad, distance * 1e-3)
        far = distance - z_low + pad
        eye = center + cam_z * distance
        return cls(
            eye=tuple(eye),
            target=tuple(center),
            up=tuple(cam_y),
            near=near,
            far=far,
            aspect=aspect,
            fov=fov,
            ortho=ortho,
            height=float(height),
            name=view,
        )


T = TypeVar("T")


@dataclass(frozen=True)
class BoxedPoints:
    """Points in groups whose boxes are known, for ``Camera.fit``: ``boxes`` (N, 2, 3)
    float64, the lowest and highest corner of each group's points (their own values), and
    ``blocks(keep)`` an iterator of (M, 3) float64 blocks of the points of the groups ``keep``
    ((N,) bool flags). The fit reads the groups that may hold an extreme point alone: of a
    pattern of many instances, those at its edges."""

    boxes: np.ndarray
    blocks: Callable[[np.ndarray], Iterable[np.ndarray]]


# Points read at a time by ``Camera.fit``: a float64 copy of all at once would take 24 bytes a
# point more than the model holds.
_FIT_BLOCK = 1 << 16


def _reader(points) -> tuple[np.ndarray, np.ndarray, Callable]:
    """(lowest corner, highest corner, ``most``) of the points ``Camera.fit`` reads (an array or
    ``BoxedPoints``): ``most(exact, bound, scale)`` is the most of each of the values
    ``exact(block)`` gives a block ((K,): the most over its points) over every point, read from
    every block, or of ``BoxedPoints`` from the groups whose box may hold it alone
    (``_most_of_groups``)."""
    if isinstance(points, BoxedPoints):

        def most_of_groups(exact, bound, scale):
            return _most_of_groups(points, exact, bound, scale)

        return points.boxes[:, 0].min(axis=0), points.boxes[:, 1].max(axis=0), most_of_groups
    each = _each_block(points)

    def most(exact, bound, scale):
        return np.max(each(exact), axis=0)

    return np.min(each(column_min), axis=0), np.max(each(column_max), axis=0), most


def _each_block(points) -> Callable[[Callable[[np.ndarray], T]], list[T]]:
    """``each(work)``: ``work`` of every block of the points ``Camera.fit`` reads, in order:
    float64 copies of ``_FIT_BLOCK`` rows (each row's products the same as the whole array's),
    the blocks side by side (``blueprint.parallel``)."""
    pts = np.asarray(points).reshape(-1, 3)
    count = max(-(-len(pts) // _FIT_BLOCK), 1)

    def each(work):
        def blocks(first: int, last: int) -> list:
            rows = (pts[k * _FIT_BLOCK : (k + 1) * _FIT_BLOCK] for k in range(first, last))
            return [work(block.astype(np.float64)) for block in rows]

        return [found for done in parallel.run(blocks, count, min_block=4) for found in done]

    return each


def _signed_ends(values: np.ndarray) -> np.ndarray:
    """(6,): the lowest of each column of (N, 3) ``values`` negated, then the highest."""
    return np.concatenate([-column_min(values), column_max(values)])


def _signed_ends_of_boxes(values: np.ndarray) -> np.ndarray:
    """(N, 6): ``_signed_ends`` of each of (N, 8, 3) ``values`` (boxes' corners)."""
    return np.concatenate([-values.min(axis=1), values.max(axis=1)], axis=1)


def _reach(points, origin, middle, basis, tan_x: float, tan_y: float) -> np.ndarray:
    """How far back along the view from the re-centred centre (``middle`` across the view
    from ``origin``) the perspective view holds each of ``points`` (..., 3)."""
    rel = (points - origin) @ basis
    x, y = rel[..., 0] - middle[0], rel[..., 1] - middle[1]
    return rel[..., 2] + np.maximum(np.abs(x) / tan_x, np.abs(y) / tan_y)


# the eight corners of a box as (lowest or highest) picks of each axis
_CORNER_PICKS = np.array([[(k >> axis) & 1 for axis in range(3)] for k in range(8)])


def _most_of_groups(points: BoxedPoints, exact, bound, scale: float) -> np.ndarray:
    """(K,): the most of each of K values over every point of ``points``, each block's by
    ``exact`` (the values as ``Camera.fit`` reads any points), read from the groups alone
    whose box might hold more than the most found so far: ``bound`` gives (N, K) each group's
    most at its box's corners (the values are convex in the point: a box's most is at a
    corner), widened by far more than the values' rounding (``scale``: the size of the terms
    they sum)."""
    corners = np.stack([points.boxes[:, _CORNER_PICKS[:, axis], axis] for axis in range(3)], axis=-1)
    upper = bound(corners)
    upper = upper + 1e-9 * (np.abs(upper) + scale)
    first = np.zeros(len(upper), bool)
    first[upper.argmax(axis=0)] = True
    best = np.max([exact(block) for block in points.blocks(first) if len(block)], axis=0)
    chosen = (upper >= best).any(axis=1) & ~first
    found = [exact(block) for block in points.blocks(chosen) if len(block)] if chosen.any() else []
    return np.max([best, *found], axis=0)


def fit_camera(
    model: Model | np.ndarray,
    size: tuple[int, int],
    view: str = "iso",
    *,
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    margin: float = 0.05,
) -> Camera:
    """The camera of a drawing of ``size`` (width, height in pixels): ``Camera.fit`` on a model's
    positions (or on (N, 3) points) from a named view, at the image's aspect.

    ``up`` is the model's up axis: by default the model's own, or ``"y"`` for bare points.
    """
    if isinstance(model, Model):
        # a flat model's positions are read a block at a time, never all in float64 at once
        flat = model.instances is None or model.is_flat
        points = model.positions if flat else BoxedPoints(model.instance_boxes(), model.placed_points)
        up = up or model.up
    else:
        points, up = model, up or "y"
    width, height = size
    return Camera.fit(
        points,
        view,
        azimuth=azimuth,
        elevation=elevation,
        fov=fov,
        ortho=ortho,
        aspect=width / height if height else 1.0,
        margin=margin,
        up=up,
    )


# A drawing sheet in third-angle projection: (column, row) of each view in a 2 x 2 grid, the
# top view above the front view, the right view beside it, an iso view in the free corner.
SHEET_CELLS: dict[str, tuple[int, int]] = {"top": (0, 0), "iso": (1, 0), "front": (0, 1), "right": (1, 1)}


def sheet_cameras(
    model: Model | np.ndarray, size: tuple[int, int], fov: float = 30.0, up: str | None = None
) -> dict[str, Camera]:
    """The cameras of a sheet's cells (``SHEET_CELLS``), each ``size`` pixels: the three
    orthographic views at one scale (the largest any of them needs), the iso view fitted on its
    own. ``up`` as for ``fit_camera``."""
    fitted = {
        v: fit_camera(model, size, v, ortho=True, up=up, margin=0.08) for v in ("top", "front", "right")
    }
    height = max(c.height for c in fitted.values())
    cameras = {v: replace(c, height=height) for v, c in fitted.items()}
    cameras["iso"] = fit_camera(model, size, "iso", fov=fov, up=up, margin=0.08)
    return cameras
