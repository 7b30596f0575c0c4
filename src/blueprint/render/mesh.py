"""A model's triangles on the GPU, and the programs of the geometry passes drawing them."""

from __future__ import annotations

import numpy as np

from blueprint.gpu.fences import OneAhead
from blueprint.scene.model import Model
from blueprint.scene.prepare import gpu_arrays

GEOMETRY_VERT = "blueprint.render:glsl/geometry.vert"
# the storage binding of the placements (instance.glsl's PLACEMENTS), free in every program
# that reads faces by their ID (the compute rasteriser, the A-buffer's resolve)
PLACEMENTS_BINDING = 10
# the most faces a draw call of a software rasteriser draws: llvmpipe holds every triangle of a
# draw call until it has rasterised them, so a big group is drawn a run of faces at a time, each
# set up while the one before is rasterised (flushed only, they would all be held at once again)
PIECE_FACES = 1 << 16
# Parts a k-buffer's or A-buffer's surface holds beside a normal of three halves (16 bits, one
# value kept for none); a mesh of more packs its surfaces' normals in 32 bits (kbuffer.glsl's
# WIDE_PARTS) and its parts whole.
NARROW_PARTS = 0xFFFF


def geometry_program(capturer, fragment: str, mesh, defines=None, modern: bool = False):
    """A geometry pass's program (geometry.vert and ``fragment``) on ``capturer``'s device for
    drawing ``mesh`` (its ``vertex_defines``), with its depth rule: fragment_depth.glsl's
    EXACT_DEPTH where its capture table's ``exact_depth`` (then ``u_target``, the target's
    size, is the program's to set: ``target_uniform``)."""
    defines = {**(defines or {}), **mesh.vertex_defines, "EXACT_DEPTH": capturer.table.exact_depth}
    return capturer.device.program(fragment, GEOMETRY_VERT, defines, modern=modern)


def target_uniform(r, prog, size: tuple[int, int]) -> None:
    """The size of the target a geometry pass of ``geometry_program`` draws into."""
    r.uniforms.set(prog, "u_target", (float(size[0]), float(size[1])))


# One instance of the instance buffer: rows of its affine transform, rows of its normals'
# transform (instance.glsl), its part (added to the vertices') and its first face.
INSTANCE = np.dtype(
    [
        ("x", "f4", 4),
        ("y", "f4", 4),
        ("z", "f4", 4),
        ("nx", "f4", 3),
        ("ny", "f4", 3),
        ("nz", "f4", 3),
        ("part", "i4"),
        ("face", "i4"),
    ]
)
_VERTEX_FIELDS = (("3f", "in_position"), ("3f", "in_normal"), ("1i", "in_part"))
_INSTANCE_FIELDS = (
    ("4f", "i_x"),
    ("4f", "i_y"),
    ("4f", "i_z"),
    ("3f", "i_nx"),
    ("3f", "i_ny"),
    ("3f", "i_nz"),
    ("1i", "i_part"),
    ("1i", "i_face"),
)


# One placement of the faces table (instance.glsl's ``Placement``, std430): an instance's
# transform and normals' transform as ``INSTANCE`` has them (each normal row padded to four),
# its part, its first face ID and where its faces start in the uploaded index buffer (in faces).
PLACEMENT = np.dtype(
    [
        ("x", "f4", 4),
        ("y", "f4", 4),
        ("z", "f4", 4),
        ("nx", "f4", 4),
        ("ny", "f4", 4),
        ("nz", "f4", 4),
        ("part", "i4"),
        ("face", "i4"),
        ("base", "i4"),
        ("pad", "i4"),
    ]
)


def instance_records(transform: np.ndarray, part: np.ndarray, first_face: np.ndarray) -> np.ndarray:
    """(N,) ``INSTANCE``: the records of instances placed by ``transform`` (N, 4, 4), of parts
    ``part`` and first faces ``first_face`` (N,). Normals are carried by the cofactor matrix of
    the transform's linear part (the inverse transpose times its determinant: a mirror turns
    them as it turns the faces' winding, as they are in the flattened scene), scaled to keep
    the length of a similarity's."""
    linear = transform[:, :3, :3]
    columns = [linear[:, :, k] for k in range(3)]
    cofactor = np.stack(
        [
            np.cross(columns[1], columns[2]),
            np.cross(columns[2], columns[0]),
            np.cross(columns[0], columns[1]),
        ],
        axis=2,
    )
    det = np.abs(np.einsum("ni,ni->n", columns[0], cofactor[:, :, 0]))
    scale = np.where(det > 0, det ** (2.0 / 3.0), 1.0)
    cofactor /= scale[:, None, None]
    out = np.zeros(len(transform), INSTANCE)
    for k, row in enumerate("xyz"):
        out[row] = transform[:, k, :]
        out["n" + row] = cofactor[:, k, :]
    out["part"] = part
    out["face"] = first_face
    return out


def draw_groups(model: Model, crease_angle: float | None) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """What ``GpuMesh`` uploads: (vertices ``VERTEX``, indices uint32, instances ``INSTANCE``)
    a draw call. A flattened model is one, its triangles placed by the identity. Of a model kept
    as instances, each mesh used more than once is prepared (``prepare.gpu_arrays``) in its own
    coordinates, once, and drawn at its instances; the instances of meshes used once are
    flattened a run of them (consecutive in the scene's order) at a time, a draw a run, so that
    thousands of distinct parts do not cost thousands of draws."""
    identity = np.eye(4)[None]
    inst = model.instances
    if inst is None:
        vertices, indices = gpu_arrays(model, crease_angle)
        return [(vertices, indices, instance_records(identity, np.zeros(1), np.zeros(1)))]
    first = inst.first_face()
    shared = np.bincount(inst.mesh, minlength=inst.mesh_count)[inst.mesh] > 1
    groups = []
    for m, members in inst.by_mesh(shared):
        positions, faces = inst.mesh_arrays(m)
        mesh = Model.from_arrays(positions, faces)
        vertices, indices = gpu_arrays(mesh, crease_angle)
        groups.append(
            (vertices, indices, instance_records(inst.transform[members], inst.part[members], first[members]))
        )
    alone = np.flatnonzero(~shared)
    if len(alone):
        breaks = np.flatnonzero(np.diff(alone) > 1) + 1
        for run in np.split(alone, breaks):
            keep = np.zeros(len(inst.mesh), bool)
            keep[run] = True
            part_number = np.arange(len(model.part_names))
            from blueprint.scene.instances import flatten

            positions, faces, face_part = flatten(inst.subset(keep, part_number))
            block = Model(positions, faces, face_part, model.part_names)
            vertices, indices = gpu_arrays(block, crease_angle)
            groups.append((vertices, indices, instance_records(identity, np.zeros(1), first[run[:1]])))
    return groups


def joined(groups: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> tuple:
    """``draw_groups``'s groups as one vertex array and one index array: (vertices ``VERTEX``,
    indices uint32 into the whole vertex array, each group's first index and index count
    (G,) int64)."""
    vertex_count = np.array([len(vertices) for vertices, _, _ in groups], np.int64)
    index_count = np.array([len(indices) for _, indices, _ in groups], np.int64)
    vertex_base, index_base = np.cumsum(vertex_count) - vertex_count, np.cumsum(index_count) - index_count
    if len(groups) == 1:
        vertices, indices = groups[0][:2]
    else:
        vertices = np.concatenate([v for v, _, _ in groups])
        indices = np.concatenate([i + np.uint32(b) for (_, i, _), b in zip(groups, vertex_base, strict=True)])
    return vertices, indices, index_base, index_count


def placements(groups: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> np.ndarray:
    """(P,) ``PLACEMENT``: the faces table of ``draw_groups``'s groups uploaded one after
    another, each instance record with its group's first face in the index buffer, ordered by
    first face ID; records of no faces are left out, so the first face IDs rise strictly and
    face ID ``t`` is placed by the last record whose first face is at most ``t``."""
    faces = np.array([len(indices) // 3 for _, indices, _ in groups], np.int64)
    base = np.cumsum(faces) - faces
    records = [(records, b) for (_, _, records), b, f in zip(groups, base, faces, strict=True) if f]
    if not records:
        records = [(instance_records(np.eye(4)[None], np.zeros(1), np.zeros(1)), 0)]
    out = np.zeros(sum(len(r) for r, _ in records), PLACEMENT)
    at = 0
    for r, b in records:
        block = out[at : at + len(r)]
        for row in "xyz":
            block[row] = r[row]
            block["n" + row][:, :3] = r["n" + row]
        block["part"], block["face"], block["base"] = r["part"], r["face"], b
        at += len(r)
    return out[np.argsort(out["face"], kind="stable")]


class GpuMesh:
    """A model's triangles on the GPU, drawn by ``vao(program).render()``: every draw group's
    (``draw_groups``) shared vertices (split only where crease-split normals differ) in one
    vertex buffer (``vbo``), its faces in model order in one index buffer (``ibo``, indices into
    the whole vertex buffer), and each group's instances, so that a face's ID is its instance's
    first face plus ``gl_PrimitiveID`` (degenerate faces rasterise to nothing). With ``pieces``
    (a software rasteriser) a group of more than ``PIECE_FACES`` faces is drawn as draws of at
    most that many, each at its instances with their first faces moved on by the piece's. Without a
    crease angle the normals are left zero, for passes that draw no normals (ID buffers): the
    smoothing is most of the time of an upload.

    Passes that read faces by their ID (the compute rasteriser, the slim A-buffer's resolve)
    read the same buffers through the faces table (``bind_faces``): a placement an instance,
    ordered by first face (``placements``), in which ``instance.glsl`` finds a face's instance
    by a binary search; so a model kept as instances is never flattened for them."""

    # the faces uploaded at a time (None: all of them, once: ``ChunkedMesh`` draws chunks)
    chunk_faces: int | None = None

    def __init__(self, ctx, model: Model, crease_angle: float | None, pieces: bool = False) -> None:
        self.ctx = ctx
        groups = draw_groups(model, crease_angle)
        vertices, indices, index_base, index_count = joined(groups)
        self.vbo, self.ibo = ctx.buffer(vertices), ctx.buffer(indices)
        # (instance records, the draw's first index and index count, whether another piece of
        # its group follows, its first instance's first face) a draw
        limit = PIECE_FACES if pieces else None
        self.groups = [
            (ctx.buffer(piece), len(piece), int(first + at), int(count), wait, int(piece["face"][0]))
            for (_, _, records), first, faces in zip(groups, index_base, index_count // 3, strict=True)
            for piece, at, count, wait in _pieces(records, int(faces), limit)
        ]
        table = placements(groups)
        # a flattened model's one placement, the identity from face 0: programs look up nothing
        self.one_placement = len(table) == 1 and _identity(table[0])
        self._placements = ctx.buffer(table)
        del groups, vertices, indices
        self._vaos: dict[int, _Draws] = {}
        self._of_model(model)

    def _of_model(self, model: Model) -> None:
        """What passes read of the model drawn, whole or in chunks."""
        self._corners = None
        self._model = model
        # what each capture source prepares once for the mesh drawn (its programs), by its key
        self.prepared: dict[tuple, object] = {}
        self.part_count = len(model.part_names)
        self.triangles = model.triangle_count
        self.instanced = model.instances is not None
        self.bounds = model.bounds  # (2, 3): its used vertices' corners

    @property
    def unplaced(self) -> bool:
        """Whether each draw is one instance of the identity in part 0: a flattened model's
        (``draw_groups``)."""
        return not self.instanced

    @property
    def vertex_defines(self) -> dict:
        """The defines of a program whose vertex stage draws these buffers (instance.glsl's
        UNPLACED where ``unplaced``: no instance attribute is read)."""
        return {"UNPLACED": self.unplaced}

    @property
    def surface_defines(self) -> dict:
        """The defines of a program that packs or reads surfaces of this mesh (kbuffer.glsl's
        WIDE_PARTS where its parts pass ``NARROW_PARTS``)."""
        return {"WIDE_PARTS": self.part_count >= NARROW_PARTS}

    @property
    def placement_defines(self) -> dict:
        """The defines of a program that reads these faces by their ID (instance.glsl's
        PLACEMENTS, and ONE_PLACEMENT where the faces table is the identity alone)."""
        return {"PLACEMENTS": PLACEMENTS_BINDING, "ONE_PLACEMENT": self.one_placement}

    def bind_faces(self, vertices: int, indices: int) -> None:
        """Bind the vertex and index buffers to storage bindings ``vertices`` and ``indices``,
        and the faces table to ``PLACEMENTS_BINDING`` (instance.glsl with PLACEMENTS)."""
        self.vbo.bind_to_storage_buffer(vertices)
        self.ibo.bind_to_storage_buffer(indices)
        self._placements.bind_to_storage_buffer(PLACEMENTS_BINDING)

    def vao(self, program) -> _Draws:
        """The draws of these buffers for ``program`` (a vertex array binds one program)."""
        draws = self._vaos.get(program.glo)
        if draws is None:
            # attributes a program does not read (pipeline attribute passes need no part, ID
            # passes no normal) are skipped over
            vertices = _layout(self.vbo, _VERTEX_FIELDS, program, "")
            arrays = []
            for records, count, first, indices, wait, face in self.groups:
                layout = [vertices, *_instances_read(records, program)]
                vao = self.ctx.vertex_array(program, layout, index_buffer=self.ibo, index_element_size=4)
                arrays.append((vao, count, first, indices, wait, face))
            draws = self._vaos[program.glo] = _Draws(arrays, program)
        return draws

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
        held = [draw[0] for draws in self._vaos.values() for draw in draws.arrays]
        held += [records for records, *_ in self.groups]
        for obj in (*held, self.vbo, self.ibo, self._placements, self._corners):
            if obj is not None:
                obj.release()


class FaceSubset(GpuMesh):
    """Some faces of a flattened model's ``GpuMesh`` (``mesh``), from an index buffer of their
    own (``ibo``, ``faces`` faces of ``mesh``'s vertices, released with the subset), drawn as
    the whole mesh draws them (in pieces on a software rasteriser): a pass that draws only the
    faces that can reach some pixels (the contour lines' levels, ``vector.contour_gpu``). Face
    ID ``i`` of its passes is its ``i``-th face. Passes choose their capture as for the whole
    mesh (``triangles``); its bounds are the whole mesh's, and so its depth tolerance."""

    def __init__(self, mesh: GpuMesh, ibo, faces: int, pieces: bool = False) -> None:
        self.ctx = mesh.ctx
        self.vbo, self.ibo = mesh.vbo, ibo
        records = instance_records(np.eye(4)[None], np.zeros(1), np.zeros(1))
        limit = PIECE_FACES if pieces else None
        self.groups = [
            (self.ctx.buffer(piece), len(piece), int(at), int(count), wait, int(piece["face"][0]))
            for piece, at, count, wait in _pieces(records, faces, limit)
        ]
        self.one_placement = True
        self._placements = mesh._placements
        self._vaos = {}
        self._of_model(mesh._model)

    def release(self) -> None:
        held = [draw[0] for draws in self._vaos.values() for draw in draws.arrays]
        for obj in (*held, *(records for records, *_ in self.groups), self.ibo):
            obj.release()


def _identity(placement) -> bool:
    """Whether a ``PLACEMENT`` places faces from 0 where they are, unturned, in part 0."""
    rows = np.stack([placement[k] for k in ("x", "y", "z")])
    turns = np.stack([placement[k][:3] for k in ("nx", "ny", "nz")])
    eye = np.eye(4)[:3]
    return bool(
        (rows == eye).all()
        and (turns == eye[:, :3]).all()
        and placement["part"] == 0
        and placement["face"] == 0
        and placement["base"] == 0
    )


class ChunkedMesh(GpuMesh):
    """A model drawn ``chunk_faces`` faces at a time, for a GPU whose free memory holds the
    frame's buffers but not the whole mesh beside them (``render.budget``): the prepared arrays
    (``draw_groups``, ``joined``) stay on the host cut into chunks of consecutive faces, each
    with the vertices its faces use and a draw for each piece of a group it holds, at the
    group's instances with their first faces moved on by the piece's (as ``_pieces`` moves
    them); ``vao(program).render()`` uploads a chunk, draws it, waits for it and releases it
    before the next, so the GPU holds one chunk at a time. Every face keeps its ID, corners and
    vertex values, so a pass whose result does not hang on the order of faces of different
    chunks (the A-buffer's lists, sorted by depth and then face) draws what one upload draws.
    It has no faces table (``bind_faces``): the passes that read faces by their ID after the
    geometry pass (the slim A-buffer's resolve, the compute rasteriser) are not used on it.
    ``on_chunk(done, total)``, where set, is told each chunk drawn."""

    def __init__(
        self, ctx, model: Model, crease_angle: float | None, chunk_faces: int, pieces: bool = False
    ) -> None:
        self.ctx = ctx
        self.chunk_faces = int(chunk_faces)
        groups = draw_groups(model, crease_angle)
        vertices, indices, index_base, index_count = joined(groups)
        records = [records for _, _, records in groups]
        del groups
        limit = PIECE_FACES if pieces else None
        self.chunks = _chunks(
            vertices, indices, index_base // 3, index_count // 3, records, self.chunk_faces, limit
        )
        del vertices, indices, records
        self.on_chunk = None
        self._vaos: dict[int, _ChunkDraws] = {}
        self._of_model(model)

    def bind_faces(self, vertices: int, indices: int) -> None:
        raise TypeError("a mesh drawn in chunks has no faces table on the GPU")

    def vao(self, program) -> _ChunkDraws:
        """The chunks' draws for ``program``."""
        draws = self._vaos.get(program.glo)
        if draws is None:
            draws = self._vaos[program.glo] = _ChunkDraws(self, program)
        return draws

    def release(self) -> None:
        if self._corners is not None:
            self._corners.release()
        self.chunks = []


def _chunks(
    vertices: np.ndarray,
    indices: np.ndarray,
    group_face: np.ndarray,
    group_faces: np.ndarray,
    records: list[np.ndarray],
    chunk_faces: int,
    limit: int | None,
) -> list[tuple[np.ndarray, np.ndarray, list]]:
    """The chunks of ``ChunkedMesh``: (vertices ``VERTEX`` the chunk's faces use, indices
    uint32 into them, draws (instance records, first index, index count, whether another piece
    of its group follows)) a run of at most ``chunk_faces`` of the joined faces (``joined``'s
    ``vertices`` and ``indices``), the groups' first faces ``group_face`` and face counts
    ``group_faces`` (G,) and instance ``records`` (G arrays of ``INSTANCE``); each draw of at
    most ``limit`` faces (None: any)."""
    group_end = group_face + group_faces
    total = len(indices) // 3
    out = []
    for start in range(0, total, chunk_faces):
        end = min(start + chunk_faces, total)
        used, local = _used(indices[3 * start : 3 * end], len(vertices))
        draws = []
        first = int(np.searchsorted(group_end, start, side="right"))
        last = int(np.searchsorted(group_face, end, side="left"))
        for g in range(first, last):
            lo, hi = max(start, int(group_face[g])), min(end, int(group_end[g]))
            if hi <= lo:
                continue
            moved = records[g].copy()
            moved["face"] += lo - int(group_face[g])
            for piece, at, count, wait in _pieces(moved, hi - lo, limit):
                draws.append((piece, 3 * (lo - start) + at, count, wait))
        out.append((vertices[used], local, draws))
    return out


def _used(corners: np.ndarray, vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """(the vertices ``corners`` (N,) uint32 use, ascending; ``corners`` as indices into them,
    uint32) of ``vertices`` vertices: by flags over every vertex where the corners are not far
    fewer, else by sorting the corners."""
    if vertices > 4 * len(corners):
        used, local = np.unique(corners, return_inverse=True)
        return used, local.astype(np.uint32)
    seen = np.zeros(vertices, bool)
    seen[corners] = True
    return np.flatnonzero(seen), (np.cumsum(seen, dtype=np.uint32) - np.uint32(1))[corners]


def _pieces(records: np.ndarray, faces: int, limit: int | None) -> list[tuple[np.ndarray, int, int, bool]]:
    """The draws of a group of ``faces`` faces at instances ``records`` (``INSTANCE``): (the
    instance records, first index from the group's, index count, whether another piece
    follows) a draw of at most ``limit`` faces (None: one draw), each draw's records with first
    faces moved on by the draw's first face."""
    if limit is None or faces <= limit:
        return [(records, 0, 3 * faces, False)]
    out = []
    for start in range(0, faces, limit):
        moved = records.copy()
        moved["face"] += start
        out.append((moved, 3 * start, 3 * min(limit, faces - start), start + limit < faces))
    return out


def identity_instance(ctx):
    """A buffer of one instance at the identity, part 0, first face 0: what a vertex array of a
    geometry program (``instance_layout``) that draws corners of its own is placed by."""
    return ctx.buffer(instance_records(np.eye(4)[None], np.zeros(1), np.zeros(1)))


def instance_layout(buffer, program) -> tuple:
    """A vertex array's entry for the instance records ``buffer`` (``INSTANCE``), one a draw's
    instance, for a geometry ``program``."""
    return _layout(buffer, _INSTANCE_FIELDS, program, "/i")


def _instances_read(buffer, program) -> list:
    """``instance_layout``'s entry in a list, or none where ``program`` reads no instance
    attribute (instance.glsl's UNPLACED)."""
    entry = instance_layout(buffer, program)
    return [entry] if len(entry) > 2 else []


def _layout(buffer, fields, program, suffix: str) -> tuple:
    """A vertex array's entry for ``buffer`` of ``fields`` (format, name), those ``program``
    does not read skipped over."""
    used = [(f, name) if name in program else (f"{4 * int(f[0])}x", None) for f, name in fields]
    return (buffer, " ".join(f for f, _ in used) + suffix, *(name for _, name in used if name))


def _first_face(program):
    """The uniform of ``program``'s first face, where the draws set it (instance.glsl's
    UNPLACED), else None."""
    return program["u_first_face"] if "u_first_face" in program else None


class _Draws:
    """A mesh's draw calls for one program: each draw's vertex array, (vertex array,
    instances, first index, indices, wait, first face), its indices at its instances; after a
    draw with ``wait`` (a piece of a group drawn in pieces) the draw before it is waited for
    (``OneAhead``), so that one piece is set up while the last is rasterised."""

    def __init__(self, arrays: list, program) -> None:
        self.arrays = arrays
        self.first_face = _first_face(program)

    def render(self) -> None:
        ahead = None
        for vao, count, first, indices, wait, face in self.arrays:
            if indices:
                if self.first_face is not None:
                    self.first_face.value = face
                vao.render(vertices=indices, first=first, instances=count)
                if wait:
                    ahead = ahead or OneAhead(vao.ctx)
                    ahead.drawn()
        if ahead is not None:
            ahead.close()


class _ChunkDraws:
    """A ``ChunkedMesh``'s draws for one ``program``: each chunk uploaded, drawn, finished and
    released before the next is uploaded."""

    def __init__(self, mesh: ChunkedMesh, program) -> None:
        self.mesh, self.program = mesh, program

    def render(self) -> None:
        mesh, program = self.mesh, self.program
        ctx, first_face = mesh.ctx, _first_face(program)
        for k, (vertices, indices, draws) in enumerate(mesh.chunks):
            vbo, ibo = ctx.buffer(vertices), ctx.buffer(indices)
            held = [vbo, ibo]
            layout = _layout(vbo, _VERTEX_FIELDS, program, "")
            ahead = OneAhead(ctx)
            for records, first, count, wait in draws:
                placed = ctx.buffer(records)
                vao = ctx.vertex_array(
                    program,
                    [layout, *_instances_read(placed, program)],
                    index_buffer=ibo,
                    index_element_size=4,
                )
                held += [placed, vao]
                if first_face is not None:
                    first_face.value = int(records["face"][0])
                vao.render(vertices=count, first=first, instances=len(records))
                if wait:
                    ahead.drawn()
            ahead.close()
            # the driver frees the chunk's buffers only once its draws are done
            ctx.finish()
            for obj in reversed(held):
                obj.release()
            if mesh.on_chunk is not None:
                mesh.on_chunk(k + 1, len(mesh.chunks))
