"""Scenes of instanced meshes for the tests of models kept as instances, and their flattened
twins (the same triangles as plain arrays, which every path drew before instances were kept).

``exact_scene``: every transform a rotation by a multiple of 90 degrees, a scale by 2, a
mirror, and whole translations, every coordinate a multiple of 1/4: the products placing a
vertex are exact in float32 and float64 alike, so a pass drawing instances and one drawing
the flattened triangles rasterise the same corners. ``turned_scene`` adds instances turned by
30 degrees, whose placed corners round differently on the GPU and the CPU.
"""

from __future__ import annotations

import numpy as np
import trimesh

from blueprint.scene.loader import model_from_object
from blueprint.scene.model import Model


def l_prism() -> trimesh.Trimesh:
    """An L-shaped prism (no symmetry that maps it onto itself), closed, outward-wound."""
    outline = np.array([[0, 0], [2, 0], [2, 0.5], [0.5, 0.5], [0.5, 1.5], [0, 1.5]], float)
    bottom = np.c_[outline, np.zeros(6)]
    top = np.c_[outline, np.full(6, 0.75)]
    vertices = np.r_[bottom, top]
    caps = [[0, 2, 1], [0, 3, 2], [0, 5, 3], [3, 5, 4]]
    faces = caps + [[a + 6, c + 6, b + 6] for a, b, c in caps]
    for k in range(6):
        j = (k + 1) % 6
        faces += [[k, j, j + 6], [k, j + 6, k + 6]]
    mesh = trimesh.Trimesh(vertices, np.array(faces), process=False)
    mesh.fix_normals()
    return mesh


def wedge() -> trimesh.Trimesh:
    """A wedge (a triangular prism with unequal sides)."""
    base = np.array([[0, 0], [1.5, 0], [0, 0.75]], float)
    vertices = np.r_[np.c_[base, np.zeros(3)], np.c_[base, np.full(3, 1.25)]]
    faces = [[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [2, 0, 3], [2, 3, 5]]
    mesh = trimesh.Trimesh(vertices, np.array(faces), process=False)
    mesh.fix_normals()
    return mesh


def placed(linear=None, translation=(0, 0, 0)) -> np.ndarray:
    """(4, 4): the affine transform of ``linear`` (3, 3; identity where None) and
    ``translation``."""
    out = np.eye(4)
    if linear is not None:
        out[:3, :3] = linear
    out[:3, 3] = translation
    return out


def turn(axis: int, degrees: float) -> np.ndarray:
    """(3, 3): a rotation about ``axis`` (0, 1, 2) by ``degrees``, exact at multiples of 90."""
    quarter = degrees / 90
    if quarter == int(quarter):
        c, s = [1, 0, -1, 0][int(quarter) % 4], [0, 1, 0, -1][int(quarter) % 4]
    else:
        c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out = np.eye(3)
    out[i, i], out[i, j], out[j, i], out[j, j] = c, -s, s, c
    return out


MIRROR_X = np.diag([-1.0, 1.0, 1.0])
MIRROR_Z = np.diag([1.0, 1.0, -1.0])

# (mesh, transform) of exact_scene's instances, in the scene's order
EXACT = [
    ("l", placed()),
    ("wedge", placed(None, (0, -3, 0))),
    ("l", placed(turn(1, 90), (4, 0, 0))),
    ("l", placed(2 * np.eye(3), (0, 0, -8))),
    ("wedge", placed(turn(2, 90), (2, -3, 1))),
    ("l", placed(MIRROR_X, (-1, 0, 0))),
    ("l", placed(turn(0, 90), (0, 4, 0))),
    ("wedge", placed(MIRROR_Z, (-2, -3, 0))),
]
TURNED = [("l", placed(turn(1, 30), (1, 2, 3))), ("wedge", placed(turn(0, -30) * 1.5, (-3, 2, -2)))]


def trimesh_scene(instances, meshes: dict | None = None) -> trimesh.Scene:
    """A trimesh scene of ``meshes`` (name to mesh; default ``l_prism`` as "l" and ``wedge``)
    at ``instances`` ((mesh name, transform) each), a node each, the meshes held once."""
    scene = trimesh.Scene()
    meshes = meshes or {"l": l_prism(), "wedge": wedge()}
    for name, mesh in meshes.items():
        scene.add_geometry(mesh, geom_name=name, node_name=f"{name}_mesh", transform=None)
    scene.graph.clear()
    for k, (name, transform) in enumerate(instances):
        scene.graph.update(
            frame_to=f"{name}{k}", frame_from=scene.graph.base_frame, matrix=transform, geometry=name
        )
    return scene


def exact_scene() -> Model:
    """The scene of ``EXACT``, kept as instances."""
    return model_from_object(trimesh_scene(EXACT), name="exact scene")


# the order of the mixed scene's copies: meshes used three times and twice between meshes used once
MIXED_ORDER = ("l", "w1", "l", "w2", "wedge", "l", "wedge")


def mixed_scene(order=MIXED_ORDER) -> Model:
    """Meshes used three times and twice (turned, mirrored, scaled) and meshes used once, in
    ``order`` (names of an L prism ``l``, a wedge ``wedge``, and wedges ``w1``, ``w2`` used
    once): a draw group per shared mesh and runs of flattened blocks."""
    meshes = {"l": l_prism(), "wedge": wedge(), "w1": wedge(), "w2": wedge()}
    linear = [None, turn(1, 90), MIRROR_X, 2 * np.eye(3), turn(0, 90), MIRROR_X @ turn(2, 90), None]
    instances = [
        (name, placed(m, (3 * k, 0, 0))) for k, (name, m) in enumerate(zip(order, linear, strict=True))
    ]
    return model_from_object(trimesh_scene(instances, meshes), name="mixed")


def turned_scene() -> Model:
    """The scene of ``EXACT`` and ``TURNED``, kept as instances."""
    return model_from_object(trimesh_scene(EXACT + TURNED), name="turned scene")


def flattened(model: Model) -> Model:
    """The model's flattened twin: its triangles as plain arrays, parts and axis kept."""
    return Model(model.positions, model.faces, model.face_part, model.part_names, model.up, model.source)


def copies(n: int, mesh: trimesh.Trimesh | None = None) -> trimesh.Scene:
    """``n`` copies of ``mesh`` (default ``l_prism``) on a grid, a node each: what an assembly
    of repeated parts is."""
    side = int(np.ceil(np.sqrt(n)))
    grid = [("m", placed(None, (3 * (k % side), 0, 3 * (k // side)))) for k in range(n)]
    return trimesh_scene(grid, {"m": l_prism() if mesh is None else mesh})


# (mesh, transform) of smooth_scene's instances: smooth meshes among the prisms, turned by
# quarter turns, mirrored and scaled by 2, cutting through each other in places
SMOOTH = [
    ("ball", placed()),
    ("post", placed(None, (0.75, 0, 0))),
    ("ball", placed(turn(1, 90), (3, 0, 0))),
    ("post", placed(MIRROR_X @ turn(0, 90), (3, 0.5, 0.25))),
    ("l", placed(None, (-2, -1, 0))),
    ("ball", placed(2 * np.eye(3), (0, 4, 0))),
    ("wedge", placed(MIRROR_Z, (-2, 2, 0.5))),
]


def smooth_scene() -> Model:
    """The scene of ``SMOOTH`` (an icosphere, a cylinder, ``l_prism`` and ``wedge``), kept as
    instances: lines of every kind, smooth contours among them."""
    meshes = {
        "ball": trimesh.creation.icosphere(3),
        "post": trimesh.creation.cylinder(0.5, 2.0, sections=48),
        "l": l_prism(),
        "wedge": wedge(),
    }
    return model_from_object(trimesh_scene(SMOOTH, meshes), name="smooth scene")


# the cross-section (y, z) of ``stepped_prism``, counter-clockwise: a wall leaning 14 degrees
# (its slope 1/4) broken by a step square to the y axis, the same wall going on above it
STEPPED_SECTION = np.array([[0, 0], [2, 0], [2.25, 1], [2.25, 1.5], [2.5, 2.5], [0, 2.5]], float)
# the step's two long edges, along x, in the prism's frame
STEP_EDGES = np.array([[[0, 2.25, 1], [1.5, 2.25, 1]], [[0, 2.25, 1.5], [1.5, 2.25, 1.5]]])


def stepped_prism() -> trimesh.Trimesh:
    """``STEPPED_SECTION`` drawn out 1.5 along x, closed, outward-wound: the step's face is seen
    edge-on along z, where the walls on either side of it, 14 degrees from it (no crease), both
    face away from the eye; only the flat path's edge-on rule (``lines._with_edge_on_outlines``)
    draws its outline."""
    n = len(STEPPED_SECTION)
    vertices = np.r_[np.c_[np.zeros(n), STEPPED_SECTION], np.c_[np.full(n, 1.5), STEPPED_SECTION]]
    caps = [[0, 1, 2], [0, 2, 3], [0, 3, 5], [3, 5, 4]]
    faces = caps + [[a + n, c + n, b + n] for a, b, c in caps]
    for k in range(n):
        j = (k + 1) % n
        faces += [[k, j, j + n], [k, j + n, k + n]]
    mesh = trimesh.Trimesh(vertices, np.array(faces), process=False)
    mesh.fix_normals()
    return mesh


# (mesh, transform) of stepped_scene's instances: turned about z (the step still edge-on along
# z), mirrored through x and through z, scaled by 2, turned about x (the step faces z), an L
STEPPED = [
    ("step", placed()),
    ("step", placed(turn(2, 90), (4, 0, 0))),
    ("step", placed(MIRROR_X, (-1, 0, 0))),
    ("step", placed(MIRROR_Z, (0, 0, -4))),
    ("step", placed(2 * np.eye(3), (0, 5, 0))),
    ("step", placed(turn(0, 90), (0, -4, 0))),
    ("l", placed(None, (6, 0, 0))),
]


def stepped_scene() -> Model:
    """The scene of ``STEPPED`` (``stepped_prism`` and ``l_prism``), kept as instances."""
    meshes = {"step": stepped_prism(), "l": l_prism()}
    return model_from_object(trimesh_scene(STEPPED, meshes), name="stepped scene")
