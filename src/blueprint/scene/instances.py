"""A scene kept as its unique meshes and the instances that place them.

A GLB of N copies of a mesh holds the mesh once and N transforms; flattened, it holds N
copies of every vertex and face, and everything after the loader (welding, normals, upload)
pays for the copies. ``Instances`` keeps the scene as the file has it: a ``Model`` that carries
one (``Model.instances``) answers its bounds, triangle count, digest and parts from it, and
makes its flattened arrays only when a reader asks for them (``flatten``), in the order the
flattened scene has: instance after instance, each one's faces in its mesh's order, so face
``i`` is triangle ID ``i`` whether a pass draws instances or the flattened triangles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.columns import face_cross, ranges, row_norm
from blueprint.sorting import row_numbers, stable_argsort, unique_first

__all__ = ["Instances", "flatten", "instance_boxes", "worth_instancing"]

# Drawn triangles at least this many times the unique ones: the scene is kept as instances.
INSTANCED_FACTOR = 2.0
# Rows (vertices or faces) transformed by one matrix product.
_ROWS = 1 << 16


@dataclass(frozen=True, eq=False)
class Instances:
    """Unique meshes and the instances that place them.

    Parameters
    ----------
    positions : (V, 3) float64
        Every unique mesh's vertices in its own coordinates, mesh after mesh.
    faces : (F, 3) int32
        Every unique mesh's faces, mesh after mesh, as vertex indices within its mesh.
    vertex_start, face_start : (M + 1,) int64
        Where mesh ``m``'s vertices and faces start in ``positions`` and ``faces`` (the last
        entry: their count).
    mesh : (N,) int32
        The mesh of each instance.
    transform : (N, 4, 4) float64
        Each instance's affine transform from its mesh to the scene.
    part : (N,) int32
        The part of each instance.
    """

    positions: np.ndarray
    faces: np.ndarray
    vertex_start: np.ndarray
    face_start: np.ndarray
    mesh: np.ndarray
    transform: np.ndarray
    part: np.ndarray

    def __post_init__(self) -> None:
        meshes = len(self.vertex_start) - 1
        if self.face_start.shape != (meshes + 1,) or self.vertex_start[-1] != len(self.positions):
            raise ValueError("vertex_start and face_start must hold M + 1 offsets of the meshes")
        if self.face_start[-1] != len(self.faces):
            raise ValueError("face_start must end at the face count")
        n = len(self.mesh)
        if self.transform.shape != (n, 4, 4) or self.part.shape != (n,):
            raise ValueError("each instance needs a mesh, a (4, 4) transform and a part")
        if n and (self.mesh.min() < 0 or self.mesh.max() >= meshes):
            raise ValueError("instances refer to meshes that do not exist")
        if len(self.faces):
            local_limit = np.repeat(np.diff(self.vertex_start), np.diff(self.face_start))
            if self.faces.min() < 0 or (self.faces.max(axis=1) >= local_limit).any():
                raise ValueError("faces refer to vertices outside their mesh")

    @property
    def mesh_count(self) -> int:
        return len(self.vertex_start) - 1

    def mesh_faces(self) -> np.ndarray:
        """(M,) int64: faces of each unique mesh."""
        return np.diff(self.face_start)

    def mesh_vertices(self) -> np.ndarray:
        """(M,) int64: vertices of each unique mesh."""
        return np.diff(self.vertex_start)

    def instance_faces(self) -> np.ndarray:
        """(N,) int64: faces each instance draws."""
        return self.mesh_faces()[self.mesh]

    def first_face(self) -> np.ndarray:
        """(N,) int64: each instance's first face in the flattened scene."""
        counts = self.instance_faces()
        return np.cumsum(counts) - counts

    @property
    def triangle_count(self) -> int:
        """Triangles drawn: every instance's mesh's."""
        return int(self.instance_faces().sum())

    def mesh_arrays(self, m: int) -> tuple[np.ndarray, np.ndarray]:
        """Mesh ``m``'s (V, 3) float64 vertices and (F, 3) int32 faces, views."""
        vs, fs = self.vertex_start, self.face_start
        return self.positions[vs[m] : vs[m + 1]], self.faces[fs[m] : fs[m + 1]]

    def by_mesh(self, keep: np.ndarray | None = None) -> list[tuple[int, np.ndarray]]:
        """(mesh, its instances in order) for each mesh placed, among the instances ``keep``
        (N,) bool flags (all where None)."""
        chosen = np.arange(len(self.mesh)) if keep is None else np.flatnonzero(keep)
        order = chosen[stable_argsort(self.mesh[chosen])]
        meshes = self.mesh[order]
        starts = np.flatnonzero(np.r_[True, meshes[1:] != meshes[:-1]]) if len(order) else np.zeros(0, int)
        ends = np.r_[starts[1:], len(order)]
        return [(int(meshes[s]), order[s:e]) for s, e in zip(starts, ends, strict=True)]

    def subset(self, keep: np.ndarray, part_number: np.ndarray) -> Instances:
        """The instances ``keep`` (N,) bool flags, their parts renumbered by ``part_number``
        (old part to new), with the meshes they use alone."""
        mesh = self.mesh[keep]
        used = np.zeros(self.mesh_count, bool)
        used[mesh] = True
        renumber = np.cumsum(used) - 1
        vcounts, fcounts = self.mesh_vertices()[used], self.mesh_faces()[used]
        vrows = ranges(self.vertex_start[:-1][used], vcounts)
        frows = ranges(self.face_start[:-1][used], fcounts)
        return Instances(
            np.ascontiguousarray(self.positions[vrows]),
            np.ascontiguousarray(self.faces[frows]),
            np.r_[0, np.cumsum(vcounts)].astype(np.int64),
            np.r_[0, np.cumsum(fcounts)].astype(np.int64),
            renumber[mesh].astype(np.int32),
            np.ascontiguousarray(self.transform[keep]),
            part_number[self.part[keep]].astype(np.int32),
        )


def worth_instancing(drawn: int, unique: int) -> bool:
    """Whether a scene drawing ``drawn`` triangles of ``unique`` is kept as instances."""
    return drawn >= INSTANCED_FACTOR * max(unique, 1)


def _moved(vertices: np.ndarray, transforms: np.ndarray) -> np.ndarray:
    """(B, V, 3) float64: ``vertices`` (V, 3) placed by each of ``transforms`` (B, 4, 4), the
    loader's product (``loader._place``), so a flattened scene has the loader's values."""
    return np.matmul(vertices[None], transforms[:, :3, :3].transpose(0, 2, 1)) + transforms[:, None, :3, 3]


def _blocks(members: np.ndarray, rows: int):
    """``members`` in blocks of instances whose ``rows`` each come to about ``_ROWS``."""
    step = max(1, _ROWS // max(rows, 1))
    for first in range(0, len(members), step):
        yield members[first : first + step]


def flatten(inst: Instances) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The flattened scene: (V', 3) float32 positions, (F', 3) int32 faces and (F',) int32
    face parts, instance after instance; every vertex of a mesh is placed, as the loader
    places them, a block of one mesh's instances at a time."""
    vcounts = inst.mesh_vertices()[inst.mesh]
    fcounts = inst.instance_faces()
    vstart = np.cumsum(vcounts) - vcounts
    fstart = np.cumsum(fcounts) - fcounts
    positions = np.empty((int(vcounts.sum()), 3), np.float32)
    faces = np.empty((int(fcounts.sum()), 3), np.int32)
    with np.errstate(all="ignore"):
        for m, members in inst.by_mesh():
            vertices, mesh_faces = inst.mesh_arrays(m)
            for block in _blocks(members, max(len(vertices), len(mesh_faces))):
                rows = vstart[block][:, None] + np.arange(len(vertices))
                positions[rows] = _moved(vertices, inst.transform[block])
                face_rows = fstart[block][:, None] + np.arange(len(mesh_faces))
                faces[face_rows] = mesh_faces[None] + vstart[block][:, None, None].astype(np.int32)
    face_part = np.repeat(inst.part, fcounts).astype(np.int32)
    return positions, faces, face_part


def placed_blocks(inst: Instances, keep: np.ndarray | None = None):
    """The used vertices of every instance (of the instances ``keep``, (N,) bool flags, where
    given) placed as ``flatten`` places them (float32), in blocks of (B, V, 3) of one mesh's
    instances."""
    for m, members in inst.by_mesh(keep):
        points = _used_vertices(inst, m)
        for block in _blocks(members, len(points)):
            with np.errstate(all="ignore"):
                yield _moved(points, inst.transform[block]).astype(np.float32)


def _used_vertices(inst: Instances, mesh: int) -> np.ndarray:
    """The vertices of ``mesh`` that a face uses, in order: those the flattened model keeps."""
    vertices, mesh_faces = inst.mesh_arrays(mesh)
    used = np.zeros(len(vertices), bool)
    used[mesh_faces.reshape(-1)] = True
    return vertices if used.all() else vertices[used]


def instance_boxes(inst: Instances) -> np.ndarray:
    """(N, 2, 3) float64: each instance's lowest and highest corner, of its mesh's used
    vertices placed as ``flatten`` places them (float32 values): exactly the bounds of its
    flattened vertices, without flattening the scene."""
    boxes = np.empty((len(inst.mesh), 2, 3))
    # instances of one mesh turned alike (a pattern of copies) share their turned vertices'
    # bounds: adding the shift and rounding to float32 keep the order, so the bounds are the
    # turned bounds shifted and rounded, the same values as every vertex placed
    key = np.concatenate([inst.mesh[:, None], inst.transform[:, :3, :3].reshape(-1, 9)], axis=1)
    _, first, alike = np.unique(key, axis=0, return_index=True, return_inverse=True)
    turned = np.empty((len(first), 2, 3))
    unturned = np.zeros((len(first), 4, 4))
    unturned[:, :3, :3] = inst.transform[first, :3, :3]
    leading = np.zeros(len(inst.mesh), bool)
    leading[first] = True
    with np.errstate(all="ignore"):
        for m, members in inst.by_mesh(leading):
            points = _used_vertices(inst, m)
            for block in _blocks(alike[members], len(points)):
                placed = _moved(points, unturned[block])
                turned[block, 0] = placed.min(axis=1)
                turned[block, 1] = placed.max(axis=1)
        boxes[:] = (turned[alike.ravel()] + inst.transform[:, None, :3, 3]).astype(np.float32)
    return boxes


def instance_corners(inst: Instances, members: np.ndarray) -> np.ndarray:
    """(K, 3, 3) float64: the placed corners (float32 values) of every face of the instances
    ``members``, mesh by mesh: a few instances' triangles, not the scene's."""
    keep = np.zeros(len(inst.mesh), bool)
    keep[members] = True
    out = [np.zeros((0, 3, 3))]
    for m, chosen in inst.by_mesh(keep):
        vertices, mesh_faces = inst.mesh_arrays(m)
        placed = _moved(vertices, inst.transform[chosen]).astype(np.float32)
        out.append(placed[:, mesh_faces].reshape(-1, 3, 3).astype(np.float64))
    return np.concatenate(out)


def mesh_degenerate(inst: Instances) -> np.ndarray:
    """(F,) bool: the unique meshes' faces with a repeated vertex or, in their mesh's own
    coordinates, no area (relative to the mesh's size, as ``Model.degenerate_faces``)."""
    out = np.zeros(len(inst.faces), bool)
    for m in range(inst.mesh_count):
        vertices, mesh_faces = inst.mesh_arrays(m)
        if not len(mesh_faces):
            continue
        cross = face_cross(vertices[mesh_faces])
        area2 = np.einsum("ij,ij->i", cross, cross)
        scale = float(np.ptp(vertices, axis=0).max())
        f = mesh_faces
        repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
        out[inst.face_start[m] : inst.face_start[m + 1]] = repeated | (area2 <= (scale * scale * 1e-12) ** 2)
    return out


def most_coincident(inst: Instances) -> int:
    """The most copies of one triangle among the drawn ones: copies within a mesh (by centroid
    and area, as the loader finds them) times the instances of that mesh placed by one
    transform."""
    key = np.concatenate([inst.mesh[:, None].astype(np.float64), inst.transform.reshape(-1, 16)], axis=1)
    # the (finite) rows alike as floats alike as bits, -0.0 made 0.0: grouped by the pool's sorts
    _, which, group = unique_first(row_numbers((key + 0.0).view(np.int64)))
    placed_alike = np.bincount(group)
    within = np.ones(inst.mesh_count, np.int64)
    for m in np.unique(inst.mesh):
        vertices, mesh_faces = inst.mesh_arrays(int(m))
        tri = vertices[mesh_faces]
        cross = face_cross(tri)
        keys = (tri[:, 0] + tri[:, 1] + tri[:, 2]) @ np.array([1.0, np.pi, np.e]) + row_norm(cross) * np.sqrt(
            2
        )
        within[m] = np.unique(keys, return_counts=True)[1].max()
    return int((within[inst.mesh[which]] * placed_alike).max())
