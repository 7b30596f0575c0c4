"""The line method's pass: the object-space silhouette and border edges of a mesh classified and
drawn, anti-aliased, on the GPU, once per peeled depth layer into that layer's r8 texture (max
blending, so crossing lines keep the stronger coverage), and their read-back. The last layer
asked for holds every edge behind the one before; the pass of that one before draws it too, so
L layers take L - 1 geometry passes and as many line passes (the default 2: one of each)."""

from __future__ import annotations

import numpy as np

from blueprint.gpu import units
from blueprint.render.gbuffer import depth_range
from blueprint.render.renderer import LayerRenderer
from blueprint.scene.camera import Camera

from .tables import Corners

LINES_VERT = "blueprint.gpu_silhouettes:glsl/idsil_lines.vert"
LINES_GEOM = "blueprint.gpu_silhouettes:glsl/idsil_lines.geom"
LINES_FRAG = "blueprint.gpu_silhouettes:glsl/idsil_lines.frag"
# The CPU method's default width (draw_segments): coverage reaches 0 one pixel from the segment.
LINE_WIDTH = 1.0
# Eye-depth tolerance of the layer test, as a fraction of the model's bounding-box diagonal:
# well above the depth buffer's resolution, below the gap between surfaces that read as apart.
MARGIN = 2e-3
CORNERS_UNIT = units.SILHOUETTE_IDS + 1


class EdgeBuffer:
    """Edge records (``blueprint.silhouette.edgerecords``) of one topology in a GPU buffer, and
    on the CPU as `records`."""

    def __init__(self, ctx, records: np.ndarray) -> None:
        self.records = records
        self.count = len(records)
        # a buffer cannot be empty; a mesh without edges draws no instance of it
        data = records if len(records) else np.zeros((1, 4), np.int32)
        self.buffer = ctx.buffer(np.ascontiguousarray(data, dtype=np.int32).tobytes())
        self._vaos: dict[int, object] = {}

    def vao(self, ctx, program):
        vao = self._vaos.get(program.glo)
        if vao is None:
            vao = self._vaos[program.glo] = ctx.vertex_array(program, [(self.buffer, "4i", "in_edge")])
        return vao

    def release(self) -> None:
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
        self.buffer.release()


class LinePass:
    """Draws the edges of `edges` over `corners` seen by `camera` into `layers` textures of
    `size`, one :meth:`run` a peeled layer; `diagonal` scales the depth tolerance."""

    def __init__(
        self,
        r: LayerRenderer,
        edges: EdgeBuffer,
        corners: Corners,
        camera: Camera,
        size: tuple[int, int],
        layers: int,
        diagonal: float,
    ) -> None:
        ctx = r.ctx
        self.r, self.edges, self.size, self.layers = r, edges, size, layers
        self.prog = prog = r.program(LINES_FRAG, LINES_VERT, geometry=LINES_GEOM)
        self.vao = edges.vao(ctx, prog)
        self.targets = [r.pool.texture(f"idsil.line.{k}", size, "r8") for k in range(layers)]
        # the last layer peeled writes the layer after it too (see the module's docstring)
        last = self.peeled - 1
        self.fbos = [
            r.pool.framebuffer(tuple(self.targets[k : k + 2]) if k == last else (self.targets[k],))
            for k in range(self.peeled)
        ]
        for fbo in self.fbos:
            fbo.clear(0.0, 0.0, 0.0, 0.0)
        corners.as_texture().use(CORNERS_UNIT)
        prog["u_corners"].value = CORNERS_UNIT
        view = camera.view_matrix()
        prog["u_view"].write(view.T.astype("f4").tobytes())
        prog["u_projection"].write(camera.projection_matrix().T.astype("f4").tobytes())
        to_model = np.linalg.inv(view)
        prog["u_ortho"].value = bool(camera.ortho)
        prog["u_eye"].value = tuple(to_model[:3, 3])
        prog["u_toward"].value = tuple(to_model[:3, 2])
        prog["u_size"].value = tuple(float(v) for v in size)
        prog["u_reach"].value = 0.5 * LINE_WIDTH + 0.5
        prog["u_depth_range"].value = depth_range(camera)
        prog["u_margin"].value = MARGIN * diagonal

    @property
    def peeled(self) -> int:
        """The depth layers to peel: one fewer than the layers drawn, at least one."""
        return max(self.layers - 1, 1)

    def run(self, layer: int, guard=None) -> None:
        """Draw the edges on layer `layer` (its depth and the layer before's bound where the
        peel holds them) and, on the last layer peeled, those behind it into the next layer;
        with `guard`, the layer before's query, skipped on the GPU when that layer was empty."""
        if self.edges.count == 0:
            return
        ctx, prog = self.r.ctx, self.prog
        prog["u_layer_depth"].value = units.PEEL_DEPTH + layer % 2
        prog["u_front_depth"].value = units.PEEL_DEPTH + (layer - 1) % 2
        prog["u_first"].value = layer == 0
        prog["u_split"].value = layer + 1 < self.layers and layer == self.peeled - 1
        self.fbos[layer].use()
        ctx.enable_only(ctx.BLEND)
        ctx.blend_func = ctx.ONE, ctx.ONE
        ctx.blend_equation = ctx.MAX
        try:
            if guard is not None:
                with guard.crender:
                    self.vao.render(ctx.POINTS, vertices=self.edges.count)
            else:
                self.vao.render(ctx.POINTS, vertices=self.edges.count)
        finally:
            ctx.blend_equation = ctx.FUNC_ADD
            ctx.enable_only(ctx.NOTHING)

    def read(self) -> np.ndarray:
        """(layers, H, W) float32 coverage in [0, 1], row 0 at the top."""
        w, h = self.size
        data = np.stack([np.frombuffer(t.read(), np.uint8).reshape(h, w) for t in self.targets])
        return data[:, ::-1].astype(np.float32) / 255.0
