"""A model's triangles on the GPU, and the programs of the geometry passes drawing them."""

from __future__ import annotations

import numpy as np

from blueprint.scene.model import Model
from blueprint.scene.normals import corner_normals
from blueprint.sorting import unique_first

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
        faces = model.faces
        corner_vertex = faces.reshape(-1).astype(np.int64)
        corner_part = np.repeat(model.face_part, 3).astype(np.int64)
        # a vertex is split where its normal or its part differs, so both can be attributes
        if crease_angle is None:
            normals = None
            # where each vertex lies in one part, the vertex orders the keys alone, over a range
            # that unique_first counts over instead of sorting
            key = corner_vertex
            if len(model.part_names) > 1:
                vertex_part = np.zeros(len(model.positions), np.int64)
                vertex_part[corner_vertex] = corner_part
                if not np.array_equal(vertex_part[corner_vertex], corner_part):
                    key = corner_vertex * len(model.part_names) + corner_part
            _, first, inverse = unique_first(key)
            vertex, part = corner_vertex[first], corner_part[first]
        else:
            normals = corner_normals(model.positions, faces, crease_angle).reshape(-1, 3)
            quantized = np.round(normals * 32767).astype(np.int64)
            keys = np.column_stack([corner_vertex, corner_part, quantized])
            unique, inverse = np.unique(keys, axis=0, return_inverse=True)
            first = np.zeros(len(unique), np.int64)
            first[inverse.reshape(-1)] = np.arange(len(keys))
            vertex, part = unique[:, 0], unique[:, 1]
        data = np.zeros(len(first), [("p", "f4", 3), ("n", "f4", 3), ("part", "i4")])
        data["p"] = model.positions[vertex]
        if normals is not None:
            data["n"] = normals[first]
        data["part"] = part
        self.vbo = ctx.buffer(data.tobytes())
        self.ibo = ctx.buffer(inverse.reshape(-1).astype(np.uint32).tobytes())
        self._vaos: dict[int, object] = {}
        self._corners = None
        self._model = model
        self.part_count = len(model.part_names)
        self.triangles = len(faces)
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
