"""The viewer's rules without a window: keys, camera navigation, overlays, screenshot names."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import project

from blueprint import VIEWS, Camera, InputError, Model
from blueprint.cli import STYLE_NAMES
from blueprint.viewer.overlay import LINE_HEIGHT, band_overlay, help_overlay, screenshot_path
from blueprint.viewer.state import VIEW_KEYS, ViewState


def _model(up: str = "y") -> Model:
    # two boxes side by side: part 0 at x in [0, 1], part 1 at x in [2, 3]
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], np.float32)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], np.int32)
    positions = np.concatenate([corners, corners + [2, 0, 0]])
    return Model.from_arrays(
        positions, np.concatenate([faces, faces + 8]), np.repeat([0, 1], 12), ("left", "right"), up=up
    )


def test_start_is_exactly_the_fitted_named_view():
    model = _model()
    for view in VIEWS:
        state = ViewState.start(STYLE_NAMES, view=view, fov=40.0)
        assert state.at_fit()
        assert state.camera(model, 4 / 3) == Camera.fit(
            model.positions, view, fov=40.0, aspect=4 / 3, up=model.up
        )
    state = ViewState.start(STYLE_NAMES, azimuth=10.0, elevation=20.0, ortho=True)
    assert state.camera(model, 1.5) == Camera.fit(
        model.positions, "iso", azimuth=10.0, elevation=20.0, ortho=True, aspect=1.5
    )


def test_start_rejects_bad_arguments():
    with pytest.raises(InputError, match="unknown view"):
        ViewState.start(STYLE_NAMES, view="sideways")
    with pytest.raises(InputError, match="unknown style"):
        ViewState.start(STYLE_NAMES, style="crayon")
    with pytest.raises(InputError, match="max-layers"):
        ViewState.start(STYLE_NAMES, max_layers=0)


def test_layer_keys_as_in_the_lab():
    state = ViewState.start(STYLE_NAMES, max_layers=3)
    state.more_layers(drawn=3)
    assert state.max_layers == 4
    state.fewer_layers(drawn=4)
    state.fewer_layers(drawn=3)
    assert state.max_layers == 2
    for _ in range(5):
        state.fewer_layers(drawn=1)
    assert state.max_layers == 1
    state.all_layers()
    assert state.max_layers is None
    # from "all", one more / fewer than were drawn
    state.fewer_layers(drawn=7)
    assert state.max_layers == 6
    state.all_layers()
    state.more_layers(drawn=7)
    assert state.max_layers == 8


def test_styles_cycle_and_views_reset_navigation():
    state = ViewState.start(STYLE_NAMES, style="wireframe")
    seen = []
    for _ in STYLE_NAMES:
        state.next_style()
        seen.append(state.style)
    assert seen == ["blueprint", "paper", "transparent", "wireframe"]
    state.orbit(30, 10)
    state.zoom_by(3)
    state.pan_by(5, 5, 100)
    assert not state.at_fit()
    state.set_view("top")
    assert state.at_fit() and state.view == "top" and (state.azimuth, state.elevation) == VIEWS["top"]
    assert VIEW_KEYS == ("iso", "front", "back", "left", "right", "top", "bottom")
    state.toggle_ortho()
    assert state.ortho and state.at_fit()
    assert not state.mask
    state.toggle_mask()
    assert state.mask


@pytest.mark.parametrize("up", ["y", "z"])
@pytest.mark.parametrize("ortho", [False, True])
def test_orbit_turns_around_the_pivot_and_keeps_the_model_between_near_and_far(up, ortho):
    model = _model(up)
    state = ViewState.start(STYLE_NAMES, view="front", ortho=ortho)
    base = state.camera(model, 1.0)
    for dx, dy, steps in ((100, 0, 0), (0, -120, 0), (-300, 50, 8), (40, 400, -12)):
        state.orbit(dx, dy)
        state.zoom_by(steps)
        camera = state.camera(model, 1.0)
        assert camera.target == pytest.approx(base.target)
        # the direction is Camera.fit's for these angles
        fitted = Camera.fit(
            model.positions,
            azimuth=state.azimuth,
            elevation=state.elevation,
            ortho=ortho,
            up=up,
        )
        want = np.subtract(fitted.eye, fitted.target)
        got = np.subtract(camera.eye, camera.target)
        assert got / np.linalg.norm(got) == pytest.approx(want / np.linalg.norm(want), abs=1e-9)
        if ortho:
            assert camera.height == pytest.approx(base.height * state.zoom)
        else:
            base_distance = np.linalg.norm(np.subtract(base.eye, base.target))
            assert np.linalg.norm(got) == pytest.approx(base_distance * state.zoom)
        eye_depth = -(camera.view_matrix() @ np.c_[model.positions, np.ones(len(model.positions))].T)[2]
        assert eye_depth.min() >= camera.near and eye_depth.max() <= camera.far
        assert abs(state.elevation) <= 89.0


def test_pan_moves_the_model_with_the_mouse():
    model = _model()
    for ortho in (False, True):
        state = ViewState.start(STYLE_NAMES, view="iso", ortho=ortho)
        height = 400
        pivot = state.camera(model, 1.5).target
        state.pan_by(100, -60, height)  # right and up on the screen
        ndc = project(pivot, state.camera(model, 1.5))
        # NDC spans the window: pixels = ndc * height / 2 in y, ndc * width / 2 in x
        assert ndc[0] * 1.5 * height / 2 == pytest.approx(100)
        assert ndc[1] * height / 2 == pytest.approx(60)


def test_turntable_spins_the_azimuth():
    state = ViewState.start(STYLE_NAMES, view="front")
    state.spin(2.0)
    assert state.azimuth == pytest.approx(60.0)
    state.spin(5.0)  # 60 + 150 = 210 degrees, kept in [-180, 180)
    assert state.azimuth == pytest.approx(-150.0)


def test_overlay_covers_only_the_band_and_the_help_box():
    clear = help_overlay((300, 120), False)
    assert clear.shape == (120, 300, 4) and (clear == 0).all()
    band = LINE_HEIGHT * 2
    top = band_overlay(clear[:50], ["12.0 fps | 5 layers", "part 1: gear"])
    assert top.shape == (50, 300, 4)
    assert (top[:band, :, 3] >= 170).all() and (top[:band, :, :3] == 255).any()
    assert (top[band:] == 0).all()
    with_help = help_overlay((800, 400), True)
    assert (with_help[LINE_HEIGHT:, :, 3] > 0).any() and (with_help[0, :, 3] == 0).all()
    # a band drawn over the help box keeps the box below it
    assert np.array_equal(band_overlay(with_help[:100], ["x"])[LINE_HEIGHT:], with_help[LINE_HEIGHT:100])


def test_screenshot_names_never_overwrite(tmp_path):
    model = tmp_path / "engine.glb"
    assert screenshot_path(model) == tmp_path / "engine-1.png"
    (tmp_path / "engine-1.png").write_bytes(b"x")
    (tmp_path / "engine-2.png").write_bytes(b"x")
    assert screenshot_path(model) == tmp_path / "engine-3.png"
