"""Per-view edge classification, projection and near-plane clipping."""

import itertools

import numpy as np
import pytest
import trimesh

from blueprint.scene.camera import Camera
from blueprint.silhouette import (
    BORDER,
    CREASE,
    SILHOUETTE,
    build_adjacency,
    classify_edges,
    mesh_sharp_edges,
    silhouette_image,
)

W, H = 160, 120

# Cube [-1, 1]^3: corner index = 4x + 2y + z (bits); outward-wound triangles.
CORNERS = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))
CUBE_FACES = np.array(
    [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
     [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
)  # fmt: skip


def camera_basis(eye, target, up):
    forward = np.subtract(target, eye, dtype=float)
    forward /= np.linalg.norm(forward)
    side = np.cross(forward, up)
    side /= np.linalg.norm(side)
    return side, np.cross(side, forward), forward


def look_at(eye, target, up):
    side, true_up, forward = camera_basis(eye, target, up)
    view = np.eye(4)
    view[:3, :3] = [side, true_up, -forward]
    view[:3, 3] = -view[:3, :3] @ eye
    return view


def perspective(fovy_deg, aspect, near, far):
    f = 1.0 / np.tan(np.radians(fovy_deg) / 2.0)
    return np.array(
        [[f / aspect, 0, 0, 0], [0, f, 0, 0],
         [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)], [0, 0, -1, 0]]
    )  # fmt: skip


def ortho(half_w, half_h, near, far):
    return np.array(
        [[1 / half_w, 0, 0, 0], [0, 1 / half_h, 0, 0],
         [0, 0, -2 / (far - near), -(far + near) / (far - near)], [0, 0, 0, 1]]
    )  # fmt: skip


def hand_project(points, eye, target, up, fovy_deg=None, half_w=None, half_h=None):
    """Pixel coordinates from the camera basis directly, without any 4x4 matrix."""
    side, true_up, forward = camera_basis(eye, target, up)
    rel = np.asarray(points) - eye
    x, y = rel @ side, rel @ true_up
    if fovy_deg is not None:
        f = 1.0 / np.tan(np.radians(fovy_deg) / 2.0)
        depth = rel @ forward
        x_ndc, y_ndc = f / (W / H) * x / depth, f * y / depth
    else:
        x_ndc, y_ndc = x / half_w, y / half_h
    return np.stack([(x_ndc + 1) * W / 2, (1 - y_ndc) * H / 2], axis=-1)


def corner_pairs(segments3d):
    """Each segment as a frozenset of the two cube corner indices it joins."""
    index = lambda p: int(4 * (p[0] > 0) + 2 * (p[1] > 0) + (p[2] > 0))  # noqa: E731
    return {frozenset((index(a), index(b))) for a, b in segments3d}


# Seen from the +x+y+z octant the outline is the hexagon through every corner but
# 7 = (+,+,+) and 0 = (-,-,-); the other six box edges meet at those two corners.
HEXAGON = {frozenset(p) for p in [(4, 6), (6, 2), (2, 3), (3, 1), (1, 5), (5, 4)]}
INNER = {frozenset(p) for p in [(7, 6), (7, 5), (7, 3), (0, 4), (0, 2), (0, 1)]}
EYE, TARGET, UP = np.array([5.0, 5.0, 5.0]), np.zeros(3), np.array([0.0, 0.0, 1.0])


@pytest.mark.parametrize("projection_kind", ["perspective", "ortho"])
def test_cube_iso_view(projection_kind):
    adj = build_adjacency(CORNERS, CUBE_FACES)
    view = look_at(EYE, TARGET, UP)
    if projection_kind == "perspective":
        proj, lens = perspective(40.0, W / H, 0.1, 100.0), {"fovy_deg": 40.0}
    else:
        proj, lens = ortho(3.0, 2.25, 0.1, 100.0), {"half_w": 3.0, "half_h": 2.25}
    edges = classify_edges(adj, view, proj, W, H)

    assert len(edges.kind) == 12 and edges.kind.dtype == np.uint8
    assert corner_pairs(edges.segments3d[edges.kind == SILHOUETTE]) == HEXAGON
    assert corner_pairs(edges.segments3d[edges.kind == CREASE]) == INNER
    assert not (edges.kind == BORDER).any()
    np.testing.assert_allclose(
        edges.segments2d, hand_project(edges.segments3d, EYE, TARGET, UP, **lens), atol=1e-9
    )
    # Silhouette faces are (front, back): front ones face +x, +y or +z.
    sil_faces = edges.faces[edges.kind == SILHOUETTE]
    assert (adj.face_normals[sil_faces[:, 0]].sum(axis=1) == 1).all()
    assert (adj.face_normals[sil_faces[:, 1]].sum(axis=1) == -1).all()


def test_crease_angle_threshold():
    adj = build_adjacency(CORNERS, CUBE_FACES)
    view, proj = look_at(EYE, TARGET, UP), perspective(40.0, W / H, 0.1, 100.0)
    assert (classify_edges(adj, view, proj, W, H, crease_angle=89.0).kind == CREASE).sum() == 6
    assert (classify_edges(adj, view, proj, W, H, crease_angle=91.0).kind == CREASE).sum() == 0


def paddle_wheel(angles):
    """Triangles sharing the axis edge (0,0,-1)-(0,0,1), one per angle, all wound a -> b."""
    tips = np.stack([np.cos(angles), np.sin(angles), np.ones_like(angles)], axis=1)
    positions = np.vstack([[[0, 0, -1], [0, 0, 1]], tips])
    faces = np.stack([np.zeros(len(angles)), np.ones(len(angles)), 2 + np.arange(len(angles))], 1)
    return positions, faces.astype(np.int64)


def test_non_manifold_axis_edge_is_silhouette_when_fins_face_both_ways():
    # Fin k has normal (-sin, cos, 0) * 2; seen from +x it faces the eye iff sin(angle) < 0,
    # so fins 0-3 face away and fins 4-7 face the eye.
    positions, faces = paddle_wheel(2 * np.pi * np.arange(8) / 8 + 0.2)
    adj = build_adjacency(positions, faces)
    view = look_at(np.array([5.0, 0, 0]), np.zeros(3), np.array([0, 0, 1.0]))
    edges = classify_edges(adj, view, perspective(40.0, W / H, 0.1, 100.0), W, H)
    assert (edges.kind == BORDER).sum() == 16
    axis = np.flatnonzero(edges.kind == SILHOUETTE)
    assert axis.size == 1
    np.testing.assert_array_equal(edges.segments3d[axis[0]], [[0, 0, -1], [0, 0, 1]])
    np.testing.assert_array_equal(edges.faces[axis[0]], [4, 0])


def test_non_manifold_axis_edge_is_not_silhouette_when_fins_all_face_away():
    positions, faces = paddle_wheel(np.pi * np.arange(4) / 4 + 0.2)
    adj = build_adjacency(positions, faces)
    view = look_at(np.array([5.0, 0, 0]), np.zeros(3), np.array([0, 0, 1.0]))
    edges = classify_edges(adj, view, perspective(40.0, W / H, 0.1, 100.0), W, H)
    np.testing.assert_array_equal(edges.kind, np.full(8, BORDER))


def closed_cylinder(n=64):
    """Radius 1, z in [-1, 1]; side quad i spans angles 2 pi i / n to 2 pi (i + 1) / n."""
    theta = 2 * np.pi * np.arange(n) / n
    ring = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    positions = np.vstack([np.c_[ring, -np.ones(n)], np.c_[ring, np.ones(n)], [[0, 0, -1], [0, 0, 1]]])
    i, j = np.arange(n), (np.arange(n) + 1) % n
    side = np.r_[np.c_[i, j, n + j], np.c_[i, n + j, n + i]]
    caps = np.r_[np.c_[np.full(n, 2 * n), j, i], np.c_[np.full(n, 2 * n + 1), n + i, n + j]]
    return positions, np.r_[side, caps]


@pytest.mark.parametrize(
    ("projection_kind", "generator_deg", "front_sides"),
    # Perspective from (5, 0, 2): side face i faces the eye iff 5 cos(mid angle) > cos(pi/64),
    # true for 14 faces each side of the x axis, so the outline generators sit at vertex
    # angles +-78.75 deg. Orthographic: iff cos(mid angle) > 0, generators at +-90 deg.
    [("perspective", 78.75, 28), ("ortho", 90.0, 32)],
)
def test_closed_cylinder_silhouette(projection_kind, generator_deg, front_sides):
    positions, faces = closed_cylinder(64)
    adj = build_adjacency(positions, faces)
    view = look_at(np.array([5.0, 0, 2]), np.zeros(3), np.array([0, 0, 1.0]))
    proj = perspective(40.0, W / H, 0.1, 100) if projection_kind == "perspective" else None
    edges = classify_edges(adj, view, ortho(3, 2.25, 0.1, 100) if proj is None else proj, W, H)

    sil = edges.segments3d[edges.kind == SILHOUETTE]
    # Two generators, the top rim where the sides face away (the cap faces the eye) and the
    # bottom rim where the sides face the eye (the cap faces away).
    assert len(sil) == 2 + (64 - front_sides) + front_sides
    vertical = sil[sil[:, 0, 2] != sil[:, 1, 2]]
    angles = np.degrees(np.arctan2(vertical[:, 0, 1], vertical[:, 0, 0]))
    np.testing.assert_allclose(np.sort(angles), [-generator_deg, generator_deg], atol=1e-9)
    np.testing.assert_allclose(np.abs(vertical[:, :, 2]), 1.0)
    rim_x = sil[sil[:, 0, 2] == sil[:, 1, 2]][:, :, 0].mean(axis=1)
    rim_z = sil[sil[:, 0, 2] == sil[:, 1, 2]][:, 0, 2]
    assert (rim_z == 1).sum() == 64 - front_sides and (rim_x[rim_z == 1] < 0.2).all()
    assert (rim_z == -1).sum() == front_sides and (rim_x[rim_z == -1] > 0).all()
    # Every other rim edge is a 90-degree crease; the 5.6-degree generators are not.
    assert (edges.kind == CREASE).sum() == 64


def test_near_plane_clipping():
    # Camera at the origin looking down -z with near = 1. The triangle's apex is behind the
    # camera, so its two slanted edges are cut at z = -1 and its far edge is kept whole.
    positions = np.array([[-1.0, -1, -5], [1, -1, -5], [0, -1, 5], [0, -1, 6], [1, -1, 6]])
    faces = np.array([[0, 1, 2], [2, 3, 4]])
    adj = build_adjacency(positions, faces)
    proj = perspective(90.0, W / H, 1.0, 100.0)
    edges = classify_edges(adj, np.eye(4), proj, W, H)
    assert (edges.kind == BORDER).all() and len(edges.kind) == 3
    ends = edges.segments3d.reshape(-1, 3)
    near_ends = ends[np.isclose(ends[:, 2], -1.0, rtol=0, atol=1e-12)]
    # The slanted edges run from (+-1, -1, -5) to (0, -1, 5): at z = -1 they are at x = +-0.6.
    np.testing.assert_allclose(np.sort(near_ends[:, 0]), [-0.6, 0.6], atol=1e-12)
    assert (ends[:, 2] <= -1.0 + 1e-12).all()
    expected = hand_project(edges.segments3d, np.zeros(3), [0, 0, -1], [0, 1, 0], fovy_deg=90.0)
    np.testing.assert_allclose(edges.segments2d, expected, atol=1e-9)


def test_segments_in_front_of_the_near_plane_are_projected_without_a_copy():
    """Where no segment reaches the near plane (most drawings), the endpoints given are the
    endpoints kept, not copied; where one does, the others are kept as they were."""
    from blueprint.silhouette.edges import _projected

    proj = perspective(90.0, W / H, 1.0, 100.0)
    segments = np.array([[[-1.0, -1, -5], [1, -1, -5]], [[0, 1, -3], [0, 2, -4]]])
    model, pixels, keep = _projected(segments, np.eye(4), proj, (W, H))
    assert model is segments and keep.tolist() == [0, 1] and pixels.shape == (2, 2, 2)
    crossing = np.concatenate([segments, [[[0.0, -1, -5], [0, -1, 5]]]])
    model, _, keep = _projected(crossing.copy(), np.eye(4), proj, (W, H))
    assert keep.tolist() == [0, 1, 2]
    np.testing.assert_array_equal(model[:2], segments)
    np.testing.assert_allclose(model[2], [[0, -1, -5], [0, -1, -1]], atol=1e-12)


@pytest.mark.parametrize("threads", [1, 3])
def test_near_kept_is_near_clipped_a_step_at_a_time(threads, monkeypatch):
    """The kept endpoints and rows of segments taken a few rows a step on the pool are those of
    all at once, bit for bit: steps where none is cut, steps where some are cut or dropped
    (wholly behind the eye), the last step short; the endpoints given where none is cut."""
    from blueprint import parallel, settings
    from blueprint.silhouette.edges import near_clipped, near_kept

    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 8)
    monkeypatch.setattr(parallel, "STEP", 5)
    proj = perspective(70.0, W / H, 0.5, 100.0)
    view = look_at((0.3, 0.2, 4.0), (0.0, 0.0, 0.0), (0, 1, 0))
    rng = np.random.default_rng(7)
    ahead = rng.uniform(-1, 1, (43, 2, 3))
    for segments in (ahead, np.concatenate([ahead[:12], rng.uniform(-6, 6, (31, 2, 3)), ahead[12:]])):
        _, model, kept = near_clipped(segments, view, proj)
        got_model, got_kept = near_kept(segments, view, proj)
        assert got_model.tobytes() == model.tobytes() and got_kept.tolist() == kept.tolist()
    assert len(kept) < len(segments) and not np.array_equal(model, segments[kept])  # some cut, some dropped
    assert near_kept(ahead, view, proj)[0] is ahead


@pytest.mark.parametrize(
    "kwargs",
    [
        {"view": np.eye(3)},
        {"projection": np.full((4, 4), np.nan)},
        {"width": 0},
        {"height": 2.5},
        {"crease_angle": 181.0},
    ],
)
def test_classify_rejects_bad_arguments(kwargs):
    args = {"view": np.eye(4), "projection": ortho(1, 1, 0.1, 10), "width": 4, "height": 4}
    with pytest.raises(ValueError):
        classify_edges(build_adjacency(CORNERS, CUBE_FACES), **(args | kwargs))


def test_silhouette_image_draws_square_outline():
    # Square [-1, 1]^2 facing an orthographic camera spanning [-2, 2]^2 on 40x40 pixels: its
    # left border projects onto the pixel boundary x = 10, half covering columns 9 and 10.
    positions = np.array([[-1.0, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]])
    view = look_at(np.array([0, 0, 5.0]), np.zeros(3), np.array([0, 1.0, 0]))
    image = silhouette_image(positions, [[0, 1, 2], [0, 2, 3]], view, ortho(2, 2, 1, 10), 40, 40)
    assert image.shape == (40, 40) and image.dtype == np.float32
    np.testing.assert_allclose(image[20, 8:12], [0, 0.5, 0.5, 0])
    np.testing.assert_allclose(image[8:12, 20], [0, 0.5, 0.5, 0])
    assert image[20, 20] == 0
    none = silhouette_image(positions, [[0, 1, 2], [0, 2, 3]], view, ortho(2, 2, 1, 10), 40, 40,
                            kinds=(CREASE,))  # fmt: skip
    assert not none.any()
    with pytest.raises(ValueError):
        silhouette_image(positions, [[0, 1, 2]], view, ortho(2, 2, 1, 10), 40, 40, kinds=(4,))


def test_first_faces_from_the_first_two_equal_the_incidences():
    """An edge's lowest-index chosen face, from its first two faces where it has at most two,
    equals the search over every incidence: on a mesh with borders, degenerate faces and
    non-manifold edges (three and four faces on one edge), for random choices of faces."""
    from blueprint.silhouette.edges import _first_face, _first_face_of, _first_two_faces

    rng = np.random.default_rng(5)
    sphere = trimesh.creation.icosphere(subdivisions=2)
    n = len(sphere.vertices)
    fins = np.array([[0, 1, n], [1, 0, n + 1], [0, 1, n + 2]])
    positions = np.vstack([sphere.vertices, rng.normal(size=(3, 3)) * 2])
    faces = np.vstack([sphere.faces[:-7], fins, [[3, 3, 4]]])
    adj = build_adjacency(positions, faces)
    count, f0, f1 = _first_two_faces(adj)
    assert (count > 2).any() and (count == 1).any()
    for _ in range(20):
        chosen = rng.random(len(adj.faces)) < 0.5
        np.testing.assert_array_equal(_first_face_of(adj, chosen, count, f0, f1), _first_face(adj, chosen))


def test_sharp_edges_kept_for_every_view_classify_alike():
    """The sharp edges given (kept by a caller for every view, ``mesh_sharp_edges``) classify
    a mesh's edges exactly as those found for the view."""
    mesh = trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.4, sections=24)
    adj = build_adjacency(mesh.vertices, mesh.faces)
    sharp = mesh_sharp_edges(adj, 30.0)
    assert sharp.any() and not sharp.all()
    for view in ("iso", "front", "top"):
        camera = Camera.fit(mesh.vertices, view, aspect=1.0)
        v, p = camera.view_matrix(), camera.projection_matrix()
        found = classify_edges(adj, v, p, 256, 256, 30.0)
        given = classify_edges(adj, v, p, 256, 256, 30.0, sharp=sharp)
        np.testing.assert_array_equal(found.edges, given.edges)
        np.testing.assert_array_equal(found.kind, given.kind)
        np.testing.assert_array_equal(found.faces, given.faces)


def test_sharp_edges_kept_give_the_same_smooth_surface():
    """The smooth surface (its feature vertices) from the sharp edges a caller keeps, as from
    those it finds itself; and from other sharp edges, other features: the ones given are read."""
    from blueprint.silhouette.contours import smooth_surface
    from blueprint.silhouette.edges import feature_vertices

    mesh = trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.4, sections=24)
    adj = build_adjacency(mesh.vertices, mesh.faces)
    sharp = mesh_sharp_edges(adj, 30.0)
    np.testing.assert_array_equal(feature_vertices(adj, 30.0, sharp), feature_vertices(adj, 30.0))
    found, given = smooth_surface(adj, 30.0), smooth_surface(adj, 30.0, sharp)
    np.testing.assert_array_equal(found.smooth, given.smooth)
    np.testing.assert_array_equal(found.normals, given.normals)
    assert feature_vertices(adj, 30.0, np.zeros_like(sharp)).sum() < feature_vertices(adj, 30.0).sum()
