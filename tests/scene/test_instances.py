"""Models kept as instances (blueprint.scene.instances): loaded, checked, fitted and their parts
chosen without flattening, and flattened, when asked, into the loader's own arrays."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from instanced_scenes import (
    EXACT,
    TURNED,
    copies,
    exact_scene,
    flattened,
    l_prism,
    placed,
    trimesh_scene,
    turn,
    turned_scene,
)

import blueprint
from blueprint.errors import InputError
from blueprint.scene import loader
from blueprint.scene import model as model_module
from blueprint.scene.camera import fit_camera, sheet_cameras
from blueprint.scene.environment import choose_parts, environment_parts
from blueprint.scene.instanced_parts import choose_instanced_parts, environment_of, stand_in


@pytest.fixture
def never_flattened(monkeypatch):
    """Any read of a kept model's flattened arrays fails the test."""
    original = model_module._Flattened.__get__

    def refuse(self, model, owner=None):
        if model is not None and model.__dict__[self.key] is None:
            raise AssertionError(f"{self.name} of a model kept as instances was read")
        return original(self, model, owner)

    monkeypatch.setattr(model_module._Flattened, "__get__", refuse)


def test_flattened_arrays_are_the_loaders(never_flattened, monkeypatch):
    """The arrays a kept model makes on first read are those the loader makes flattening the
    scene, to the bit, in its order (face i is triangle i either way)."""
    scene = trimesh_scene(EXACT + TURNED)
    model = loader.model_from_object(scene, name="scene")
    assert model.instances is not None and not model.is_flat
    positions, faces, face_part, names = loader._flatten(scene, None)
    monkeypatch.undo()
    assert np.array_equal(model.positions, positions.astype(np.float32))
    assert np.array_equal(model.faces, faces)
    assert np.array_equal(model.face_part, face_part)
    assert model.part_names == tuple(names) and model.is_flat


def test_loading_and_fitting_a_glb_never_flattens(never_flattened, monkeypatch, tmp_path):
    """A GLB of instanced meshes loads, reports its size and parts and fits every camera from
    its unique meshes and transforms: the same bounds and cameras as its flattened twin."""
    path = tmp_path / "scene.glb"
    path.write_bytes(trimesh_scene(EXACT + TURNED).export(file_type="glb"))
    model = blueprint.load_model(path)
    assert model.instances is not None and model.instances.mesh_count == 2
    assert model.triangle_count == 5 * 20 + 3 * 8 + 20 + 8
    assert sorted(model.part_triangle_counts()) == [8] * 4 + [20] * 6
    model.content_digest()
    cameras = [
        fit_camera(model, (320, 200), view, ortho=ortho)
        for view in ("iso", "front", "top")
        for ortho in (0, 1)
    ]
    sheet = sheet_cameras(model, (200, 200))
    bounds = model.bounds
    monkeypatch.undo()
    flat = flattened(blueprint.load_model(path))
    assert np.array_equal(bounds, flat.bounds)
    twins = [
        fit_camera(flat, (320, 200), view, ortho=ortho)
        for view in ("iso", "front", "top")
        for ortho in (0, 1)
    ]
    assert cameras == twins and sheet == sheet_cameras(flat, (200, 200))


def test_bounds_are_of_the_used_vertices_placed():
    """Each instance's bounds are those of its mesh's used vertices as placed: a vertex no face
    uses is left out, as the flattened model leaves it out."""
    mesh = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [9, 9, 9]], [[0, 1, 2]], process=False)
    scene = trimesh_scene([("m", placed(None, (k, 0, 0))) for k in range(4)], {"m": mesh})
    model = loader.model_from_object(scene, name="scene")
    assert model.instances is not None
    assert np.array_equal(model.bounds, [[0, 0, 0], [4, 1, 0]])


@pytest.mark.parametrize("turned", [False, True])
def test_cameras_of_many_instances_read_the_instances_at_their_edges(turned, monkeypatch):
    """A camera fitted to a pattern of instances is its flattened twin's to the bit, every
    view, perspective and orthographic, while the fit places the vertices of the instances
    that may hold an extreme point alone: those at the pattern's edges, not all of them (the
    copies stand at different heights: copies tied for the lowest all hold it). Each copy
    turned its own way, the same cameras."""
    rng = np.random.default_rng(5)
    grid = [
        (
            "l" if k % 3 else "wedge",
            placed(
                turn(int(rng.integers(3)), float(rng.uniform(0, 360))) if turned else None,
                (3 * (k % 12), 0.37 * (k % 5), 3 * (k // 12)),
            ),
        )
        for k in range(144)
    ]
    model = loader.model_from_object(trimesh_scene(grid), name="scene")
    assert model.instances is not None
    read = []
    placed_points = model_module.Model.placed_points

    def counted(self, keep):
        read.append(int(keep.sum()))
        return placed_points(self, keep)

    monkeypatch.setattr(model_module.Model, "placed_points", counted)
    views = [(v, o, az) for v in ("iso", "front", "top") for o in (0, 1) for az in (None, 20.0)]
    cameras = [fit_camera(model, (320, 200), v, ortho=o, azimuth=az) for v, o, az in views]
    flat = flattened(loader.model_from_object(trimesh_scene(grid), name="scene"))
    assert cameras == [fit_camera(flat, (320, 200), v, ortho=o, azimuth=az) for v, o, az in views]
    fits = len(views) + sum(o == 0 for _, o, _ in views)
    assert sum(read) < 0.25 * fits * len(grid)


def test_instances_turned_alike_have_their_flattened_bounds():
    """Each instance's bounds equal its flattened vertices' to the bit, where instances share
    a turn (found once for them all) and where each has its own, with shifts whose float32
    rounding would show any other order of operations."""
    rng = np.random.default_rng(3)
    shared, own = turn(1, 30) @ turn(0, 17), [turn(2, float(d)) * 1.3 for d in rng.uniform(0, 360, 6)]
    turns = [shared] * 12 + own + [np.eye(3)] * 5
    instances = [
        (("l", "wedge")[k % 2], placed(linear, rng.normal(size=3) * 10.0 ** rng.integers(0, 6)))
        for k, linear in enumerate(turns)
    ]
    model = loader.model_from_object(trimesh_scene(instances), name="scene")
    assert model.instances is not None and len(model.instances.mesh) == len(instances)
    boxes = model.instance_boxes()
    flat = flattened(loader.model_from_object(trimesh_scene(instances), name="scene"))
    for part in range(len(instances)):
        placed_vertices = flat.positions[flat.faces[flat.face_part == part]].reshape(-1, 3)
        assert np.array_equal(boxes[part], [placed_vertices.min(axis=0), placed_vertices.max(axis=0)])


def test_parts_chosen_by_name_keep_the_instances(never_flattened, monkeypatch):
    """``include`` / ``exclude`` keep the instances of the chosen parts, renumbered, as
    instances: the same triangles as choosing among the flattened model's parts."""
    model = exact_scene()
    chosen = loader.model_from_object(model, include=["l*"], exclude=["l3"])
    assert chosen.instances is not None and chosen.part_names == ("l0", "l2", "l5", "l6")
    assert list(chosen.instances.part) == [0, 1, 2, 3] and chosen.instances.mesh_count == 1
    bounds = chosen.bounds
    monkeypatch.undo()
    twin = choose_parts(flattened(exact_scene()), include=["l*"], exclude=["l3"])
    assert np.array_equal(bounds, twin.bounds)
    ours, theirs = flattened(chosen), twin
    assert np.array_equal(ours.positions[ours.faces], theirs.positions[theirs.faces])
    assert np.array_equal(ours.face_part, theirs.face_part)
    with pytest.raises(InputError, match="--include/--exclude leave no part"):
        choose_instanced_parts(model, exclude=["*"])


def skybox_scene() -> trimesh.Scene:
    """30 copies of the L prism inside an inward-facing box far larger than them (a mesh
    used once)."""
    sky = trimesh.creation.box(extents=(80, 80, 80))
    sky.invert()
    scene = trimesh_scene(
        [("m", placed(None, (3 * (k % 6), 0, 3 * (k // 6)))) for k in range(30)], {"m": l_prism()}
    )
    scene.add_geometry(sky, geom_name="sky", node_name="sky")
    return scene


def test_environment_left_out_without_flattening(never_flattened, caplog):
    """A skybox around an instanced scene is found on the stand-in (each part's bounds, the
    triangles of the parts that could enclose the rest) and left out, the scene kept as
    instances; the flattened scene finds the same parts."""
    scene = skybox_scene()
    model = loader.model_from_object(scene, name="sky scene")
    assert model.instances is not None and "sky" not in model.part_names
    assert "left out sky" in caplog.text
    whole = loader.model_from_object(scene, name="sky scene", include=["*"])
    found = environment_parts(stand_in(whole))
    assert list(np.flatnonzero(found)) == [whole.part_names.index("sky")]
    # the stand-in holds the sky's triangles alone, and a triangle of no area a part
    assert stand_in(whole).triangle_count == len(whole.part_names) + 12


def test_flattened_twin_finds_the_same_environment():
    scene = skybox_scene()
    whole = loader.model_from_object(scene, name="sky scene", include=["*"])
    flat = flattened(whole)
    assert np.array_equal(environment_parts(flat), environment_parts(stand_in(whole)))
    # ``environment_of`` a flat model is the model's own
    assert np.array_equal(environment_of(flat), environment_parts(flat))


def test_the_environment_of_a_kept_model_is_found_without_flattening_it(never_flattened):
    """``environment_of`` a model kept as instances (what ``blueprint info`` lists) tests its
    stand-in: the sky found, the model never flattened."""
    whole = loader.model_from_object(skybox_scene(), name="sky scene", include=["*"])
    assert whole.instances is not None
    assert list(np.flatnonzero(environment_of(whole))) == [whole.part_names.index("sky")]


def test_copies_in_one_place_are_refused_in_one_line():
    """300 instances of a mesh at one transform are 300 copies of each triangle: refused as
    the flattened copies are, before anything is drawn."""
    scene = trimesh_scene([("l", np.eye(4))] * 300)
    with pytest.raises(InputError, match="300 faces lie on one another"):
        loader.model_from_object(scene, name="stack")


def test_copies_placed_by_transforms_equal_as_numbers_are_one_place():
    """Transforms equal as numbers place copies in one place, though -0.0 and 0.0 differ in
    their bits: 150 of each are 300 copies, refused; 150 a transform apart are not."""
    signed = np.eye(4)
    signed[:3, 3] = -0.0
    scene = trimesh_scene([("l", np.eye(4))] * 150 + [("l", signed)] * 150)
    with pytest.raises(InputError, match="300 faces lie on one another"):
        loader.model_from_object(scene, name="stack")
    moved = np.eye(4)
    moved[0, 3] = 1e-9
    apart = trimesh_scene([("l", np.eye(4))] * 150 + [("l", moved)] * 150)
    assert loader.model_from_object(apart, name="two").triangle_count > 0


def test_nan_vertices_counted_per_instance():
    mesh = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [np.nan, 0, 0]], [[0, 1, 2], [0, 1, 3]], process=False
    )
    scene = trimesh_scene([("m", placed(None, (k, 0, 0))) for k in range(3)], {"m": mesh})
    with pytest.raises(InputError, match="3 vertices have NaN"):
        loader.model_from_object(scene, name="nan scene")


def test_degenerate_faces_counted_per_instance(caplog):
    mesh = trimesh.Trimesh(
        [[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], [[0, 1, 2], [0, 1, 3]], process=False
    )
    scene = trimesh_scene([("m", placed(None, (k, 0, 0))) for k in range(3)], {"m": mesh})
    model = loader.model_from_object(scene, name="flat scene")
    assert model.instances is not None and "dropped 3 degenerate faces" in caplog.text


def test_scenes_drawing_meshes_once_stay_flat():
    """Only scenes drawing at least twice their unique triangles are kept as instances."""
    once = loader.model_from_object(trimesh_scene(EXACT[:2]), name="two")
    assert once.instances is None
    assert loader.model_from_object(copies(3), name="three").instances is not None


def test_a_kept_model_turned_up_stays_kept():
    model = turned_scene()
    turned = loader.model_from_object(model, up="z")
    assert turned.up == "z" and turned.instances is model.instances and not turned.is_flat
