"""Models the project makes itself: the shipped example and shapes for tests and benchmarks.

Everything here is generated from code, so it carries the project's own licence.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import numpy as np

from blueprint.scene.model import Model


def box(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """An axis-aligned box as 8 vertices and 12 outward-wound triangles."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    vertices = lo + corners * (hi - lo)
    faces = np.array(
        [
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],  # x = lo, x = hi
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],  # y = lo, y = hi
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],  # z = lo, z = hi
        ]
    )
    return vertices, faces


def prism(radii, height: float, segments: int, axis: int = 2, center=(0, 0, 0), phase=0.0):
    """A closed prism over a star-shaped outline (radius per outline vertex, cycled over
    ``segments`` vertices), extruded ``height`` along ``axis`` and centred at ``center``."""
    radii = np.resize(np.asarray(radii, float), segments)
    angles = phase + np.arange(segments) * 2 * math.pi / segments
    ring = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
    n = segments
    bottom = np.column_stack([ring, np.full(n, -height / 2)])
    top = np.column_stack([ring, np.full(n, height / 2)])
    vertices = np.vstack([bottom, top, [[0, 0, -height / 2], [0, 0, height / 2]]])
    i = np.arange(n)
    j = (i + 1) % n
    sides = np.concatenate([np.column_stack([i, j, j + n]), np.column_stack([i, j + n, i + n])])
    caps = np.concatenate(
        [
            np.column_stack([np.full(n, 2 * n), j, i]),
            np.column_stack([np.full(n, 2 * n + 1), i + n, j + n]),
        ]
    )
    return _turn(vertices, axis) + np.asarray(center, float), np.concatenate([sides, caps])


def tube(r_in: float, r_out: float, height: float, segments: int, axis: int = 2, center=(0, 0, 0)):
    """A closed hollow cylinder (ring) of ``segments`` sides."""
    a = np.arange(segments) * 2 * math.pi / segments
    n = segments
    outer = np.column_stack([np.cos(a), np.sin(a)])
    rings = [
        np.column_stack([outer * r, np.full(n, z)])
        for r, z in (
            (r_out, -height / 2),
            (r_out, height / 2),
            (r_in, -height / 2),
            (r_in, height / 2),
        )
    ]
    vertices = np.vstack(rings)
    i = np.arange(n)
    j = (i + 1) % n
    ob, ot, ib, it = 0, n, 2 * n, 3 * n

    def quad(a0, a1, b0, b1):
        return np.concatenate([np.column_stack([a0, a1, b1]), np.column_stack([a0, b1, b0])])

    faces = np.concatenate(
        [
            quad(ob + i, ob + j, ot + i, ot + j),  # outer wall
            quad(it + i, it + j, ib + i, ib + j),  # inner wall, facing the axis
            quad(ot + i, ot + j, it + i, it + j),  # top
            quad(ib + i, ib + j, ob + i, ob + j),  # bottom
        ]
    )
    return _turn(vertices, axis) + np.asarray(center, float), faces


def _turn(vertices: np.ndarray, axis: int) -> np.ndarray:
    """Cyclically permute coordinates so local z becomes ``axis`` (a rotation, not a mirror)."""
    return vertices[:, [(2, 0, 1), (1, 2, 0), (0, 1, 2)][axis]]


def assemble(parts: dict[str, tuple[np.ndarray, np.ndarray]], up: str = "y") -> Model:
    """One Model from named (vertices, faces) parts, in the dict's order."""
    positions, faces, face_part = [], [], []
    offset = 0
    for index, (vertices, tris) in enumerate(parts.values()):
        positions.append(vertices)
        faces.append(np.asarray(tris) + offset)
        face_part.append(np.full(len(tris), index))
        offset += len(vertices)
    return Model.from_arrays(
        np.concatenate(positions),
        np.concatenate(faces),
        np.concatenate(face_part),
        tuple(parts),
        up=up,
        source="generated",
    )


def gearbox() -> Model:
    """A small gearbox: base plate, two bearing blocks with bearings, a shaft carrying a gear,
    four bolts, and a thin cover over it all: most of it is only visible as hidden lines."""
    teeth = 20
    parts = {
        "base": box((-70, 0, -35), (70, 8, 35)),
        "block_left": box((-55, 8, -16), (-35, 34, 16)),
        "block_right": box((35, 8, -16), (55, 34, 16)),
        "bearing_left": tube(7, 12, 22, 48, axis=0, center=(-45, 40, 0)),
        "bearing_right": tube(7, 12, 22, 48, axis=0, center=(45, 40, 0)),
        "shaft": prism([6.0], 130, 48, axis=0, center=(0, 40, 0)),
        "gear": prism(
            [22.0, 22.0, 26.0, 26.0],
            14,
            teeth * 4,
            axis=0,
            center=(0, 40, 0),
            phase=math.pi / (teeth * 4),
        ),
        "hub": tube(6, 10, 26, 48, axis=0, center=(0, 40, 0)),
    }
    for k, (x, z) in enumerate([(-62, -27), (62, -27), (-62, 27), (62, 27)]):
        parts[f"bolt_{k + 1}"] = prism([3.0], 14, 24, axis=1, center=(x, 9, z))
    wall = 1.5
    cover = [
        box((-66, 8, -31), (-66 + wall, 72, 31)),
        box((66 - wall, 8, -31), (66, 72, 31)),
        box((-66 + wall, 8, -31), (66 - wall, 72, -31 + wall)),
        box((-66 + wall, 8, 31 - wall), (66 - wall, 72, 31)),
        box((-66, 72, -31), (66, 72 + wall, 31)),
    ]
    offset, vertices, faces = 0, [], []
    for v, f in cover:
        vertices.append(v)
        faces.append(f + offset)
        offset += len(v)
    parts["cover"] = (np.concatenate(vertices), np.concatenate(faces))
    return assemble(parts)


def example_path() -> Path:
    """The shipped example model (a GLB written by ``write_glb(gearbox(), ...)``)."""
    return Path(str(resources.files("blueprint").joinpath("data/gearbox.glb")))


def write_glb(model: Model, path: str | Path) -> None:
    """Write a model as GLB, one node per part, through trimesh."""
    import trimesh

    scene = trimesh.Scene()
    for index, name in enumerate(model.part_names):
        mask = model.face_part == index
        used = np.unique(model.faces[mask])
        remap = np.full(len(model.positions), -1)
        remap[used] = np.arange(len(used))
        mesh = trimesh.Trimesh(model.positions[used], remap[model.faces[mask]], process=False)
        scene.add_geometry(mesh, node_name=name, geom_name=name)
    Path(path).write_bytes(scene.export(file_type="glb"))
