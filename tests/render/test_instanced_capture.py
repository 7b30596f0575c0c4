"""Models kept as instances, drawn instanced: the same layers, pictures and drawings as their
flattened twins (tests/instanced_scenes.py), by every capture way, and the ray-casting
oracle's layers (tests/oracle.py)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from capture_helpers import FACES_TABLE, WAYS, abuffer_row, captured_way
from instanced_scenes import (
    copies,
    exact_scene,
    flattened,
    l_prism,
    mixed_scene,
    placed,
    trimesh_scene,
    turned_scene,
    wedge,
)
from oracle import cast_oracle, compare_layers

import blueprint
from blueprint.render import mesh as mesh_module
from blueprint.render import renderer as renderer_module
from blueprint.render.mesh import GpuMesh, draw_groups, instance_records, placements
from blueprint.render.raster import ComputeRaster
from blueprint.render.table import CaptureTable, PeelRow, capture_table
from blueprint.scene.loader import model_from_object

SIZE = (96, 80)
CAMERA = {"view": "iso", "azimuth": 35.0, "elevation": 25.0}


@pytest.fixture(params=WAYS)
def way(request, renderer):
    """The renderer capturing every frame one way (a capture table of that way alone)."""
    with captured_way(renderer, request.param):
        yield request.param


def test_primitive_ids_start_again_for_each_instance(renderer):
    """``gl_PrimitiveID`` counts from 0 again at each instance of an instanced draw on this
    driver: each copy's pixels carry its own faces' IDs (its first face plus its mesh's face),
    which the layers' parts confirm independently (from the G-buffer's part channel)."""
    model = model_from_object(copies(9), name="copies")
    assert model.instances is not None and model.instances.mesh_count == 1
    layers = blueprint.peel(model, size=(120, 120), renderer=renderer, view="top", ortho=True, max_layers=1)
    faces, parts = layers.triangle[0], layers.part[0]
    seen = faces >= 0
    per_copy = len(model.instances.faces)
    assert len(np.unique(parts[seen])) == 9
    assert np.array_equal(faces[seen] // per_copy, parts[seen])
    # every copy shows its top's faces, the same local faces in each
    local = {p: set(np.unique(faces[seen & (parts == p)] % per_copy)) for p in range(9)}
    assert all(found == local[0] for found in local.values()) and len(local[0]) >= 2


def test_instanced_layers_are_the_flattened_ones(way, renderer):
    """Every capture way gives an instanced scene (rotated, scaled, mirrored copies) the depths,
    faces and parts of its flattened twin to the bit, and normals within float16 rounding."""
    model = exact_scene()
    flat = flattened(model)
    ours = blueprint.peel(model, size=SIZE, renderer=renderer, **CAMERA)
    theirs = blueprint.peel(flat, size=SIZE, renderer=renderer, **CAMERA)
    assert ours.depth.shape == theirs.depth.shape and ours.depth.shape[0] >= 4
    assert np.array_equal(ours.depth, theirs.depth)
    assert np.array_equal(ours.triangle, theirs.triangle)
    assert np.array_equal(ours.part, theirs.part)
    assert np.abs(ours.normal - theirs.normal).max() <= 2e-3
    # every copy is seen
    assert set(np.unique(ours.part[ours.part >= 0])) == set(range(len(model.part_names)))


def test_instanced_layers_match_the_oracle(way, renderer):
    """The layers of the instanced scene, turned copies included, agree with ray casting the
    flattened triangles (in float64, no GL) as the flattened scene's must
    (test_layers_oracle.py's agreement)."""
    model = turned_scene()
    layers = blueprint.peel(model, size=SIZE, renderer=renderer, **CAMERA)
    oracle = cast_oracle(model.positions, model.faces, layers.view, layers.projection, *SIZE, merge_tol=1e-5)
    result = compare_layers(layers.depth, oracle)
    assert result.compared.sum() > 0.25 * result.covered.sum(), result.describe()
    assert result.fraction >= 0.998, result.describe()
    front = (oracle.face[0] >= 0) & ~oracle.boundary & (layers.triangle[0] >= 0)
    assert (layers.triangle[0][front] == oracle.face[0][front]).mean() >= 0.995


def test_instanced_picture_and_drawing_are_the_flattened_ones(renderer):
    """The PNG and the SVG of the instanced scene are the flattened scene's, byte for byte."""
    model = exact_scene()
    flat = flattened(exact_scene())
    options = {"size": (160, 120), **CAMERA}
    assert blueprint.draw(model, **options).png() == blueprint.draw(flat, **options).png()
    assert (
        blueprint.draw(model, vector=True, **options).svg()
        == blueprint.draw(flat, vector=True, **options).svg()
    )


def test_turned_instances_draw_within_rounding_of_the_flattened(renderer):
    """Copies turned by 30 degrees are placed on the GPU in float32 and by the loader in
    float64: the pictures differ only where the rounding moves an edge across a pixel."""
    model = turned_scene()
    options = {"size": (160, 120), **CAMERA}
    ours = np.asarray(blueprint.draw(model, **options).image, np.int16)
    theirs = np.asarray(blueprint.draw(flattened(turned_scene()), **options).image, np.int16)
    differ = np.abs(ours - theirs).max(axis=2) > 0
    assert differ.mean() < 0.002


def test_meshes_used_once_are_drawn_in_runs(renderer):
    """A draw group per mesh used more than once, and one per run of consecutive instances of
    meshes used once, their triangles flattened: the draws follow unique meshes, not parts;
    and the layers are the flattened scene's."""
    meshes = {"l": l_prism(), "wedge": wedge(), "w1": wedge(), "w2": wedge()}
    order = ["l", "w1", "w2", "l", "wedge", "l", "wedge"]
    scene = trimesh_scene([(name, placed(None, (2 * k, 0, 0))) for k, name in enumerate(order)], meshes)
    model = model_from_object(scene, name="mixed")
    assert model.instances is not None and model.instances.mesh_count == 4
    groups = draw_groups(model, 30.0)
    assert len(groups) == 3
    first = model.instances.first_face()
    drawn = np.sort(np.concatenate([records["face"] for _, _, records in groups]))
    assert np.array_equal(drawn, first[[0, 1, 3, 4, 5, 6]])
    ours = blueprint.peel(model, size=SIZE, renderer=renderer, **CAMERA)
    theirs = blueprint.peel(flattened(model), size=SIZE, renderer=renderer, **CAMERA)
    assert np.array_equal(ours.triangle, theirs.triangle) and np.array_equal(ours.depth, theirs.depth)


def test_groups_drawn_in_pieces_give_the_same_layers(way, renderer, monkeypatch):
    """Every group drawn as draws of at most 5 faces (flattened runs and meshes shared by
    several instances alike, on any device), each at its instances with their first faces
    moved on: the layers of the mixed scene and of its flattened twin are those of one draw a
    group, bit for bit, normals included."""
    ours, theirs, draws = [], [], []
    monkeypatch.setattr(mesh_module, "PIECE_FACES", 5)
    for pieces in (False, True):

        def upload(ctx, model, crease_angle, pieces, forced=pieces):
            mesh = GpuMesh(ctx, model, crease_angle, forced)
            draws.append((forced, model.is_flat or model.instances is None, len(mesh.groups)))
            return mesh

        monkeypatch.setattr(renderer_module, "GpuMesh", upload)
        for model, out in ((mixed_scene(), ours), (flattened(mixed_scene()), theirs)):
            out.append(blueprint.peel(model, size=SIZE, renderer=renderer, **CAMERA))
            renderer.forget(model)
    groups = len(draw_groups(mixed_scene(), None))
    faces = mixed_scene().triangle_count
    assert {(p, f, n) for p, f, n in draws if not p} == {(False, False, groups), (False, True, 1)}
    split = {(f, n) for p, f, n in draws if p}
    assert (True, -(-faces // 5)) in split and any(not f and n > groups for f, n in split)
    for split, whole in ((ours[1], ours[0]), (theirs[1], theirs[0])):
        assert split.depth.shape == whole.depth.shape and split.depth.shape[0] >= 3
        for name in ("depth", "triangle", "part", "normal"):
            assert np.array_equal(getattr(split, name), getattr(whole, name)), name
    assert np.array_equal(ours[1].triangle, theirs[1].triangle)


@pytest.mark.parametrize("faces_way", list(FACES_TABLE))
def test_faces_read_by_id_are_placed_from_the_unique_meshes(renderer, monkeypatch, faces_way):
    """The compute rasteriser and the slim A-buffer's resolve read faces by their ID from the
    unique meshes, each face's instance found in the faces table: the layers of a scene of
    shared meshes and runs of meshes used once are its flattened twin's (depths, faces and
    parts to the bit), its normals those the graphics pipeline's instanced draws give (within
    float16 rounding, where both draw the same face: the compute rasteriser's coverage differs
    from the driver's at a few edge pixels, test_compute_capture.py), and its flattened arrays
    are never made (``Model``'s lazy arrays)."""
    if renderer.ctx.version_code < 430:
        pytest.skip("the A-buffer needs OpenGL 4.3")
    model, flat = mixed_scene(), flattened(mixed_scene())
    assert model.instances is not None and len(draw_groups(model, None)) == 4
    default = capture_table(renderer)
    saved = renderer.capture_table
    renderer.capture_table = CaptureTable((abuffer_row("a-buffer"), PeelRow()), default.exact_depth)
    drawn = blueprint.peel(mixed_scene(), size=SIZE, renderer=renderer, **CAMERA)
    renderer.capture_table = CaptureTable((abuffer_row(faces_way), PeelRow()), default.exact_depth)
    listed = []
    fragments = ComputeRaster.fragments
    monkeypatch.setattr(ComputeRaster, "fragments", lambda *a: listed.append(1) or fragments(*a))
    try:
        theirs = blueprint.peel(flat, size=SIZE, renderer=renderer, **CAMERA)
        ours = blueprint.peel(model, size=SIZE, renderer=renderer, **CAMERA)
    finally:
        renderer.capture_table = saved
    assert not model.is_flat  # the whole model's arrays were never made
    assert len(listed) == (2 if FACES_TABLE[faces_way][1] else 0)
    assert ours.depth.shape == theirs.depth.shape and ours.depth.shape[0] >= 3
    assert np.array_equal(ours.depth, theirs.depth)
    assert np.array_equal(ours.triangle, theirs.triangle)
    assert np.array_equal(ours.part, theirs.part)
    same = (ours.triangle == drawn.triangle) & (ours.triangle >= 0)
    assert same.sum() >= 0.99 * (drawn.triangle >= 0).sum()
    assert np.abs(ours.normal - drawn.normal)[same].max() <= 2e-3
    assert set(np.unique(ours.part[ours.part >= 0])) == set(range(7))


def test_the_faces_table_places_every_face_id():
    """Each face ID of the mixed scene finds, as instance.glsl's binary search does (the last
    placement whose first face is at most it), the index-buffer face, transform and part the
    flattened scene has for it: every face's corners and part, on the CPU."""
    model = mixed_scene()
    groups = draw_groups(model, None)
    table = placements(groups)
    assert np.all(np.diff(table["face"]) > 0) and table["face"][0] == 0
    counts = np.array([len(v) for v, _, _ in groups])
    vertices = np.concatenate([v for v, _, _ in groups])
    indices = np.concatenate(
        [i.reshape(-1, 3) + b for (_, i, _), b in zip(groups, np.cumsum(counts) - counts, strict=True)]
    )
    ids = np.arange(model.triangle_count)
    which = np.searchsorted(table["face"], ids, side="right") - 1
    face = table["base"][which] + ids - table["face"][which]
    rows = np.stack([table["x"], table["y"], table["z"]], axis=1)[which].astype(np.float64)  # (F, 3, 4)
    corners = vertices["p"][indices[face]].astype(np.float64)  # (F, 3, 3)
    placed_corners = np.einsum("fij,fkj->fki", rows[:, :, :3], corners) + rows[:, None, :, 3]
    assert np.array_equal(placed_corners.astype(np.float32), model.positions[model.faces])
    assert np.array_equal(table["part"][which] + vertices["part"][indices[face, 0]], model.face_part)


def test_only_a_flattened_model_skips_the_faces_table(renderer):
    """A flattened model's faces table is the identity alone, so its programs look nothing up
    (ONE_PLACEMENT); a model kept as instances, or one placed off the identity, looks up."""
    instanced = mixed_scene()
    flat = flattened(instanced)
    moved = instance_records(np.diag([1.0, 1.0, 1.0, 1.0]) + np.eye(4, k=3)[None], np.zeros(1), np.zeros(1))
    for model, one in ((flat, True), (instanced, False)):
        mesh = GpuMesh(renderer.ctx, model, 30.0)
        try:
            assert mesh.one_placement is one
            assert mesh.placement_defines["ONE_PLACEMENT"] is one
        finally:
            mesh.release()
    assert not mesh_module._identity(placements([(np.zeros(3), np.zeros(3, np.uint32), moved)])[0])


def test_a_flattened_models_draws_read_no_instance(way, renderer, monkeypatch):
    """A flattened model's draws are each one instance of the identity: its geometry programs
    read no instance attribute (instance.glsl's UNPLACED; a draw's first face is a uniform) and
    give the layers of the same draws placed by the identity, to the bit; a model kept as
    instances reads its instances."""
    instanced = mixed_scene()
    flat = flattened(instanced)
    for model, unplaced in ((flat, True), (instanced, False)):
        mesh = GpuMesh(renderer.ctx, model, 30.0)
        try:
            assert mesh.unplaced is unplaced and mesh.vertex_defines == {"UNPLACED": unplaced}
        finally:
            mesh.release()
    layers = []
    for unplaced in (True, False):
        if not unplaced:
            monkeypatch.setattr(GpuMesh, "vertex_defines", property(lambda mesh: {"UNPLACED": False}))
        layers.append(blueprint.peel(flat, size=SIZE, renderer=renderer, max_layers=None, **CAMERA))
        renderer.forget(flat)
    assert layers[0].depth.shape[0] >= 3
    for name in ("depth", "triangle", "part", "normal"):
        assert np.array_equal(getattr(layers[0], name), getattr(layers[1], name)), name


def test_normals_follow_the_transform_as_the_flattened_faces_turn():
    """The normals' transform is the cofactor matrix: a mirror turns normals as it turns the
    faces' winding, a scale by 2 keeps their length, a turn turns them."""
    transforms = np.stack([np.eye(4), np.diag([-1.0, 1, 1, 1]), np.diag([2.0, 2, 2, 1])])
    records = instance_records(transforms, np.arange(3), np.arange(3) * 10)
    normal = lambda r: np.stack([r["nx"], r["ny"], r["nz"]])  # noqa: E731
    assert np.array_equal(normal(records[0]), np.eye(3))
    assert np.allclose(normal(records[1]), np.diag([1.0, -1, -1]))
    assert np.allclose(normal(records[2]), np.eye(3))
    a, b, c = np.array([0.0, 0, 0]), np.array([1.0, 0.5, 0]), np.array([0.25, 1, 0.5])
    for transform, record in zip(transforms, records, strict=True):
        m = transform[:3, :3]
        moved = np.cross(m @ b - m @ a, m @ c - m @ a)
        turned = normal(record) @ np.cross(b - a, c - a)
        assert np.allclose(moved / np.linalg.norm(moved), turned / np.linalg.norm(turned))


def test_instanced_upload_holds_unique_geometry(renderer):
    """400 copies upload one mesh and 400 instance records, not 400 copies."""
    model = model_from_object(copies(400), name="copies")
    mesh = GpuMesh(renderer.ctx, model, 30.0)
    try:
        uploaded = mesh.vbo.size + mesh.ibo.size
        assert mesh.triangles == 400 * len(model.instances.faces)
        assert uploaded < 2 * 12 * len(model.instances.faces) * 28
        assert not model.is_flat
    finally:
        mesh.release()


MEMORY = textwrap.dedent(
    """
    import sys, tracemalloc
    sys.path.insert(0, sys.argv[1])
    import trimesh
    import blueprint
    from instanced_scenes import copies
    from blueprint.scene.loader import model_from_object
    scene = copies(int(sys.argv[2]), trimesh.creation.icosphere(4))
    tracemalloc.start()
    model = model_from_object(scene, name="copies")
    blueprint.draw(model, size=(128, 128)).png()
    peak = tracemalloc.get_traced_memory()[1]
    flat = model.positions.nbytes + model.faces.nbytes + model.face_part.nbytes
    print(peak, flat, model.instances is not None)
    """
)


def test_memory_of_loading_and_drawing_follows_unique_geometry(tmp_path):
    """Loading and drawing 400 copies of a mesh of 5 120 triangles takes far less host memory
    than the flattened arrays alone would (measured in a process of its own, by tracemalloc)."""
    tests = str(__import__("pathlib").Path(__file__).resolve().parents[1])
    proc = subprocess.run(
        [sys.executable, "-c", MEMORY, tests, "400"], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    peak, flat, instanced = proc.stdout.split()[-3:]
    assert instanced == "True"
    assert int(peak) < int(flat) / 4, (peak, flat)
