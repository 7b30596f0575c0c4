"""Meshes of more parts than a surface's 16 bits hold (``render.mesh.NARROW_PARTS``): the
k-buffer and the A-buffer pack their surfaces' normals in 32 bits instead and keep the parts
whole (kbuffer.glsl's WIDE_PARTS), where they used to hand such a frame to the peel, a
geometry pass a layer. Every way captures such a frame itself, each pixel's part and normal
are its face's, and the graphics pipeline's ways give the peel's layers (whose part channel is
written from the vertices, never packed)."""

from __future__ import annotations

import numpy as np
import pytest
from capture_helpers import DEPTH_STEP, WAYS, captured_way, one_way, slim_normal_tolerance

from blueprint.render.capture import Capture, gbuffer
from blueprint.render.mesh import NARROW_PARTS
from blueprint.scene.camera import Camera
from blueprint.scene.instances import Instances
from blueprint.scene.model import Model

SIZE = (96, 96)
# two sheets of copies, one behind the other: the nearest parts number past 16 bits
SIDE = 188
SHEETS = 2


def tetrahedra(side: int = SIDE, sheets: int = SHEETS, seed: int = 7) -> Model:
    """``side`` x ``side`` x ``sheets`` tetrahedra on a grid, each turned its own way and its
    own part, kept as instances of one mesh: normals every way, overlapping in depth."""
    rng = np.random.default_rng(seed)
    corners = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float) * 0.9
    faces = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]], np.int32)
    n = side * side * sheets
    k = np.arange(n)
    # a random rotation each (QR of a Gaussian matrix, its sign fixed to a proper rotation)
    q, r = np.linalg.qr(rng.normal(size=(n, 3, 3)))
    q *= np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 0] *= -1
    transform = np.zeros((n, 4, 4))
    transform[:, :3, :3] = q
    transform[:, :3, 3] = np.c_[k % side, (k // side) % side, -3.0 * (k // (side * side))] * 2.0
    transform[:, 3, 3] = 1.0
    # numbered from the back: the parts past 16 bits lie in the front sheet
    part = (n - 1 - k).astype(np.int32)
    instances = Instances(
        corners, faces, np.array([0, 4]), np.array([0, 4]), np.zeros(n, np.int32), transform, part
    )
    return Model(None, None, None, tuple(f"t{i}" for i in range(n)), "y", "tetrahedra", instances=instances)


def _layers(renderer, model: Model) -> tuple[list, str]:
    """Every layer's (depth, normal, ids) of a capture of ``model`` head-on, and its way."""
    mesh = renderer.mesh(model, 30.0)
    gb = gbuffer(renderer.pool, SIZE, "test.wide")
    capture = Capture(renderer.capturer, mesh, _camera(model), gb, layers=None)
    got = []
    for layer in range(64):
        capture.draw(layer, renderer.queries("test.wide")[0])
        depth = np.frombuffer(gb.layer_depth(layer).read(), np.float32).reshape(SIZE[::-1]).copy()
        covered = depth < 1
        if not covered.any():
            break
        normal = np.frombuffer(gb.normal.read(), np.float16).reshape(SIZE[1], SIZE[0], 4)[..., :3]
        ids = np.frombuffer(gb.ids.read(), np.int32).reshape(SIZE[1], SIZE[0], 2)
        got.append((depth, np.where(covered[..., None], normal, 0), np.where(covered[..., None], ids, 0)))
    way = capture.way
    capture.release()
    return got, way


def _camera(model: Model) -> Camera:
    return Camera.fit(model.positions, "front", aspect=1.0, ortho=False)


def _assert_true_to_the_faces(model: Model, layers: list, tolerance: float) -> None:
    """Each covered pixel's part is its face's, and its normal its face's (eye space, up to the
    side it is seen from): found from the model, not from any capture."""
    p, f = model.positions.astype(np.float64), model.faces
    normal = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
    normal = normal / np.linalg.norm(normal, axis=1, keepdims=True) @ _camera(model).view_matrix()[:3, :3].T
    for _, n, ids in layers:
        covered = ids[..., 0] > 0
        face, part = ids[covered, 0] - 1, ids[covered, 1] - 1
        assert np.array_equal(part, model.parts_of(face))
        got, true = n[covered].astype(np.float64), normal[face]
        off = np.minimum(np.abs(got - true).max(axis=1), np.abs(got + true).max(axis=1))
        assert off.max() <= tolerance, off.max()


@pytest.fixture(scope="module")
def wide() -> Model:
    model = tetrahedra()
    assert len(model.part_names) > NARROW_PARTS
    return model


@pytest.mark.parametrize("way", WAYS)
def test_every_way_keeps_parts_past_16_bits(renderer, wide, way):
    """Every way captures the frame itself (none hands it to the peel), each pixel's part is
    its face's and its normal its face's within a half's rounding and the octahedral pair's
    step; the graphics pipeline's ways give the peel's depths, faces and parts to the bit (the
    compute rasteriser covers pixels by rules of its own: test_compute_capture's oracle)."""
    with captured_way(renderer, way):
        ours, used = _layers(renderer, wide)
    if way.startswith("a-buffer"):
        assert used == "A-buffer" + (", compute rasteriser" if "compute" in way else "")
    else:
        assert used == way
    assert len(ours) >= 3
    parts = np.concatenate([ids[..., 1][ids[..., 1] > 0] - 1 for _, _, ids in ours])
    assert parts.max() > NARROW_PARTS and len(np.unique(parts)) > 500
    _assert_true_to_the_faces(wide, ours, max(2e-3, slim_normal_tolerance(renderer)))
    if "compute" in way:
        return
    with one_way(renderer, "peel"):
        theirs, _ = _layers(renderer, wide)
    assert len(ours) == len(theirs)
    differ = np.zeros(SIZE[::-1], bool)
    for (d, _, ids), (pd, _, pids) in zip(ours, theirs, strict=True):
        differ |= (np.abs(d - pd) > DEPTH_STEP) | (ids != pids).any(axis=-1)
    # surfaces a peeling tolerance apart merge either way (test_abuffer's same layers): a handful
    assert differ.sum() <= 3, f"{differ.sum()} pixels differ"
