"""The silhouette pass of one depth layer, as a compute shader writing one slice of an image
array or as a full-screen fragment pass into one texture per layer, and its read-back."""

from __future__ import annotations

import numpy as np

from blueprint.gpu import units
from blueprint.ops import Op
from blueprint.render.renderer import LayerRenderer

from .ops import IDSIL_VERTEX
from .tables import Corners, ListTextures

# Texture units of the pass (the G-buffer pass holds 0-2; the renderer's edges use 3-4).
IDS_UNIT, TABLE_UNIT = units.SILHOUETTE_IDS, units.SILHOUETTE_IDS + 1


def silhouette_pass(
    renderer: LayerRenderer,
    op: Op,
    size: tuple[int, int],
    layers: int,
    corners: Corners,
    lists: ListTextures | None,
    tolerance: float,
    *,
    compute: bool,
) -> ComputePass | FragmentPass:
    """The pass of `op` over `layers` layers of `size`, its tables bound: `corners` and
    `tolerance` for the vertex method, `lists` for the ID-list one. It reads the ID buffer at
    ``IDS_UNIT``."""
    if compute:
        prog = renderer.compute(op.compute)
        target = renderer.pool.texture("idsil.edges", size, "r8", layers)
        out = ComputePass(renderer, prog, target, size)
    else:
        prog, vao = renderer.fullscreen(op.shader)
        out = FragmentPass(renderer, prog, vao, size, layers)
    prog["u_ids"].value = IDS_UNIT
    if op is IDSIL_VERTEX:
        prog["u_tolerance2"].value = tolerance * tolerance
        if compute:
            corners.buffer.bind_to_storage_buffer(0)
        else:
            corners.as_texture().use(TABLE_UNIT)
            prog["u_corners"].value = TABLE_UNIT
    else:
        for k, (name, tex) in enumerate(
            zip(("u_face_vertices", "u_pointers", "u_lists"), lists.textures, strict=True)
        ):
            tex.use(TABLE_UNIT + k)
            prog[name].value = TABLE_UNIT + k
    return out


class ComputePass:
    def __init__(self, r: LayerRenderer, prog, target, size) -> None:
        self.r, self.prog, self.target, self.size = r, prog, target, size

    def run(self, layer: int) -> None:
        self.target.bind_to_image(1, read=False, write=True)
        self.prog["u_depth"].value = layer % 2
        self.prog["u_layer"].value = layer
        self.prog.run((self.size[0] + 7) // 8, (self.size[1] + 7) // 8)

    def read(self) -> np.ndarray:
        ctx = self.r.ctx
        ctx.memory_barrier(ctx.TEXTURE_UPDATE_BARRIER_BIT)
        w, h = self.size
        data = np.frombuffer(self.target.read(), np.uint8).reshape(-1, h, w)
        return (data[:, ::-1] > 127).astype(np.float32)


class FragmentPass:
    def __init__(self, r: LayerRenderer, prog, vao, size, layers: int) -> None:
        self.prog, self.vao = prog, vao
        self.targets = [r.pool.texture(f"idsil.edge.{k}", size, "r8") for k in range(layers)]
        self.fbos = [r.pool.framebuffer((t,)) for t in self.targets]
        self.size = size

    def run(self, layer: int) -> None:
        self.prog["u_depth"].value = layer % 2
        self.fbos[layer].use()
        self.vao.render(vertices=3)

    def read(self) -> np.ndarray:
        w, h = self.size
        data = np.stack([np.frombuffer(t.read(), np.uint8).reshape(h, w) for t in self.targets])
        return (data[:, ::-1] > 127).astype(np.float32)
