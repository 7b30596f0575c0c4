"""Faces of a mesh file that scatters them are loaded in an order that keeps neighbours together
(``scene.order``); the drawing is the same, face for face."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from instanced_scenes import copies

import blueprint
from blueprint.scene.camera import fit_camera
from blueprint.scene.instances import INSTANCED_FACTOR
from blueprint.scene.order import MIN_FACES, local_order, reordered_faces

# 81 920 faces: past MIN_FACES
SUBDIVISIONS = 6


@pytest.fixture(scope="module")
def sphere() -> tuple[np.ndarray, np.ndarray]:
    """A noisy icosphere's vertices (float32) and faces, in trimesh's order, which keeps a
    face's children together."""
    mesh = trimesh.creation.icosphere(subdivisions=SUBDIVISIONS)
    rng = np.random.default_rng(5)
    radius = 1 + 0.002 * rng.standard_normal(len(mesh.vertices))
    return (np.asarray(mesh.vertices) * radius[:, None]).astype(np.float32), np.asarray(mesh.faces, np.int32)


def shuffled(faces: np.ndarray, seed: int = 11) -> np.ndarray:
    return faces[np.random.default_rng(seed).permutation(len(faces))]


def write_ply(path, positions: np.ndarray, faces: np.ndarray) -> None:
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(positions)}\nproperty float x\n"
        f"property float y\nproperty float z\nelement face {len(faces)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    rows = np.empty(len(faces), np.dtype([("count", "u1"), ("corners", "<i4", 3)]))
    rows["count"], rows["corners"] = 3, faces
    with open(path, "wb") as fh:
        fh.write(header.encode())
        positions.astype("<f4").tofile(fh)
        rows.tofile(fh)


def triangles(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each face's corners' coordinates (F, 9), rows sorted: the triangles whatever their order
    and numbering."""
    rows = positions[faces].reshape(len(faces), 9)
    return rows[np.lexsort(rows.T[::-1])]


def test_a_file_in_order_keeps_it(sphere):
    positions, faces = sphere
    assert local_order(positions, faces[:, 0]) is None
    assert reordered_faces(positions, faces) is faces


def test_a_small_file_keeps_its_order_however_scattered(sphere):
    positions, faces = sphere
    few = shuffled(faces)[: MIN_FACES - 1]
    assert local_order(positions, few[:, 0]) is None


def test_scattered_faces_are_put_together(sphere):
    positions, faces = sphere
    scattered = shuffled(faces)
    found = local_order(positions, scattered[:, 0])
    assert found is not None
    assert np.array_equal(np.sort(found), np.arange(len(faces)))
    # in the new order the windows of consecutive faces lie together: the test finds nothing to do
    assert local_order(positions, scattered[found, 0]) is None
    # a face's first corners given as the rows themselves, as an STL's are
    assert np.array_equal(local_order(positions[scattered[:, 0]]), found)
    assert np.array_equal(reordered_faces(positions, scattered), scattered[found])


def test_loaded_ply_draws_the_same_face_for_face(sphere, tmp_path):
    positions, faces = sphere
    scattered = shuffled(faces)
    path = tmp_path / "scattered.ply"
    write_ply(path, positions, scattered)
    loaded = blueprint.load_model(path)
    assert not np.array_equal(loaded.faces, scattered)
    assert np.array_equal(triangles(loaded.positions, loaded.faces), triangles(positions, scattered))
    as_filed = blueprint.Model.from_arrays(positions, scattered)
    renderer = blueprint.Renderer()
    camera = fit_camera(as_filed, (160, 120))
    ours = renderer.peel(loaded, camera, size=(160, 120), max_layers=4)
    theirs = renderer.peel(as_filed, camera, size=(160, 120), max_layers=4)
    assert np.array_equal(ours.depth, theirs.depth)
    drawn = theirs.triangle >= 0
    assert np.array_equal(ours.triangle >= 0, drawn)
    # the same triangle at every pixel of every layer, under its new ID
    ours_corners = loaded.positions[loaded.faces[ours.triangle[drawn]]]
    assert np.array_equal(ours_corners, positions[scattered[theirs.triangle[drawn]]])


@pytest.mark.parametrize("suffix", ["stl", "glb"])
def test_an_stl_and_a_scene_of_one_mesh_are_ordered_as_read(sphere, tmp_path, suffix):
    """An STL stays a soup numbered by first corner; a scene's one mesh is ordered as a mesh
    file's faces are."""
    positions, faces = sphere
    scattered = shuffled(faces)
    path = tmp_path / f"scattered.{suffix}"
    trimesh.Trimesh(positions, scattered, process=False).export(path)
    loaded = blueprint.load_model(path)
    assert local_order(loaded.positions, loaded.faces[:, 0]) is None
    assert np.array_equal(
        triangles(loaded.positions.astype(np.float32), loaded.faces), triangles(positions, scattered)
    )
    if suffix == "stl":
        assert loaded.soup
        _, first = np.unique(loaded.faces.ravel(), return_index=True)
        assert np.all(np.diff(first) > 0)
        assert len(np.unique(loaded.positions, axis=0)) == len(loaded.positions)


@pytest.mark.parametrize("flaw", ["out of range", "negative"])
def test_corners_out_of_range_are_ordered_without_an_error(sphere, flaw):
    """The loader's checks, after the order is found, refuse such a file (below)."""
    positions, faces = sphere
    faces = shuffled(faces)
    faces[7, 0] = len(positions) if flaw == "out of range" else -1
    assert local_order(positions, faces[:, 0]) is not None


def test_points_not_finite_keep_their_order(sphere):
    positions, faces = sphere
    positions = positions.copy()
    positions[3] = np.nan
    assert local_order(positions, shuffled(faces)[:, 0]) is None


def test_a_scattered_file_with_bad_faces_is_refused_in_one_line(sphere, tmp_path):
    positions, faces = sphere
    faces = shuffled(faces)
    faces[100, 0] = len(positions) + 5
    path = tmp_path / "bad.ply"
    write_ply(path, positions, faces)
    with pytest.raises(blueprint.InputError, match="bad.ply"):
        blueprint.load_model(path)


def test_each_mesh_of_a_scene_is_ordered_on_its_own(sphere, tmp_path):
    """A scene's big mesh has its faces put together; the parts stay whole, in the scene's
    order, and a small mesh keeps its faces' order."""
    positions, faces = sphere
    scattered = shuffled(faces)
    box = trimesh.creation.box()
    box_faces = np.asarray(box.faces)[::-1]
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.Trimesh(box.vertices, box_faces, process=False), geom_name="box")
    scene.add_geometry(trimesh.Trimesh(positions, scattered, process=False), geom_name="scan")
    path = tmp_path / "two.glb"
    scene.export(path)
    loaded = blueprint.load_model(path)
    scan, cube = loaded.part_names.index("scan"), loaded.part_names.index("box")
    assert np.all(np.diff(loaded.face_part) >= 0) or np.all(np.diff(loaded.face_part) <= 0)
    mine = loaded.faces[loaded.face_part == scan]
    assert local_order(loaded.positions, mine[:, 0]) is None
    assert np.array_equal(
        triangles(loaded.positions.astype(np.float32), mine), triangles(positions, scattered)
    )
    box_rows = loaded.faces[loaded.face_part == cube]
    assert np.array_equal(box_rows - box_rows.min(), box_faces)


def test_a_mesh_drawn_many_times_is_ordered_once(sphere, tmp_path):
    """A scene kept as instances has its mesh's faces put together, once for every copy."""
    positions, faces = sphere
    scattered = shuffled(faces)
    scene = copies(int(INSTANCED_FACTOR) + 1, trimesh.Trimesh(positions, scattered, process=False))
    path = tmp_path / "copies.glb"
    scene.export(path)
    loaded = blueprint.load_model(path)
    assert loaded.instances is not None
    vertices, mesh_faces = loaded.instances.mesh_arrays(0)
    assert local_order(vertices, mesh_faces[:, 0]) is None
    assert np.array_equal(
        triangles(np.asarray(vertices, np.float32), mesh_faces), triangles(positions, scattered)
    )
