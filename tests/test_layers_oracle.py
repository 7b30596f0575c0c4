"""Depth layers agree with an independent ray-casting oracle (tests/oracle.py).

The GPU peels; trimesh casts one ray per pixel centre through the same view and projection
matrices, in float64, and merges coincident hits. Both must find the same number of surfaces
at every covered pixel, at the same depths, with the same triangle and part IDs.

Which pixels are left out, and why that is fair: the comparison skips pixels where the
oracle's own layer count changes when its ray moves a quarter pixel along x or y. There a
silhouette, a mesh border or the end of a surface passes within about a quarter pixel of the
pixel centre, and which side of it the centre lies on is decided by the rasterizer's fixed-point
snapping of vertices (1/256 px on llvmpipe, at least 1/16 px by the GL spec) and its tie-breaking
rules, not by the geometry; the oracle has neither. Every other covered pixel counts, and at
least 99.8 % of them must agree exactly in count and within tolerance in depth
(``oracle.compare_layers`` explains the tolerance). The rare pixels where two hits lie about one
merge tolerance apart (so "one surface or two" is decided by float rounding on either side)
stay in the denominator; failure messages count them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pytest
import trimesh
from capture_helpers import nested_boxes, nested_round, one_way, sphere_in_cube
from helpers import SNAPPED_GEOMETRY, run_cli
from oracle import (
    accepted_faces,
    cast_oracle,
    compare_layers,
    depth_range,
    layer_count,
    raycast_layers,
    window_to_eye_depth,
)

import blueprint
from blueprint import examples
from blueprint.render import mesh
from blueprint.render.gbuffer import depth_tolerance
from blueprint.render.table import ABufferRow, PeelRow

# share of compared pixels that must agree (depth layers) and of interior pixels (IDs)
DEPTH_AGREEMENT = 0.998
ID_AGREEMENT = 0.995
# Hits closer than this (eye depth, fraction of the depth range) are one surface in the oracle's
# own test of coincident faces below
MERGE_TOL = 1e-5


def merge_tol(model: blueprint.Model, camera: blueprint.Camera) -> float:
    """The oracle's merge tolerance for ``model`` seen by ``camera`` (a fraction of the depth
    range): the capture's depth tolerance (``gbuffer.depth_tolerance``), far below any gap a
    model here has on purpose (the thinnest, the gearbox cover's 1.5-unit walls, is about 1e-2
    of its range): where two hits lie that close, "one surface" is the renderer's rule."""
    return depth_tolerance(camera, model.bounds) / (camera.far - camera.near)


@dataclass(frozen=True)
class Case:
    name: str
    source: object  # a function making a Model, or a path under ../shared/models
    size: tuple[int, int] = (128, 128)
    camera: dict = field(default_factory=dict)

    def model(self, request) -> blueprint.Model:
        if callable(self.source):
            return self.source()
        root = request.getfixturevalue("shared_models")
        return _load(root / self.source)


_MODELS: dict[Path, blueprint.Model] = {}


def _load(path: Path) -> blueprint.Model:
    if path not in _MODELS:
        # the shared_models fixture skips where ../shared/models is absent; a model missing
        # from it is a broken copy
        assert path.exists(), f"{path} is missing from the shared models"
        _MODELS[path] = blueprint.load_model(path)
    return _MODELS[path]


CASES = [
    Case("nested-boxes", nested_boxes),
    Case("nested-boxes-ortho", nested_boxes, (120, 96), dict(ortho=True, azimuth=30.0, elevation=20.0)),
    Case("nested-round", nested_round, camera=dict(azimuth=20.0, elevation=35.0)),
    Case("sphere-in-cube", sphere_in_cube),
    Case("gearbox", examples.gearbox),
    Case("gearbox-front-ortho", examples.gearbox, camera=dict(view="front", ortho=True)),
    Case("fandisk", "common-3d-test-models/fandisk.obj"),
    Case("bunny-ortho", "libigl-tutorial-data/bunny.off", camera=dict(ortho=True, view="left")),
    Case("featuretype", "trimesh/featuretype.STL", (112, 128), dict(azimuth=-30.0, elevation=40.0)),
    # plan view: hole and pocket walls edge-on, their rims seen head-on
    Case("featuretype-top-ortho", "trimesh/featuretype.STL", (256, 256), dict(view="top", ortho=True)),
    Case("rod-assembly", "trimesh/converted/rod.glb"),
    Case("engine-assembly", "glTF-Sample-Models/2CylinderEngine.glb"),
]

# The ways the renderer peels: a geometry pass a layer (its back-face tie-break in the shader,
# or as two culled draws: big frames of dense models on a GPU; both forced here whatever the
# size), a k-buffer (several layers a pass, where the driver has framebuffer fetch or
# interlock; forced whatever the model's size), the A-buffer (every layer from one geometry
# pass, OpenGL 4.3; forced whatever the layers), and the lean pass of vector drawings (no
# normals: depth and triangle IDs alone).
# a-buffer-slim: fragments listed as depth and face alone, the rest found by the sort: what GPUs
# use (ABufferRow.slim); a-buffer-compute: those listed by the rasteriser in compute
# (render.raster, ABufferRow.compute_from: forced whatever the size)
METHODS = [
    "pass-a-layer",
    "two-culled-draws",
    "k-buffer",
    "a-buffer",
    "a-buffer-slim",
    "a-buffer-compute",
    "ids-only",
]


@pytest.fixture(params=METHODS)
def method(request, renderer):
    """The renderer capturing every frame the method's way (``render.table``: a capture table
    of that way alone, whatever its thresholds, the peel taking what it cannot)."""
    way = "a-buffer" if request.param.startswith("a-buffer") else request.param
    slim = request.param in ("a-buffer-slim", "a-buffer-compute")
    compute_from = 0 if request.param == "a-buffer-compute" else None
    peel = PeelRow(culled_from=(0, 0) if request.param == "two-culled-draws" else None)
    with one_way(
        renderer,
        way,
        abuffer=lambda _: ABufferRow(1 << 30, min_layers=2, slim=slim, compute_from=compute_from),
        peel=peel,
    ):
        yield request.param


# peeled Layers per (case, method) and the Oracle per case, shared by the depth and ID tests
_LAYERS: dict[tuple[str, str], object] = {}
_ORACLES: dict[str, tuple] = {}


def _peel_and_cast(case: Case, renderer, request, method: str = "pass-a-layer"):
    key = (case.name, method)
    if key not in _LAYERS:
        model = case.model(request)
        normals = method != "ids-only"
        _LAYERS[key] = blueprint.peel(
            model, size=case.size, renderer=renderer, normals=normals, **case.camera
        )
        assert (_LAYERS[key].normal is None) != normals
    layers = _LAYERS[key]
    if case.name not in _ORACLES:
        model = case.model(request)
        oracle = cast_oracle(
            model.positions,
            model.faces,
            layers.view,
            layers.projection,
            *case.size,
            merge_tol=merge_tol(model, layers.camera),
        )
        _ORACLES[case.name] = (model, oracle)
    model, oracle = _ORACLES[case.name]
    return model, layers, oracle


# -- the oracle itself ---------------------------------------------------------------------------
@pytest.mark.parametrize("ortho", [False, True], ids=["perspective", "ortho"])
def test_oracle_model_space_rays_match_ndc_rays(ortho):
    """The fast path (rays mapped to NDC) finds the hits of the literal model-space rays."""
    for model in (nested_boxes(), sphere_in_cube()):
        camera = blueprint.Camera.fit(model.positions, "iso", ortho=ortho, aspect=48 / 40)
        view, proj = camera.view_matrix(), camera.projection_matrix()
        fast, fast_face = raycast_layers(model.positions, model.faces, view, proj, 48, 40, space="ndc")
        slow, slow_face = raycast_layers(model.positions, model.faces, view, proj, 48, 40, space="model")
        assert fast.shape == slow.shape and fast.shape[0] >= 4
        assert np.array_equal(layer_count(fast), layer_count(slow))
        assert np.abs(fast.astype(np.float64) - slow).max() < 1e-6
        assert (fast_face == slow_face).mean() > 0.999


def test_oracle_on_a_hand_computed_box():
    """Front ortho view of a box: two surfaces per covered pixel, at the depths of its faces."""
    positions, faces = examples.box((-1, -1, -0.5), (1, 1, 0.5))
    view = np.eye(4)
    view[2, 3] = -5.0  # eye at z = 5 looking down -z: the box spans eye depths 4.5 .. 5.5
    proj = np.diag([1 / 2, 1 / 2, -2 / (8 - 2), 1.0])
    proj[2, 3] = -(8 + 2) / (8 - 2)  # near 2, far 8, view 4 x 4 units wide
    depth, face = raycast_layers(positions, faces, view, proj, 16, 16)
    assert depth.shape == (2, 16, 16)
    inside = np.zeros((16, 16), bool)
    inside[4:12, 4:12] = True  # x, y in [-1, 1] is the middle half of the image
    assert np.array_equal(layer_count(depth), np.where(inside, 2, 0))
    eye = window_to_eye_depth(depth, proj)
    assert np.allclose(eye[0][inside], 4.5) and np.allclose(eye[1][inside], 5.5)
    assert set(np.unique(face[0][inside])) == {10, 11}  # z = hi faces
    assert set(np.unique(face[1][inside])) == {8, 9}
    assert depth_range(proj) == pytest.approx((2.0, 8.0))


def test_oracle_merges_coincident_faces():
    """Two boxes sharing a face: the shared plane is one surface, the ray sees three."""
    model = examples.assemble(
        {"left": examples.box((-1, -1, -1), (0, 1, 1)), "right": examples.box((0, -1, -1), (1, 1, 1))}
    )
    camera = blueprint.Camera.fit(model.positions, "front", azimuth=60.0, ortho=True)
    depth, _, hits = raycast_layers(
        model.positions,
        model.faces,
        camera.view_matrix(),
        camera.projection_matrix(),
        32,
        32,
        return_hits=True,
    )
    counts = layer_count(depth)
    assert set(np.unique(counts)) <= {0, 2, 3}
    assert (counts == 3).sum() > 50
    assert (hits.gap[hits.gap < MERGE_TOL] >= 0).all() and (hits.gap < 1e-9).any()


def test_oracle_accepts_either_side_of_a_step_through_the_centre():
    """Two slabs side by side, one higher, seen from above: two surfaces at every pixel on either
    side, so the layer count does not change at the step; the front surface's depth does. Where
    the step passes through a pixel centre, the depth of either side is right (the rasterizer's
    snapping decides); half a pixel from it, only the centre's side is."""
    model = examples.assemble(
        {"low": examples.box((-1, -1, -1), (0, 1, 0)), "high": examples.box((0, -1, -1), (1, 1, 0.5))}
    )
    view = np.eye(4)
    view[2, 3] = -5.0  # eye at z = 5 looking down -z onto both tops
    proj = np.diag([1 / 1.6, 1 / 1.6, -2 / (8 - 2), 1.0])
    proj[2, 3] = -(8 + 2) / (8 - 2)
    # 40 px over x in [-1.6, 1.6], moved 0.4 px: the step at x = 0 passes a tenth of a pixel
    # beside column 20's centre (not through it: a ray in the walls' plane meets them), more
    # than half a pixel from columns 19 and 21
    proj[0, 3] = 0.4 / 20
    oracle = cast_oracle(model.positions, model.faces, view, proj, 40, 8)
    assert set(layer_count(oracle.depth)[4, 8:32].tolist()) == {2} and not oracle.boundary[4, 19:22].any()
    low, high = oracle.depth[0, 4, 19], oracle.depth[0, 4, 21]
    assert high < low
    for col, other in ((20, high if oracle.depth[0, 4, 20] == low else low), (19, high), (21, low)):
        depth = oracle.depth.copy()
        depth[0, 4, col] = other
        result = compare_layers(depth, oracle)
        assert result.agree[4, col] == (col == 20), (col, result.describe())


# -- GPU against the oracle ----------------------------------------------------------------------
@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_depth_layers_match_oracle(case, method, renderer, request):
    _, layers, oracle = _peel_and_cast(case, renderer, request, method)
    result = compare_layers(layers.depth, oracle)
    assert result.compared.sum() > 0.25 * result.covered.sum(), result.describe()
    assert result.fraction >= DEPTH_AGREEMENT, result.describe()


@pytest.mark.parametrize("exact", [False, True], ids=["depth-as-rasterised", "exact-depth"])
def test_exact_depth_undoes_snapped_corners(exact, method, renderer, monkeypatch, request):
    """A rasteriser taking depth from the plane through corners snapped to its sub-pixel grid
    (the H200's: 1/256 px; ``Device.snapped_depth``) gives coincident faces of one part with
    different corners depths up to the slope times the snap apart, and the peel keeps them as
    two layers: on the H200 the gearbox had 248 of 5 878 pixels a layer too many. Corners
    snapped the same way in the vertex shader reproduce it on any driver; exact depth (the
    depth moved along the true plane to the pixel centre) brings back the oracle's layers."""
    case = next(c for c in CASES if c.name == "gearbox")
    model, _, oracle = _peel_and_cast(case, renderer, request, method)
    monkeypatch.setattr(mesh, "GEOMETRY_VERT", SNAPPED_GEOMETRY)
    monkeypatch.setattr(renderer, "capture_table", replace(renderer.capture_table, exact_depth=exact))
    layers = blueprint.peel(model, size=case.size, renderer=renderer, normals=method != "ids-only")
    result = compare_layers(layers.depth, oracle)
    # the compute rasteriser takes every depth from the plane through the projected corners,
    # never from snapped ones, exact depth or not
    if exact or method == "a-buffer-compute":
        assert result.fraction >= DEPTH_AGREEMENT, result.describe()
    else:
        assert (result.compared & ~result.count_ok).sum() > 0.01 * result.compared.sum(), result.describe()


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_ids_match_oracle(case, method, renderer, request):
    """Triangle IDs name a face the pixel's ray hits on that surface; part IDs are its part."""
    model, layers, oracle = _peel_and_cast(case, renderer, request, method)
    result = compare_layers(layers.depth, oracle)
    drawn = layers.triangle >= 0
    assert np.array_equal(drawn, layers.depth < 1.0)
    assert np.array_equal(layers.part[drawn], model.face_part[layers.triangle[drawn]])
    assert (layers.part[~drawn] == -1).all()

    interior = result.compared & result.count_ok
    count = layer_count(layers.depth)
    ok = accepted_faces(oracle, layers.triangle[: len(oracle.depth)])
    seen = interior & (count > 0)
    front = ok[0][seen]
    assert front.mean() >= ID_AGREEMENT, f"layer 0 triangles: {front.mean():.4f} of {front.size} pixels"
    part = layers.part[0][seen] == model.face_part[oracle.face[0][seen]]
    assert part.mean() >= ID_AGREEMENT, f"layer 0 parts: {part.mean():.4f} of {part.size} pixels"
    every = ok & (np.arange(len(ok))[:, None, None] < count) & interior
    total = (interior * count).sum()
    assert every.sum() / total >= ID_AGREEMENT, f"all layers: {every.sum()} of {total} surfaces"


# every other shared model, at a smaller size and in the renderer's own choice of method (the
# cases above try every method): none of them is below the agreement either
OTHER_SHARED = [
    "common-3d-test-models/stanford-bunny.obj",
    "common-3d-test-models/teapot.obj",
    "common-3d-test-models/spot.obj",
    "common-3d-test-models/rocker-arm.obj",
    "common-3d-test-models/ogre.obj",
    "common-3d-test-models/cow.obj",
    "libigl-tutorial-data/armadillo.obj",
    "libigl-tutorial-data/fertility.off",
    "libigl-tutorial-data/screwdriver.off",
    "Euclid/dragon.ply",
    "glTF-Sample-Models/CesiumMilkTruck.glb",
    "trimesh/1002_tray_bottom.STL",
    "trimesh/counter.unitsmm.STL",
    "trimesh/converted/cycloidal.glb",
    "trimesh/converted/FM1_satellite.glb",
]


@pytest.mark.parametrize("path", OTHER_SHARED, ids=[p.rsplit("/", 1)[-1] for p in OTHER_SHARED])
@pytest.mark.parametrize("camera", [{}, dict(view="top", ortho=True)], ids=["iso", "top-ortho"])
def test_every_shared_model_matches_oracle(path, camera, renderer, shared_models):
    model = _load(shared_models / path)
    size = (64, 64)
    layers = blueprint.peel(model, size=size, renderer=renderer, **camera)
    view, projection = layers.view, layers.projection
    tol = merge_tol(model, layers.camera)
    oracle = cast_oracle(model.positions, model.faces, view, projection, *size, merge_tol=tol)
    result = compare_layers(layers.depth, oracle)
    # a sheet seen edge-on (the tray from the top) is nothing to either
    assert result.fraction >= DEPTH_AGREEMENT or not result.covered.any(), result.describe()


def test_oracle_rejects_wrong_layers(renderer, request):
    """The comparison is sharp enough to fail a flipped image, a half-pixel offset and a lost
    layer, so passing it means something."""
    case = next(c for c in CASES if c.name == "gearbox")
    model, layers, oracle = _peel_and_cast(case, renderer, request)
    assert compare_layers(layers.depth, oracle).fraction >= DEPTH_AGREEMENT

    flipped = layers.depth[:, ::-1]  # row 0 at the bottom
    lost = np.concatenate([layers.depth[:3], layers.depth[4:], np.ones_like(layers.depth[:1])])
    moved, _ = raycast_layers(  # sampled half a pixel to the right of the centres
        model.positions, model.faces, layers.view, layers.projection, *case.size, offset=(0.5, 0.0)
    )
    for name, wrong in (("flipped", flipped), ("lost layer 3", lost), ("half-pixel", moved)):
        fraction = compare_layers(wrong, oracle).fraction
        assert fraction < 0.95, f"{name}: {fraction:.4f} still agree"


def test_changing_size_between_frames_leaves_no_gl_error(renderer):
    """Peeling and rendering at one size, then another, is an ordinary use of one renderer (the
    cases above do it); it must not leave a GL error behind."""
    model = nested_boxes()
    _ = renderer.ctx.error  # reading the flag clears it
    errors = []
    for size in ((64, 64), (80, 48), (64, 64)):
        blueprint.peel(model, size=size, renderer=renderer)
        errors.append((f"peel {size}", renderer.ctx.error))
        renderer.render(model, size=size, max_layers=2)
        errors.append((f"render {size}", renderer.ctx.error))
    bad = [(step, error) for step, error in errors if error != "GL_NO_ERROR"]
    assert not bad, f"GL errors after changing the frame size: {bad}"


# -- the command line, end to end ----------------------------------------------------------------
def test_cli_layers_npz_matches_oracle(shared_models, tmp_path):
    """`blueprint layers` writes the NPZ of the contract; rays cast through its own matrices at
    the mesh as trimesh loads the file (not through blueprint's loader) reproduce it."""
    path = shared_models / "trimesh" / "featuretype.STL"
    assert path.exists(), f"{path} is missing from the shared models"
    out = tmp_path / "layers.npz"
    width, height = 120, 96
    run = run_cli("layers", path, "-o", out, "--size", width, height, "--view", "iso", timeout=120)
    assert run.returncode == 0, run.stderr
    with np.load(out) as npz:
        data = {key: npz[key] for key in npz.files}
    assert {"depth", "triangle", "part", "view", "projection"} <= set(data)
    depth, triangle, part = data["depth"], data["triangle"], data["part"]
    assert depth.dtype == np.float32 and triangle.dtype == np.int32 and part.dtype == np.int32
    assert data["view"].dtype == np.float64 and data["projection"].dtype == np.float64
    assert data["view"].shape == (4, 4) and data["projection"].shape == (4, 4)
    assert depth.ndim == 3 and depth.shape[1:] == (height, width) and len(depth) >= 2
    assert triangle.shape == depth.shape and part.shape == depth.shape
    assert ((depth > 0) & (depth <= 1)).all()
    assert np.array_equal(triangle >= 0, depth < 1) and np.array_equal(part >= 0, depth < 1)
    assert (part[depth < 1] == 0).all()  # one mesh, one part
    # the matrices are what they claim: a rotation plus translation, and a projection that
    # puts window depth 0 and 1 in front of the eye
    rotation = data["view"][:3, :3]
    assert np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-9)
    near, far = depth_range(data["projection"])
    assert 0 < near < far

    mesh = trimesh.load(path, process=False, force="mesh")
    oracle = cast_oracle(mesh.vertices, mesh.faces, data["view"], data["projection"], width, height)
    result = compare_layers(depth, oracle)
    assert result.fraction >= DEPTH_AGREEMENT, result.describe()
    interior = result.compared & result.count_ok & (layer_count(depth) > 0)
    ok = accepted_faces(oracle, triangle[: len(oracle.depth)])[0][interior]
    assert ok.mean() >= ID_AGREEMENT, f"layer 0 triangles: {ok.mean():.4f} of {ok.size}"
