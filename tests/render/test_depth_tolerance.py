"""The depth tolerance comes from the geometry: surfaces a small fraction of the model apart
stay two layers in every way of capturing, whatever the camera's depth range; coincident faces
still peel as one. Layers are checked against the ray-casting oracle (tests/oracle.py), whose
merge tolerance is its own (float64 rays: far below any gap here, far above their rounding)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from capture_helpers import one_way, tab_in_slot
from oracle import cast_oracle, compare_layers, layer_count, window_to_eye_depth

from blueprint import examples
from blueprint.render.gbuffer import BACK_BIAS, depth_tolerance
from blueprint.render.table import ABufferRow
from blueprint.scene.camera import Camera

SIZE = (96, 96)
# the oracle's merge tolerance, a fraction of the depth range
ORACLE_MERGE = 1e-7


@pytest.fixture(params=["peel", "k-buffer", "a-buffer"])
def method(request, renderer):
    """The renderer capturing every frame that way alone (as tests/test_layers_oracle.py does)."""
    with one_way(renderer, request.param, abuffer=lambda _: ABufferRow(1 << 30, min_layers=2)):
        yield request.param


def _deep_camera(model, depth: float) -> Camera:
    """The fitted orthographic iso camera with its far plane ``depth`` model diagonals away:
    a camera a scene brings along, its depth range set for far more than this model."""
    camera = Camera.fit(model.positions, "iso", azimuth=30.0, elevation=25.0, ortho=True)
    diag = float(np.linalg.norm(np.ptp(model.bounds, axis=0)))
    return dataclasses.replace(camera, far=camera.near + depth * diag)


def _layers_and_oracle(renderer, model, camera):
    layers = renderer.peel(model, camera, size=SIZE)
    oracle = cast_oracle(
        model.positions, model.faces, layers.view, layers.projection, *SIZE, merge_tol=ORACLE_MERGE
    )
    return layers, oracle


@pytest.mark.parametrize("depth", [1.0, 200.0], ids=["fitted", "deep-range"])
def test_tab_in_slot_keeps_its_layers(method, renderer, depth):
    """A tab 0.1 % of the model from the slot's walls: the walls and the tab's sides are layers
    of their own where the rays say so, also where the camera's depth range is 200 models deep
    (a tolerance of a fraction of the depth range took the gap for one surface there)."""
    model = tab_in_slot(1e-3)
    camera = _deep_camera(model, depth)
    layers, oracle = _layers_and_oracle(renderer, model, camera)
    result = compare_layers(layers.depth, oracle)
    assert result.compared.sum() > 0.25 * result.covered.sum(), result.describe()
    assert result.fraction >= 0.998, result.describe()
    # the gap is seen: pixels where the rays cross the wall and the tab's side both
    assert (layer_count(oracle.depth) >= 6).sum() > 20


@pytest.mark.parametrize("depth", [1.0, 200.0], ids=["fitted", "deep-range"])
def test_coincident_faces_peel_as_one(method, renderer, depth):
    """Two blocks sharing a face, and a third face duplicated over one of their fronts: where a
    ray crosses the shared face or the duplicate, that is one layer (the rays' merge is exact)."""
    left, right = examples.box((-2, -1, -1), (0, 1, 1)), examples.box((0, -1, -1), (2, 1, 1))
    front = (right[0], right[1][10:12])  # the right block's z = 1 face again
    model = examples.assemble({"left": left, "right": right, "sheet": front})
    camera = _deep_camera(model, depth)
    layers, oracle = _layers_and_oracle(renderer, model, camera)
    result = compare_layers(layers.depth, oracle)
    assert result.fraction >= 0.998, result.describe()
    counts = layer_count(layers.depth)
    # 2 surfaces a block, the shared face one of them: 3 where a ray crosses both blocks
    assert set(np.unique(counts[result.compared])) <= {0, 2, 3} and (counts == 3).sum() > 50


def test_tolerance_scales_with_the_model_and_holds_the_back_push():
    """The tolerance is a fraction of the model's diagonal wherever the depth buffer resolves
    that (so a model twice the size has twice the tolerance), never below what the back faces'
    push (``BACK_BIAS``, a window depth) is in eye depth at the far plane, so that coincident
    faces of opposite winding still peel as one."""
    for ortho in (False, True):
        model = tab_in_slot(1e-3)
        camera = Camera.fit(model.positions, "iso", ortho=ortho)
        small = depth_tolerance(camera, model.bounds)
        big = depth_tolerance(camera, 2.0 * model.bounds)
        assert big == pytest.approx(2.0 * small)
        diag = float(np.linalg.norm(np.ptp(model.bounds, axis=0)))
        assert 1e-6 * diag < small < 1e-4 * diag
        for cam in (camera, _deep_camera(model, 1e4)):
            eye = window_to_eye_depth(np.array([1.0 - BACK_BIAS, 1.0]), cam.projection_matrix())
            push = eye[1] - eye[0]
            assert push < depth_tolerance(cam, model.bounds)
        # a deep range costs depth precision: the tolerance grows with it
        assert depth_tolerance(_deep_camera(model, 1e4), model.bounds) > 10 * small
