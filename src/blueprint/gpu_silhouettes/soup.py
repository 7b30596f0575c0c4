"""A deforming mesh on the GPU, drawn as a triangle soup whose corners are replaced each frame."""

from __future__ import annotations

import numpy as np

from blueprint.errors import InputError
from blueprint.render.mesh import identity_instance, instance_layout
from blueprint.render.renderer import LayerRenderer
from blueprint.silhouette.edgerecords import edge_records
from blueprint.silhouette.idlist import build_id_lists, id_lists_from_topology
from blueprint.silhouette.mesh import build_adjacency, connect

from .context import CurrentContext, on_gl
from .lines import EdgeBuffer
from .tables import Corners, ListTextures, diagonal


class SoupMesh:
    """A deforming triangle mesh on the GPU, drawn as a soup: F triangles whose corner
    positions are replaced every frame.

    Create it with :meth:`GpuSilhouettes.soup`. :meth:`update` uploads new positions, one
    buffer write and nothing else: the same buffer is the vertex buffer of the ID pass and the
    vertex storage of the silhouette pass. The number of triangles is fixed; the topology may
    change freely (the ``"vertex"`` method never looks at it). For the ``"idlist"`` and
    ``"edges"`` methods pass the connectivity as `topology` whenever it changes; without one,
    their tables are built once by welding the first positions. ``renderer``, ``current``
    (its context made current) and ``tolerance`` (a fraction of the diagonal) are those of the
    ``GpuSilhouettes`` that made it.

    Attributes
    ----------
    bounds : np.ndarray
        (2, 3) float64 box of the positions given at creation (used to fit a camera).
    tolerance : float
        Model-space distance under which two corners are one vertex, fixed at creation.
    diagonal : float
        Length of the diagonal of `bounds`.
    """

    def current(self):
        return self._current()

    def __init__(
        self,
        renderer: LayerRenderer,
        current: CurrentContext,
        tolerance: float,
        corners,
        face_part=None,
        topology=None,
    ) -> None:
        self.renderer, self._current = renderer, current
        with self.current():
            self._create(tolerance, corners, face_part, topology)

    def _create(self, tolerance: float, corners, face_part, topology) -> None:
        corners = np.asarray(corners, dtype=np.float32)
        if corners.ndim != 3 or corners.shape[1:] != (3, 3) or len(corners) == 0:
            raise InputError(f"corners must have shape (F, 3, 3) with F > 0, got {corners.shape}")
        if not np.isfinite(corners).all():
            raise InputError("corner positions must be finite")
        ctx = self.renderer.ctx
        self.faces = len(corners)
        self.corners = Corners(ctx, self.faces)
        self.corners.write(corners)
        points = corners.reshape(-1, 3).astype(np.float64)
        self.bounds = np.array([points.min(axis=0), points.max(axis=0)])
        self.diagonal = diagonal(points)
        self.tolerance = tolerance * self.diagonal
        # what the renderer's geometry pass needs of a mesh: vertex arrays, the part per vertex
        self._vaos: dict[int, object] = {}
        parts = np.zeros(self.faces, np.int32) if face_part is None else np.asarray(face_part, np.int32)
        self._corner_parts = ctx.buffer(np.repeat(parts, 3).astype(np.int32))
        self._instance = identity_instance(ctx)
        # ...and what the capture table's thresholds weigh (render.table.Request)
        self.triangles, self.part_count = self.faces, int(parts.max(initial=0)) + 1
        self._first = corners
        self._topology = None if topology is None else tuple(topology)
        self._lists: ListTextures | None = None
        self._edges: EdgeBuffer | None = None

    @property
    def triangle_count(self) -> int:
        return self.faces

    @property
    def vertex_defines(self) -> dict:
        """Its draws read their instance, the identity (instance.glsl; ``GpuMesh``'s)."""
        return {"UNPLACED": False}

    def vao(self, program):
        """The soup drawn with `program` (the renderer's geometry pass): corner 3f + k is vertex
        3f + k, so ``gl_PrimitiveID`` is the face index. No normals: the pass's normal target
        is not read by the silhouette pass."""
        vao = self._vaos.get(program.glo)
        if vao is None:
            layout = [(self.corners.buffer, "3f", "in_position")]
            if "in_part" in program:
                layout.append((self._corner_parts, "1i", "in_part"))
            layout.append(instance_layout(self._instance, program))
            vao = self._vaos[program.glo] = self.renderer.ctx.vertex_array(program, layout)
            vao.vertices = 3 * self.faces
        return vao

    @on_gl
    def update(self, corners, topology=None) -> None:
        """Replace the corner positions, (F, 3, 3) float; `topology`, ``(faces, vertices)``
        of the new connectivity, only where it changed and only for the ``"idlist"`` and
        ``"edges"`` methods."""
        self.corners.write(corners)
        if topology is not None:
            self._topology = tuple(topology)
            self._drop_tables()

    def _drop_tables(self) -> None:
        for held in (self._lists, self._edges):
            if held is not None:
                held.release()
        self._lists = self._edges = None

    @on_gl
    def id_lists(self) -> ListTextures:
        if self._lists is None:
            if self._topology is not None:
                faces, vertices = self._topology
                lists = id_lists_from_topology(faces, vertices)
            else:
                flat = self._first.reshape(-1, 3)
                lists = build_id_lists(flat, np.arange(len(flat)).reshape(-1, 3), self.tolerance)
            if len(lists.face_vertices) != self.faces:
                raise InputError(f"topology has {len(lists.face_vertices)} faces, the mesh {self.faces}")
            self._lists = ListTextures(self.renderer.ctx, lists)
        return self._lists

    @on_gl
    def edges(self) -> EdgeBuffer:
        """The edge records of the current topology (see :mod:`blueprint.silhouette.edgerecords`)."""
        if self._edges is None:
            flat = self._first.reshape(-1, 3).astype(np.float64)
            if self._topology is not None:
                faces, vertices = self._topology
                faces = np.asarray(faces, np.int64).reshape(-1, 3)
                if len(faces) != self.faces:
                    raise InputError(f"topology has {len(faces)} faces, the mesh {self.faces}")
                # only the corner order matters to the records, not where the vertices lie
                positions = np.zeros((int(vertices), 3))
                positions[faces.reshape(-1)] = flat
                adjacency = connect(positions, faces)
            else:
                adjacency = build_adjacency(flat, np.arange(len(flat)).reshape(-1, 3), self.tolerance)
            self._edges = EdgeBuffer(self.renderer.ctx, edge_records(adjacency))
        return self._edges

    @on_gl
    def release(self) -> None:
        for obj in (*self._vaos.values(), self._corner_parts, self._instance):
            obj.release()
        self._vaos.clear()
        self.corners.release()
        self._drop_tables()


def box_corners(bounds: np.ndarray) -> np.ndarray:
    """The 8 corners, (8, 3), of a (2, 3) box, for fitting a camera to it."""
    lo, hi = bounds
    return np.array(
        [[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )
