"""GPU-free scene data and styles: exact values on tiny hand-computed cases.

Covers ``Camera`` (named views, fit, view / projection matrices), ``corner_normals`` and
``weld_ids``, ``Model`` validation and degenerate faces, and the styles of ``compose.style``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import project

from blueprint import examples
from blueprint.compose.lookup import get_style
from blueprint.compose.style import STYLES, Style, hex_color
from blueprint.errors import InputError
from blueprint.scene.camera import (
    SHEET_CELLS,
    VIEWS,
    Camera,
    clip_to_pixels,
    fit_camera,
    sheet_cameras,
    to_pixels,
    transform,
)
from blueprint.scene.model import Model
from blueprint.scene.normals import corner_normals, weld_ids

S3 = 1 / math.sqrt(3)


def view_direction(camera: Camera) -> np.ndarray:
    """Unit vector from the target to the eye."""
    d = np.subtract(camera.eye, camera.target)
    return d / np.linalg.norm(d)


@pytest.fixture(scope="module")
def gearbox_points() -> np.ndarray:
    return examples.gearbox().positions.astype(np.float64)


# -- camera: hand-computed matrices -------------------------------------------------------------


def test_view_matrix_exact_looking_down_minus_z():
    cam = Camera(eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10)
    expected = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -5], [0, 0, 0, 1]], float)
    np.testing.assert_allclose(cam.view_matrix(), expected, atol=1e-15)


def test_view_matrix_exact_from_the_side():
    # eye on +X looking at the origin: image right is -Z, image up +Y, eye axis +X
    cam = Camera(eye=(5, 0, 0), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10)
    expected = np.array([[0, 0, -1, 0], [0, 1, 0, 0], [1, 0, 0, -5], [0, 0, 0, 1]], float)
    np.testing.assert_allclose(cam.view_matrix(), expected, atol=1e-15)


def test_view_matrix_bit_for_bit_as_numpy_cross_makes_it():
    """The view matrix takes its cross products without ``np.cross`` (slow on 3-vectors): the
    same products and differences, so the same bits, for cameras at every angle and scale."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        eye, target = rng.normal(size=(2, 3)) * 10.0 ** rng.uniform(-3, 3, (2, 1))
        up = tuple(rng.normal(size=3))
        cam = Camera(eye=tuple(eye), target=tuple(target), up=up, near=0.1, far=10.0)
        f = target - eye
        f /= np.linalg.norm(f)
        side = np.cross(f, up)
        side /= np.linalg.norm(side)
        expected = np.eye(4)
        expected[0, :3], expected[1, :3], expected[2, :3] = side, np.cross(side, f), -f
        expected[:3, 3] = -expected[:3, :3] @ eye
        np.testing.assert_array_equal(cam.view_matrix(), expected)


def test_perspective_matrix_exact():
    cam = Camera(eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10, aspect=2, fov=90)
    expected = np.array(
        [[0.5, 0, 0, 0], [0, 1, 0, 0], [0, 0, -11 / 9, -20 / 9], [0, 0, -1, 0]],
        float,
    )
    np.testing.assert_allclose(cam.projection_matrix(), expected, atol=1e-15)
    # near and far planes go to -1 and +1 in NDC
    for z_eye, z_ndc in ((-1.0, -1.0), (-10.0, 1.0)):
        clip = cam.projection_matrix() @ np.array([0, 0, z_eye, 1.0])
        assert clip[2] / clip[3] == pytest.approx(z_ndc, abs=1e-12)


def test_orthographic_matrix_exact():
    cam = Camera(
        eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10, aspect=2, ortho=True, height=4
    )
    expected = np.array(
        [[0.25, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, -2 / 9, -11 / 9], [0, 0, 0, 1]],
        float,
    )
    np.testing.assert_allclose(cam.projection_matrix(), expected, atol=1e-15)


def test_pixel_angle_exact():
    persp = Camera(eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10, fov=90)
    ortho = Camera(eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10, ortho=True, height=4)
    assert persp.pixel_angle(100) == pytest.approx(0.02, abs=1e-15)
    assert ortho.pixel_angle(100) == pytest.approx(0.04, abs=1e-15)


# -- camera: model points to pixels, hand-computed ----------------------------------------------

# eye at +5 on Z looking at the origin; a 200 x 100 picture (aspect 2)
PERSPECTIVE = Camera(eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10, aspect=2, fov=90)
ORTHOGRAPHIC = Camera(
    eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10, aspect=2, ortho=True, height=4
)


def test_to_pixels_perspective_by_hand():
    # tan(45°) = 1: at eye depth d a point (x, y) lies at NDC (x / (2 d), y / d); pixels x right
    # from the left edge, y down from the top: ((ndc_x + 1) 100, (1 - ndc_y) 50)
    points = np.array([[2.0, 1.0, 1.0], [0.0, 0.0, 4.0], [-10.0, -5.0, -5.0], [0.0, 2.0, 3.0]])
    expected = np.array([[125.0, 37.5], [100.0, 50.0], [50.0, 75.0], [100.0, 0.0]])
    # (1 / tan 45° is 1 + 2e-16 in floating point)
    np.testing.assert_allclose(PERSPECTIVE.to_pixels(points, (200, 100)), expected, rtol=0, atol=1e-12)
    with_depth = PERSPECTIVE.to_pixels(points, (200, 100), depth=True)
    np.testing.assert_allclose(with_depth[:, :2], expected, rtol=0, atol=1e-12)
    # NDC z = (f + n) / (f - n) - 2 f n / ((f - n) d): -1 at the near plane, 1 at the far one
    d = 5.0 - points[:, 2]
    np.testing.assert_allclose(with_depth[:, 2], 11 / 9 - 20 / (9 * d), rtol=0, atol=1e-15)
    np.testing.assert_allclose(with_depth[1:3, 2], [-1.0, 1.0], rtol=0, atol=1e-15)


def test_to_pixels_orthographic_by_hand():
    # a view 8 wide and 4 high: NDC (x / 4, y / 2) at any depth
    points = np.array([[2.0, 1.0, 1.0], [2.0, 1.0, -3.0], [-4.0, -2.0, 0.0], [1.0, -0.5, 2.0]])
    expected = np.array([[150.0, 25.0], [150.0, 25.0], [0.0, 100.0], [125.0, 62.5]])
    np.testing.assert_array_equal(ORTHOGRAPHIC.to_pixels(points, (200, 100)), expected)
    # NDC z linear in the eye depth d: -1 at n = 1, 1 at f = 10
    d = 5.0 - points[:, 2]
    z = ORTHOGRAPHIC.to_pixels(points, (200, 100), depth=True)[:, 2]
    np.testing.assert_allclose(z, 2 * (d - 1) / 9 - 1, rtol=0, atol=1e-15)


def test_to_pixels_from_the_side_and_in_any_shape():
    # eye on +X: image right is -Z, up +Y; orthographic 4 high on a 100 x 100 picture
    side = Camera(eye=(5, 0, 0), target=(0, 0, 0), up=(0, 1, 0), near=1, far=10, ortho=True, height=4)
    points = np.array([[[0.0, 0.0, -1.0], [3.0, 1.0, 0.0]], [[0.0, -2.0, 2.0], [-1.0, 0.0, 0.0]]])
    expected = np.array([[[75.0, 50.0], [50.0, 25.0]], [[0.0, 100.0], [50.0, 50.0]]])
    pixels = side.to_pixels(points, (100, 100))
    assert pixels.shape == (2, 2, 2) and pixels.dtype == np.float64
    np.testing.assert_array_equal(pixels, expected)
    # the function over matrices is the method's, and its two steps make it
    view, projection = side.view_matrix(), side.projection_matrix()
    np.testing.assert_array_equal(to_pixels(points, view, projection, (100, 100)), expected)
    np.testing.assert_array_equal(clip_to_pixels(transform(points, projection @ view), (100, 100)), expected)
    # rows from the bottom (OpenGL's window coordinates) are the same rows counted from the other edge
    bottom = clip_to_pixels(transform(points, projection @ view), (100, 100), origin="bottom")
    np.testing.assert_array_equal(bottom, np.stack([expected[..., 0], 100 - expected[..., 1]], -1))
    with pytest.raises(ValueError, match="origin"):
        clip_to_pixels(transform(points, projection @ view), (100, 100), origin="left")


def test_transform_is_the_matrix_on_homogeneous_points():
    rng = np.random.default_rng(3)
    matrix, points = rng.normal(size=(4, 4)), rng.normal(size=(5, 3))
    expected = np.array([matrix @ np.r_[p, 1.0] for p in points])
    np.testing.assert_allclose(transform(points, matrix), expected, rtol=1e-14, atol=1e-14)
    assert transform(points.astype(np.float32), matrix).dtype == np.float64


def test_a_point_in_the_eyes_plane_stays_finite():
    # w = 0 in perspective: the divide takes w = 1 there instead of making infinities
    pixels = PERSPECTIVE.to_pixels(np.array([[1.0, 1.0, 5.0], [2.0, 1.0, 1.0]]), (200, 100))
    assert np.isfinite(pixels).all()
    np.testing.assert_allclose(pixels[1], [125.0, 37.5], rtol=0, atol=1e-12)


# -- camera: named views ------------------------------------------------------------------------

# expected unit direction from the target to the eye, per up axis
DIRECTIONS = {
    "y": {
        "iso": (S3, S3, S3),
        "front": (0, 0, 1),
        "back": (0, 0, -1),
        "left": (-1, 0, 0),
        "right": (1, 0, 0),
        "top": (0, 1, 0),
        "bottom": (0, -1, 0),
    },
    "z": {
        "iso": (S3, -S3, S3),
        "front": (0, -1, 0),
        "back": (0, 1, 0),
        "left": (-1, 0, 0),
        "right": (1, 0, 0),
        "top": (0, 0, 1),
        "bottom": (0, 0, -1),
    },
}


def test_views_table_is_complete():
    assert set(VIEWS) == set(DIRECTIONS["y"]) == set(DIRECTIONS["z"])


@pytest.mark.parametrize("up", ["y", "z"])
@pytest.mark.parametrize("view", list(VIEWS))
def test_named_view_direction_exact(gearbox_points, view, up):
    cam = Camera.fit(gearbox_points, view, up=up)
    np.testing.assert_allclose(view_direction(cam), DIRECTIONS[up][view], atol=1e-12)
    # a proper rotation (no mirror image): right x up = towards the viewer
    rotation = cam.view_matrix()[:3, :3]
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(rotation) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("up", ["y", "z"])
@pytest.mark.parametrize("ortho", [False, True], ids=["perspective", "ortho"])
@pytest.mark.parametrize("view", list(VIEWS))
def test_fit_puts_every_point_inside_the_margin(gearbox_points, view, ortho, up):
    margin, aspect = 0.05, 4 / 3
    cam = Camera.fit(gearbox_points, view, ortho=ortho, aspect=aspect, margin=margin, up=up)
    ndc = project(gearbox_points, cam)
    fill = 1 - 2 * margin
    reach = np.abs(ndc[:, :2]).max(axis=0)
    assert (reach <= fill + 1e-9).all(), f"points outside the margin: {reach}"
    # tight: the model touches the margin on at least one axis
    assert reach.max() == pytest.approx(fill, abs=1e-9)
    # between the near and far planes
    assert (ndc[:, 2] > -1).all() and (ndc[:, 2] < 1).all()
    if ortho:
        # orthographic drawings sit exactly in the middle of the image
        np.testing.assert_allclose(ndc[:, :2].min(axis=0) + ndc[:, :2].max(axis=0), 0, atol=1e-9)


@pytest.mark.parametrize("ortho", [False, True], ids=["perspective", "ortho"])
@pytest.mark.parametrize("up", ["y", "z"])
def test_top_view_keeps_the_front_at_the_bottom(up, ortho):
    right, up_axis, front = {
        "y": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
        "z": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),
    }[up]
    points = np.array([front, np.negative(front), right, np.negative(right), up_axis], float)
    cam = Camera.fit(points, "top", up=up, ortho=ortho)
    ndc = project(points, cam)
    assert ndc[0, 1] < ndc[1, 1], "front is not below the back"
    assert ndc[0, 1] == pytest.approx(-ndc[1, 1], abs=1e-9)
    assert ndc[2, 0] > ndc[3, 0], "right is not on the right"
    np.testing.assert_allclose(ndc[:2, 0], 0, atol=1e-12)  # front and back on the centre line


def test_front_view_of_z_up_model_shows_z_upwards():
    points = np.array([[0, 0, 0], [0, 0, 10], [5, 0, 0]], float)
    cam = Camera.fit(points, "front", up="z", ortho=True)
    ndc = project(points, cam)
    assert ndc[1, 1] > ndc[0, 1]  # +Z is up in the image
    assert ndc[2, 0] > ndc[0, 0]  # +X is to the right
    np.testing.assert_allclose(cam.up, (0, 0, 1), atol=1e-12)


def test_azimuth_and_elevation_override_the_view(gearbox_points):
    cam = Camera.fit(gearbox_points, "front", azimuth=90.0)
    np.testing.assert_allclose(view_direction(cam), (1, 0, 0), atol=1e-12)
    cam = Camera.fit(gearbox_points, "front", elevation=90.0)
    np.testing.assert_allclose(view_direction(cam), (0, 1, 0), atol=1e-12)


def test_fit_camera_is_camera_fit_at_the_image_aspect_and_the_model_up_axis():
    """The one camera fit of drawings: a model's positions and up axis, an image's aspect; bare
    points are Y-up unless told."""
    model = examples.gearbox()
    zup = Model.from_arrays(model.positions, model.faces, up="z")
    for m in (model, zup):
        assert fit_camera(m, (300, 200), "front", azimuth=10.0, elevation=5.0, fov=40.0) == Camera.fit(
            m.positions, "front", azimuth=10.0, elevation=5.0, fov=40.0, aspect=1.5, up=m.up
        )
    assert fit_camera(zup.positions, (100, 400), "top", ortho=True) == Camera.fit(
        zup.positions, "top", ortho=True, aspect=0.25, up="y"
    )
    assert fit_camera(model, (64, 64), margin=0.2, up="z") == Camera.fit(model.positions, margin=0.2, up="z")


def test_sheet_cameras_share_one_orthographic_scale():
    model = examples.gearbox()
    cameras = sheet_cameras(model, (200, 150))
    assert set(cameras) == set(SHEET_CELLS)
    heights = {cameras[v].height for v in ("top", "front", "right")}
    assert len(heights) == 1 and all(cameras[v].ortho for v in ("top", "front", "right"))
    assert cameras["iso"] == fit_camera(model, (200, 150), "iso", margin=0.08)


def test_fit_rejects_bad_arguments(gearbox_points):
    with pytest.raises(InputError, match="unknown view 'sideways'"):
        Camera.fit(gearbox_points, "sideways")
    for fov in (0.0, 180.0, -5.0):
        with pytest.raises(InputError, match="field of view"):
            Camera.fit(gearbox_points, fov=fov)
    with pytest.raises(InputError, match="margin"):
        Camera.fit(gearbox_points, margin=0.5)


def test_fit_rejects_non_finite_angles(gearbox_points):
    """NaN or infinite azimuth / elevation must be an InputError (the CLI passes them through:
    ``--azimuth inf`` raised ValueError from math.cos, ``--azimuth nan`` drew an empty image,
    ``--elevation nan`` silently became a top view)."""
    wrong = []
    # an infinite elevation may be clamped to +-90 like any other out-of-range elevation
    cases = [("azimuth", math.nan), ("azimuth", math.inf), ("azimuth", -math.inf), ("elevation", math.nan)]
    for name, value in cases:
        try:
            Camera.fit(gearbox_points, **{name: value})
        except InputError:
            continue
        except Exception as exc:  # noqa: BLE001 - reporting the wrong exception type
            wrong.append(f"{name}={value}: {type(exc).__name__}: {exc}")
        else:
            wrong.append(f"{name}={value}: accepted")
    assert not wrong, "non-finite camera angles not rejected with InputError: " + "; ".join(wrong)


# -- corner normals and welding -----------------------------------------------------------------

CUBE_FACE_NORMALS = np.repeat(
    np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], np.float32), 2, axis=0
)


@pytest.mark.parametrize("crease", [0.0, 30.0, 89.0])
def test_cube_keeps_face_normals_below_90_degrees(crease):
    vertices, faces = examples.box((0, 0, 0), (1, 1, 1))
    normals = corner_normals(vertices, faces, crease)
    assert normals.shape == (12, 3, 3) and normals.dtype == np.float32
    np.testing.assert_array_equal(normals, np.repeat(CUBE_FACE_NORMALS[:, None, :], 3, axis=1))


def test_cube_as_triangle_soup_keeps_face_normals():
    vertices, faces = examples.box((0, 0, 0), (1, 1, 1))
    soup = vertices[faces].reshape(-1, 3)
    normals = corner_normals(soup, np.arange(36).reshape(12, 3), 30.0)
    np.testing.assert_array_equal(normals, np.repeat(CUBE_FACE_NORMALS[:, None, :], 3, axis=1))


def _fold(theta_deg: float, flip_second: bool = False):
    """Two unit right triangles sharing the edge (0,0,0)-(1,0,0), folded by ``theta``:
    A has normal (0,0,1), B has normal (0, sin t, cos t), both with doubled area 1."""
    t = math.radians(theta_deg)
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -math.cos(t), math.sin(t)]], float)
    b = [1, 3, 0] if flip_second else [1, 0, 3]
    return positions, np.array([[0, 1, 2], b])


def test_fold_within_crease_angle_is_smoothed_exactly():
    positions, faces = _fold(20.0)
    normals = corner_normals(positions, faces, 30.0)
    shared = (0.0, math.sin(math.radians(10)), math.cos(math.radians(10)))
    # face A: corners at vertices 0, 1 (shared edge) and 2 (its own)
    np.testing.assert_allclose(normals[0], [shared, shared, (0, 0, 1)], atol=1e-6)
    # face B: corners at vertices 1, 0 (shared edge) and 3 (its own)
    own_b = (0.0, math.sin(math.radians(20)), math.cos(math.radians(20)))
    np.testing.assert_allclose(normals[1], [shared, shared, own_b], atol=1e-6)


def test_fold_beyond_crease_angle_stays_flat():
    positions, faces = _fold(20.0)
    normals = corner_normals(positions, faces, 15.0)
    own_b = (0.0, math.sin(math.radians(20)), math.cos(math.radians(20)))
    np.testing.assert_allclose(normals[0], [(0, 0, 1)] * 3, atol=1e-7)
    np.testing.assert_allclose(normals[1], [own_b] * 3, atol=1e-7)


def test_flipped_face_still_smooths_and_keeps_its_orientation():
    positions, faces = _fold(20.0, flip_second=True)
    normals = corner_normals(positions, faces, 30.0)
    shared = np.array([0.0, math.sin(math.radians(10)), math.cos(math.radians(10))])
    np.testing.assert_allclose(normals[0, :2], [shared, shared], atol=1e-6)
    # B is wound the other way: its corners (at vertices 1, 3, 0) face the other way
    own_b = np.array([0.0, math.sin(math.radians(20)), math.cos(math.radians(20))])
    np.testing.assert_allclose(normals[1], [-shared, -own_b, -shared], atol=1e-6)


@pytest.fixture(scope="module")
def cylinder():
    segments = 64
    vertices, faces = examples.prism([1.0], 2.0, segments)
    return vertices, faces, segments


def test_fine_cylinder_side_is_smooth_and_caps_flat(cylinder):
    vertices, faces, n = cylinder
    normals = corner_normals(vertices, faces, 30.0).astype(np.float64)
    side = 2 * n
    # every corner of the side at the same vertex has the same normal: no crease lines there
    by_vertex: dict[int, list[np.ndarray]] = {}
    for f in range(side):
        for j in range(3):
            by_vertex.setdefault(int(faces[f, j]), []).append(normals[f, j])
    for vertex, group in by_vertex.items():
        np.testing.assert_allclose(group, [group[0]] * len(group), atol=1e-6, err_msg=f"vertex {vertex}")
        radial = vertices[vertex, :2] / np.linalg.norm(vertices[vertex, :2])
        # horizontal, and within half a segment of the radial direction
        assert abs(group[0][2]) < 1e-6
        angle = math.degrees(math.acos(min(1.0, float(group[0][:2] @ radial))))
        assert angle <= 180 / n + 1e-6
    # area weighting, by hand: vertex i touches two triangles of segment i, one of segment i-1
    step = 2 * math.pi / n
    i = 5
    mid = lambda k: np.array([math.cos((k + 0.5) * step), math.sin((k + 0.5) * step), 0.0])  # noqa: E731
    expected = 2 * mid(i) + mid(i - 1)
    np.testing.assert_allclose(by_vertex[i][0], expected / np.linalg.norm(expected), atol=1e-6)
    # caps are not smoothed into the side (90 degrees)
    caps = normals[side:]
    np.testing.assert_allclose(caps[:n], np.tile([0, 0, -1.0], (n, 3, 1)), atol=1e-6)
    np.testing.assert_allclose(caps[n:], np.tile([0, 0, 1.0], (n, 3, 1)), atol=1e-6)


def test_cylinder_with_flipped_faces_smooths_the_same(cylinder):
    vertices, faces, n = cylinder
    reference = corner_normals(vertices, faces, 30.0)
    flipped = faces.copy()
    odd = np.arange(1, 2 * n, 2)
    flipped[odd] = flipped[odd][:, [0, 2, 1]]
    normals = corner_normals(vertices, flipped, 30.0)
    keep = np.setdiff1d(np.arange(len(faces)), odd)
    np.testing.assert_allclose(normals[keep], reference[keep], atol=1e-6)
    np.testing.assert_allclose(normals[odd][:, [0, 2, 1]], -reference[odd], atol=1e-6)


def test_weld_ids_merges_a_soup_into_eight_cube_corners():
    vertices, faces = examples.box((0, 0, 0), (1, 1, 1))
    soup = vertices[faces].reshape(-1, 3)
    ids = weld_ids(soup, np.arange(36).reshape(12, 3))
    assert ids.shape == (12, 3)
    assert len(np.unique(ids)) == 8
    # same id exactly where the original indices agree
    np.testing.assert_array_equal(
        ids[:, :, None] == ids.reshape(-1)[None, None, :],
        (faces[:, :, None] == faces.reshape(-1)[None, None, :]),
    )


def test_weld_ids_tolerance_is_relative_to_the_diagonal():
    base = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    for scale in (1e-3, 1.0, 1e4):
        near = np.vstack([base, base + [0, 0, 1e-9]]) * scale  # 1e-9 of the size: same point
        far = np.vstack([base, base + [0, 0, 1e-3]]) * scale  # 1e-3 of the size: different
        tris = np.array([[0, 1, 2], [3, 4, 5]])
        assert (weld_ids(near, tris)[0] == weld_ids(near, tris)[1]).all(), scale
        assert (weld_ids(far, tris)[0] != weld_ids(far, tris)[1]).all(), scale


def test_weld_ids_merges_points_closer_than_the_tolerance_at_any_position():
    """Two copies of a vertex 1e-12 apart (a million times below the 1e-6 tolerance) must weld
    even where they straddle a rounding cell of ``np.round(p / (diag * rel_tol))``."""
    tris = np.array([[0, 1, 2], [3, 4, 5]])
    diag = math.sqrt(2.0)
    q = diag * 1e-6
    x = (round(0.5 / q) + 0.5) * q  # on a cell boundary of the rounding grid
    positions = np.array(
        [[0, 0, 0], [1, 0, 0], [x - 1e-12, 1, 0], [1, 1, 0], [0, 1, 0], [x + 1e-12, 1, 0]], float
    )
    assert float(np.linalg.norm(np.ptp(positions, axis=0))) == pytest.approx(diag, rel=1e-15)
    ids = weld_ids(positions, tris)
    assert ids[0, 2] == ids[1, 2], "vertices 2e-12 apart were not welded"


# -- model ------------------------------------------------------------------------------------


def test_model_from_arrays_defaults():
    vertices, faces = examples.box((0, 0, 0), (1, 2, 3))
    m = Model.from_arrays(vertices, faces)
    assert m.positions.dtype == np.float32 and m.faces.dtype == np.int32
    assert m.face_part.dtype == np.int32 and (m.face_part == 0).all()
    assert m.part_names == ("part0",) and m.up == "y" and m.triangle_count == 12
    np.testing.assert_array_equal(m.bounds, [[0, 0, 0], [1, 2, 3]])


def test_model_bounds_ignore_unused_vertices_and_counts_per_part():
    vertices, faces = examples.box((0, 0, 0), (1, 2, 3))
    positions = np.vstack([vertices, [[100, 100, 100]]])
    m = Model.from_arrays(positions, faces, np.r_[np.zeros(4), np.ones(8)], ("a", "b"))
    np.testing.assert_array_equal(m.bounds, [[0, 0, 0], [1, 2, 3]])
    np.testing.assert_array_equal(m.part_triangle_counts(), [4, 8])


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(positions=np.zeros((3, 2))), "positions must be"),
        (dict(faces=np.zeros((1, 4), np.int32)), "faces must be"),
        (dict(face_part=np.zeros(2, np.int32)), "face_part"),
        (dict(up="x"), "up must be"),
    ],
    ids=["positions-shape", "faces-shape", "face-part-length", "up-axis"],
)
def test_model_rejects_malformed_arrays(kwargs, message):
    args = dict(
        positions=np.zeros((3, 3), np.float32),
        faces=np.array([[0, 1, 2]], np.int32),
        face_part=np.zeros(1, np.int32),
        part_names=("p",),
    )
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        Model(**args)


def test_model_rejects_face_indices_out_of_range():
    """Index validation lives only in the loader: a Model built from arrays with index -1 draws
    the last vertex silently, and index V raises IndexError deep in the renderer."""
    positions = np.eye(3, dtype=np.float32)
    for bad in ([0, 1, 3], [0, 1, -1]):
        with pytest.raises(ValueError, match="face"):
            Model.from_arrays(positions, np.array([bad]))


def test_degenerate_faces_exact():
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], np.float32)
    faces = np.array([[0, 1, 2], [0, 1, 3], [0, 0, 2], [2, 1, 0]])  # ok, collinear, repeated, ok
    m = Model.from_arrays(positions, faces)
    np.testing.assert_array_equal(m.degenerate_faces(), [False, True, True, False])


@pytest.mark.parametrize("scale", [1e-12, 1e-6, 1.0, 1e6])
def test_degenerate_faces_do_not_depend_on_units(scale):
    """A box is a box in any unit. The area test compares squared doubled area (length^4) with
    ``(scale * 1e-12) ** 2`` (length^2), so small-unit models lose faces: at 1e-12 8 of 12."""
    vertices, faces = examples.box((0, 0, 0), (1, 2, 3))
    m = Model.from_arrays(vertices * scale, faces)
    assert not m.degenerate_faces().any()


@pytest.mark.parametrize("threads", [1, 3])
def test_one_pass_over_the_faces_measures_what_the_checks_read(threads, monkeypatch):
    """``measure_faces`` (blocks of faces over the threads) against each measure made apart: the
    degenerate faces, each face's lowest and highest corner, and coincidence keys that copies
    of a triangle share (whatever corner they start at) and no other face does."""
    from blueprint import settings
    from blueprint.scene import model as model_module

    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(model_module, "_FACES", 7)
    rng = np.random.default_rng(3)
    positions = rng.normal(size=(60, 3)).astype(np.float32)
    faces = rng.integers(0, 60, (50, 3))
    faces[:4] = faces[4]  # copies of one triangle, one turned to start at another corner
    faces[3] = np.roll(faces[4], 1)
    faces[10, 2] = faces[10, 0]  # a repeated vertex
    m = Model.from_arrays(positions, faces)
    keys = m.measure_faces(keys=True, extremes=True)
    corners = positions[faces].astype(np.float64)
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    repeated = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])
    np.testing.assert_array_equal(m.degenerate_faces(), repeated | ((cross * cross).sum(axis=1) == 0))
    low, high = m.face_extremes()
    np.testing.assert_array_equal(low, positions[faces].min(axis=1))
    np.testing.assert_array_equal(high, positions[faces].max(axis=1))
    np.testing.assert_allclose(keys[:5], keys[4], rtol=1e-12)
    assert len(np.unique(keys[5:])) == 45 and not np.isin(keys[5:], keys[:5]).any()
    # the extremes are given once, then made anew where asked again
    np.testing.assert_array_equal(m.face_extremes()[0], low)


# -- styles ---------------------------------------------------------------------------------------


def test_hex_color_exact():
    assert hex_color("#12457a") == (0x12 / 255, 0x45 / 255, 0x7A / 255, 1.0)
    assert hex_color("ffffff", 0.5) == (1.0, 1.0, 1.0, 0.5)


@pytest.mark.parametrize("text", ["#12345", "#1234567", "blue", "#gg0000", ""])
def test_hex_color_rejects_bad_colours(text):
    with pytest.raises(InputError, match="#rrggbb"):
        hex_color(text)


@pytest.mark.parametrize(
    "field, value",
    [
        ("hidden_opacity", 1.5),
        ("hidden_opacity", -0.1),
        ("hidden_opacity", math.nan),
        ("fade", 2.0),
        ("fade", math.nan),
        ("grid", -1.0),
    ],
)
def test_style_rejects_out_of_range_values(field, value):
    with pytest.raises(InputError, match=field.split("_")[0]):
        STYLES["paper"].with_options(**{field: value})


@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_style_rejects_non_finite_grid(value):
    """``grid`` is checked with ``self.grid < 0`` only, so NaN and inf pass (``--grid nan`` and
    ``--grid inf`` exit 0)."""
    with pytest.raises(InputError, match="grid"):
        Style("x", paper=None, ink=(0, 0, 0, 1), hidden_ink=(0, 0, 0, 1), grid=value)


def test_layer_inks_exact():
    inks = STYLES["blueprint"].layer_inks(3)
    hidden = hex_color("#bfe0ff")
    np.testing.assert_allclose(
        inks,
        [(1, 1, 1, 1), (*hidden[:3], 0.9), (*hidden[:3], 0.9 * 0.85)],
        atol=1e-7,
    )
    assert inks.dtype == np.float32 and inks.shape == (3, 4)
    assert STYLES["wireframe"].layer_inks(4)[:, 3].tolist() == [1, 0.5, 0.5, 0.5]


def test_get_style():
    assert get_style("paper") is STYLES["paper"]
    gridded = get_style("blueprint", 16)
    assert gridded.grid == 16.0 and gridded.paper == STYLES["blueprint"].paper
    assert STYLES["blueprint"].grid == 0.0  # the preset itself is untouched
    custom = Style("mine", paper=None, ink=(0, 0, 0, 1), hidden_ink=(0, 0, 0, 1))
    assert get_style(custom) is custom
    with pytest.raises(InputError, match="unknown style 'neon'"):
        get_style("neon")


def test_weld_components_equal_scipy_connected_components():
    # the numpy components in weld against scipy's, on random chains and clusters of pairs
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from blueprint.scene.weld import connected_components_of

    rng = np.random.default_rng(7)
    for n, pairs in ((50, 40), (300, 100), (1000, 900)):
        i, j = rng.integers(0, n, pairs), rng.integers(0, n, pairs)
        ours = connected_components_of(np.arange(n), i, j)
        _, theirs = connected_components(coo_matrix((np.ones(pairs), (i, j)), shape=(n, n)), directed=False)
        # the same partition: labels map one to one
        assert len(set(zip(ours.tolist(), theirs.tolist(), strict=True))) == len(set(theirs.tolist()))
        assert len(set(ours.tolist())) == len(set(theirs.tolist()))
