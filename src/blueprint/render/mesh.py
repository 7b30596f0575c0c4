"""A model's triangles on the GPU, and the programs of the geometry passes drawing them."""

from __future__ import annotations

import numpy as np

from blueprint.scene.model import Model
from blueprint.scene.prepare import gpu_arrays

GEOMETRY_VERT = "blueprint.render:glsl/geometry.vert"


def geometry_program(capturer, fragment: str, defines=None, modern: bool = False):
    """A geometry pass's program (geometry.vert and ``fragment``) on ``capturer``'s device,
    with its depth rule: fragment_depth.glsl's EXACT_DEPTH where its capture table's
    ``exact_depth`` (then ``u_target``, the target's size, is the program's to set:
    ``target_uniform``)."""
    defines = {**(defines or {}), "EXACT_DEPTH": capturer.table.exact_depth}
    return capturer.device.program(fragment, GEOMETRY_VERT, defines, modern=modern)


def target_uniform(r, prog, size: tuple[int, int]) -> None:
    """The size of the target a geometry pass of ``geometry_program`` draws into."""
    r.uniforms.set(prog, "u_target", (float(size[0]), float(size[1])))


class GpuMesh:
    """A model's triangles on the GPU: shared vertices (split only where crease-split normals
    differ), every face in the index buffer in model order so ``gl_PrimitiveID`` is the face
    index (degenerate faces rasterise to nothing), and each vertex's part. Without a
    crease angle the normals are left zero, for passes that draw no normals (ID buffers): the
    smoothing is most of the time of an upload."""

    def __init__(self, ctx, model: Model, crease_angle: float | None) -> None:
        self.ctx = ctx
        vertices, indices = gpu_arrays(model, crease_angle)
        self.vbo = ctx.buffer(vertices)
        self.ibo = ctx.buffer(indices)
        self._vaos: dict[int, object] = {}
        self._corners = None
        self._model = model
        self.part_count = len(model.part_names)
        self.triangles = len(model.faces)
        self.bounds = model.bounds  # (2, 3): its used vertices' corners

    def vao(self, program):
        """The vertex array of these buffers for ``program`` (a vertex array binds one program)."""
        vao = self._vaos.get(program.glo)
        if vao is None:
            # attributes a program does not read (pipeline attribute passes need no part, ID
            # passes no normal) are skipped over
            fields = [("3f", "in_position"), ("3f", "in_normal"), ("1i", "in_part")]
            used = [(f, name) if name in program else (f"{4 * int(f[0])}x", None) for f, name in fields]
            layout = [(self.vbo, " ".join(f for f, _ in used), *(name for _, name in used if name))]
            vao = self._vaos[program.glo] = self.ctx.vertex_array(program, layout, index_buffer=self.ibo)
        return vao

    def bind_corners(self, prog, unit: int) -> None:
        """Give an edge program the corner positions of every face (3 texels per face, rows of
        4096) and the tolerance under which two corners are one vertex, for ID silhouettes."""
        if self._corners is None:
            corners = self._model.positions[self._model.faces].reshape(-1, 3).astype(np.float32)
            rows = max(1, -(-len(corners) // 4096))
            data = np.zeros((rows * 4096, 3), np.float32)
            data[: len(corners)] = corners
            self._corners = self.ctx.texture((4096, rows), 3, data.tobytes(), dtype="f4")
            self._corners.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
            diag = float(np.linalg.norm(np.ptp(self._model.bounds, axis=0))) or 1.0
            self._tolerance = diag * 1e-6
        self._corners.use(unit)
        prog["u_corners"].value = unit
        prog["u_tolerance2"].value = self._tolerance**2

    def release(self) -> None:
        for obj in (*self._vaos.values(), self.vbo, self.ibo, self._corners):
            if obj is not None:
                obj.release()
