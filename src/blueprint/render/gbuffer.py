"""The G-buffer a frame's layers are captured into, what every geometry pass of a capture
takes from the camera (its matrices and depth range), and the depth tolerance under which two
surfaces are one, which the capture and the vector drawings' occlusion both take."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from blueprint.scene.camera import Camera

# Surfaces closer in eye depth than this fraction of the model's bounding diagonal are one
# (coplanar faces, duplicates, touching parts): a hundred times float32's rounding of positions
# and depths, far below any gap a part is made with (a slot's clearance).
DEPTH_FRACTION = 1e-5
# Steps of a 24-bit depth buffer (and of float32's mantissa) in a unit
_STEP = 1.0 / (1 << 24)
# Touching solids have coincident faces of opposite winding (the top of one, the bottom of the
# other). Drawing back faces in a second draw pushed back by this polygon offset (in steps of
# the depth buffer) makes the front face win every pixel of the tie, instead of whichever
# rounds nearer (speckle); it is below the depth tolerance, so both still peel as one.
BACK_OFFSET = 16.0
# ...and the same push as a window depth, where a shader applies it
BACK_BIAS = BACK_OFFSET * _STEP


# compared by identity: its GL objects have no equality worth generating at import
@dataclass(eq=False)
class GBuffer:
    """The targets layers are peeled into: two depth textures that alternate (layer ``i`` in
    ``depth[i % 2]``, the previous layer in the other; in ``flat`` where the A-buffer
    captured the layers: read them through ``layer_depth``), the normal target (None for ID-only
    buffers) and the ID target: (face + 1, part + 1) as rg32i, or face + 1 alone as r32i.

    Each target is taken from ``pool`` when first asked for: a capture that leaves its layers
    where it found them (an A-buffer's lists, a k-buffer's surfaces) never asks for the targets
    it does not unpack into, and so never holds them."""

    pool: object
    size: tuple[int, int]
    name: str = "gb"
    normals: bool = True
    # float targets that hold the layers' depths instead, where the A-buffer captured them; or
    # what makes them, called when a layer's depth is first asked for
    flat: tuple | Callable[[], tuple] | None = None

    @functools.cached_property
    def depth(self) -> tuple:
        return tuple(self.pool.depth(f"{self.name}.depth{i}", self.size) for i in (0, 1))

    @functools.cached_property
    def normal(self):
        return self.pool.texture(f"{self.name}.normal", self.size, "rgba16f") if self.normals else None

    @functools.cached_property
    def ids(self):
        return self.pool.texture(f"{self.name}.ids", self.size, "rg32i" if self.normals else "r32i")

    @functools.cached_property
    def fbos(self) -> tuple:
        colors = (self.normal, self.ids) if self.normals else (self.ids,)
        return tuple(self.pool.framebuffer(colors, d) for d in self.depth)

    @functools.cached_property
    def clears(self) -> tuple:
        return tuple(self.pool.framebuffer((), d) for d in self.depth)

    def layer_depth(self, layer: int):
        if callable(self.flat):
            self.flat = self.flat()
        return (self.flat or self.depth)[layer % 2]


def gbuffer(pool, size: tuple[int, int], name: str = "gb", normals: bool = True) -> GBuffer:
    """The G-buffer ``name`` at ``size`` from ``pool``, its targets taken when first used;
    without ``normals``, face IDs alone (a quarter of the bytes a fragment: what triangle-ID
    passes need)."""
    return GBuffer(pool, tuple(size), name, normals)


def peel_uniforms(prog, camera: Camera, tolerance: float) -> None:
    """What every geometry pass of the peel takes from the camera, and the depth tolerance
    (``depth_tolerance``)."""
    prog["u_view"].write(camera.view_matrix().T.astype("f4").tobytes())
    prog["u_projection"].write(camera.projection_matrix().T.astype("f4").tobytes())
    prog["u_depth_range"].value = depth_range(camera)
    prog["u_peel_eps"].value = tolerance


@functools.lru_cache(maxsize=16)
def abuffer_uniforms(camera: Camera, tolerance: float) -> dict:
    """What an A-buffer's geometry pass and resolve take from the camera (``ABufferSource``),
    and the depth tolerance; kept by the camera's value, as streams may draw from one camera
    again and again (read only)."""
    return {
        "u_view": camera.view_matrix().T.astype("f4").tobytes(),
        "u_projection": camera.projection_matrix().T.astype("f4").tobytes(),
        "u_ortho": camera.ortho,
        "u_depth_range": depth_range(camera),
        "u_peel_eps": tolerance,
    }


def depth_range(camera: Camera) -> tuple[float, float, float]:
    """``u_depth_range`` of depth.glsl: near, far, and 1 for an orthographic camera."""
    return (camera.near, camera.far, 1.0 if camera.ortho else 0.0)


def depth_tolerance(camera: Camera, bounds: np.ndarray) -> float:
    """The eye depth under which two surfaces of a model within ``bounds`` seen by ``camera``
    are one: in the peel, the k-buffer, the A-buffer and the vector drawings' occlusion alike.

    ``DEPTH_FRACTION`` of the bounding diagonal, unless the depth buffer cannot tell that much
    apart. A window depth step is ``f - n`` in eye depth on an orthographic camera and
    ``d² (f - n) / (n f)`` at eye depth ``d`` on a perspective one, largest at the far plane:
    ``f (f - n) / n``. The bound is twice the back faces' push (``BACK_OFFSET`` steps there,
    which must stay within it for coincident faces of opposite winding to peel as one), plus
    float32's rounding of eye positions (8 steps of the farthest eye depth and the largest
    coordinate: a model far from the origin, or placed by instances).

    Parameters
    ----------
    camera : Camera
    bounds : (2, 3) float
        The model's lowest and highest corner.

    Returns
    -------
    float
        In the model's units, eye depth (along the view axis).
    """
    # every pass of every frame asks: kept by the camera's value and the bounds' bytes, and
    # the last answer by the very objects asked with (a mesh's bounds do not change), read and
    # set as one tuple (threads of a batch ask too)
    last = _last_tolerance[0]
    if last[0] is camera and last[1] is bounds:
        return last[2]
    tolerance = _tolerance(camera, np.asarray(bounds, np.float64).tobytes())
    _last_tolerance[0] = (camera, bounds, tolerance)
    return tolerance


_last_tolerance: list[tuple] = [(None, None, 0.0)]


@functools.lru_cache(maxsize=64)
def _tolerance(camera: Camera, bounds: bytes) -> float:
    lo, hi = np.frombuffer(bounds, np.float64).reshape(2, 3)
    n, f = camera.near, camera.far
    step = (f - n) if camera.ortho else f * (f - n) / n
    reach = f + float(np.abs(np.concatenate([lo, hi])).max())
    precision = _STEP * (2.0 * BACK_OFFSET * step + 8.0 * reach)
    return max(DEPTH_FRACTION * float(np.linalg.norm(hi - lo)), precision)
