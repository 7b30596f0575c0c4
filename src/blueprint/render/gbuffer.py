"""The G-buffer a frame's layers are captured into, and what every geometry pass of a capture
takes from the camera (its matrices, depth range and peeling tolerance)."""

from __future__ import annotations

import functools
from dataclasses import dataclass

from blueprint.scene.camera import Camera

# Peeling tolerance in eye depth, as a fraction of the camera's depth range: surfaces closer
# than this count as one (coplanar faces, duplicates, touching parts).
PEEL_EPSILON = 1e-5
# Touching solids have coincident faces of opposite winding (the top of one, the bottom of the
# other). Drawing back faces in a second draw pushed back by this polygon offset (in steps of
# the depth buffer) makes the front face win every pixel of the tie, instead of whichever
# rounds nearer (speckle); it is far below the peeling tolerance, so both still peel as one.
BACK_OFFSET = 16.0
# ...and the same push as a window depth, where a shader applies it
BACK_BIAS = BACK_OFFSET / (1 << 24)


@dataclass
class GBuffer:
    """The targets layers are peeled into: two depth textures that alternate (layer ``i`` in
    ``depth[i % 2]``, the previous layer in the other; in ``flat`` where the A-buffer
    captured the layers: read them through ``layer_depth``), the normal target (None for ID-only
    buffers) and the ID target: (face + 1, part + 1) as rg32i, or face + 1 alone as r32i."""

    depth: tuple
    normal: object | None
    ids: object
    fbos: tuple
    clears: tuple
    # float targets that hold the layers' depths instead, where the A-buffer captured them
    flat: tuple | None = None

    @functools.cached_property
    def size(self) -> tuple[int, int]:
        return tuple(self.depth[0].size)

    def layer_depth(self, layer: int):
        return (self.flat or self.depth)[layer % 2]


def gbuffer(pool, size: tuple[int, int], name: str = "gb", normals: bool = True) -> GBuffer:
    """The G-buffer ``name`` at ``size`` from ``pool``; without ``normals``, face IDs alone (a
    quarter of the bytes a fragment: what triangle-ID passes need)."""
    depth = (pool.depth(f"{name}.depth0", size), pool.depth(f"{name}.depth1", size))
    normal = pool.texture(f"{name}.normal", size, "rgba16f") if normals else None
    ids = pool.texture(f"{name}.ids", size, "rg32i" if normals else "r32i")
    colors = (normal, ids) if normals else (ids,)
    fbos = tuple(pool.framebuffer(colors, d) for d in depth)
    clears = tuple(pool.framebuffer((), d) for d in depth)
    return GBuffer(depth, normal, ids, fbos, clears)


def peel_uniforms(prog, camera: Camera) -> None:
    """What every geometry pass of the peel takes from the camera."""
    prog["u_view"].write(camera.view_matrix().T.astype("f4").tobytes())
    prog["u_projection"].write(camera.projection_matrix().T.astype("f4").tobytes())
    prog["u_depth_range"].value = depth_range(camera)
    prog["u_peel_eps"].value = peel_eps(camera)


@functools.lru_cache(maxsize=16)
def abuffer_uniforms(camera: Camera) -> dict:
    """What an A-buffer's geometry pass and resolve take from the camera (``ABufferSource``);
    kept by the camera's value, as streams may draw from one camera again and again (read
    only)."""
    return {
        "u_view": camera.view_matrix().T.astype("f4").tobytes(),
        "u_projection": camera.projection_matrix().T.astype("f4").tobytes(),
        "u_ortho": camera.ortho,
        "u_depth_range": depth_range(camera),
        "u_peel_eps": peel_eps(camera),
    }


def depth_range(camera: Camera) -> tuple[float, float, float]:
    """``u_depth_range`` of depth.glsl: near, far, and 1 for an orthographic camera."""
    return (camera.near, camera.far, 1.0 if camera.ortho else 0.0)


def peel_eps(camera: Camera) -> float:
    """The peeling tolerance in eye depth for ``camera``."""
    return PEEL_EPSILON * (camera.far - camera.near)
