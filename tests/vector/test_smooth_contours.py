"""Smooth contours (issue 39, point 2): on smooth surfaces the silhouette is the zero set of the
interpolated n . v inside the faces (Hertzmann and Zorin), so it runs smooth across triangles;
the mesh's exact silhouette stays where the surface has a crease or a border."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scan_helpers import noisy_bust, noisy_sphere, zigzag_ratio

import blueprint
from blueprint.examples import assemble, box
from blueprint.scene.camera import Camera, clip_to_pixels, transform
from blueprint.vector import draw_vector
from blueprint.vector.lines import (
    CREASE,
    SILHOUETTE,
    Segments,
    edge_numbers,
    feature_segments,
    join_polylines,
)

SIZE = (512, 512)


def _matrices(model, view="iso", ortho=False, size=SIZE):
    camera = Camera.fit(model.positions, view, aspect=size[0] / size[1], ortho=ortho)
    return camera, np.asarray(camera.view_matrix(), float), np.asarray(camera.projection_matrix(), float)


def _area_vertex_normals(positions, faces):
    """Area-weighted vertex normals, computed apart from the library (faces wound outwards)."""
    cross = np.cross(
        positions[faces[:, 1]] - positions[faces[:, 0]], positions[faces[:, 2]] - positions[faces[:, 0]]
    )
    summed = np.zeros_like(positions)
    for k in range(3):
        np.add.at(summed, faces[:, k], cross)
    return summed / np.linalg.norm(summed, axis=1, keepdims=True)


def _pixel_polylines(segments, view, projection, size=SIZE, kind=SILHOUETTE):
    chosen = segments.kind == kind
    lines = join_polylines(
        Segments(
            segments.points[chosen],
            segments.faces[chosen],
            segments.part[chosen],
            segments.kind[chosen],
            segments.edge[chosen],
            segments.end_edges()[chosen],
        )
    )
    pixels = clip_to_pixels(transform(lines.points, projection @ view), size)
    return [pixels[a:b] for a, b in zip(lines.offsets[:-1], lines.offsets[1:], strict=True)], lines


def test_sphere_contour_is_the_zero_set_of_interpolated_n_dot_v():
    """An icosphere (every edge's faces within 10 degrees: smooth everywhere) in perspective:
    no mesh silhouette edge is left, every contour point lies on a mesh edge where n . v,
    linear between the edge's vertices (area-weighted vertex normals, v towards the eye), is
    zero, and the segments join into one closed loop."""
    sphere = trimesh.creation.icosphere(subdivisions=3)
    model = blueprint.Model.from_arrays(np.asarray(sphere.vertices), np.asarray(sphere.faces))
    camera, view, projection = _matrices(model)
    found = feature_segments(model, view, projection, SIZE)
    assert set(found.kind.tolist()) == {SILHOUETTE}
    assert (found.faces[:, 1] == -1).all()  # each lies inside one face
    positions = model.positions.astype(np.float64)
    normals = _area_vertex_normals(positions, np.asarray(sphere.faces))
    eye = np.linalg.inv(view)[:3, 3]
    g = np.einsum("ij,ij->i", normals, eye - positions)
    numbered = edge_numbers(model)
    for edge_of in (found.edge, found.end_edges()):
        ends = positions[numbered[edge_of]]  # welded vertices keep the icosphere's order
        point = found.points[:, 0] if edge_of is found.edge else found.points[:, 1]
        along = ends[:, 1] - ends[:, 0]
        t = np.einsum("ij,ij->i", point - ends[:, 0], along) / np.einsum("ij,ij->i", along, along)
        np.testing.assert_allclose(point, ends[:, 0] + t[:, None] * along, atol=1e-9)
        assert ((t >= 0) & (t <= 1)).all()
        ga, gb = g[numbered[edge_of, 0]], g[numbered[edge_of, 1]]
        assert (ga * gb <= 0).all()
        np.testing.assert_allclose(ga + t * (gb - ga), 0.0, atol=1e-9)
    # the contour crosses every edge whose ends differ in sign, once
    crossing = np.flatnonzero(g[numbered[:, 0]] * g[numbered[:, 1]] < 0)
    assert np.union1d(found.edge, found.end_edges()).tolist() == crossing.tolist()
    assert np.bincount(np.r_[found.edge, found.end_edges()])[crossing].tolist() == [2] * len(crossing)
    polylines, _ = _pixel_polylines(found, view, projection)
    assert len(polylines) == 1
    np.testing.assert_allclose(polylines[0][0], polylines[0][-1])


def test_contour_source_edges_are_the_edges_it_crosses_in_order():
    """A smooth contour names the edges it crosses, as it runs: where a segment is walked
    backwards, the edge its second point lies on comes first."""
    sphere = trimesh.creation.icosphere(subdivisions=2)
    model = blueprint.Model.from_arrays(np.asarray(sphere.vertices), np.asarray(sphere.faces))
    _, view, projection = _matrices(model, "front", ortho=True)
    lines = join_polylines(feature_segments(model, view, projection, SIZE))
    assert len(lines) == 1
    numbered = edge_numbers(model)
    positions = model.positions.astype(np.float64)
    points = lines.points[:-1]
    ends = positions[numbered[lines.edge[:-1]]]
    # point j lies on the edge named for the segment that starts at it
    along = ends[:, 1] - ends[:, 0]
    t = np.einsum("ij,ij->i", points - ends[:, 0], along) / np.einsum("ij,ij->i", along, along)
    np.testing.assert_allclose(points, ends[:, 0] + t[:, None] * along, atol=1e-9)
    assert len(set(lines.edge[:-1].tolist())) == len(points)


def test_box_keeps_its_exact_silhouette():
    """Every vertex of a box is on a crease: no face is smooth, the lines are the mesh's."""
    model = assemble({"cube": box((-1, -1, -1), (1, 1, 1))})
    _, view, projection = _matrices(model)
    smooth = feature_segments(model, view, projection, SIZE)
    exact = feature_segments(model, view, projection, SIZE, smooth=False)
    np.testing.assert_array_equal(smooth.points, exact.points)
    np.testing.assert_array_equal(smooth.kind, exact.kind)
    np.testing.assert_array_equal(smooth.edge, exact.edge)


def test_hemisphere_on_a_disc_keeps_the_mesh_silhouette_at_the_rim():
    """A closed hemisphere: the dome is smooth, the rim a crease. Seen from the side the
    outline is the dome's smooth contour (a half circle) down to the faces at the rim, where the mesh's own
    silhouette edges carry on; the rim itself is drawn as creases."""
    sphere = trimesh.creation.icosphere(subdivisions=4)
    dome = trimesh.intersections.slice_mesh_plane(sphere, (0, 0, 1), (0, 0, 0), cap=True)
    model = blueprint.Model.from_arrays(np.asarray(dome.vertices), np.asarray(dome.faces))
    # from the side, off the axes: no vertex lies exactly on the contour
    camera = Camera(eye=(10, 3, 2), target=(0, 0, 0.3), up=(0, 0, 1), near=1, far=20, ortho=True, height=2.5)
    view, projection = np.asarray(camera.view_matrix(), float), np.asarray(camera.projection_matrix(), float)
    found = feature_segments(model, view, projection, SIZE)
    silhouettes = found.kind == SILHOUETTE
    inside = silhouettes & (found.faces[:, 1] == -1)
    assert inside.sum() > 20
    mesh_edges = silhouettes & (found.faces[:, 1] >= 0)
    # the mesh's silhouette edges kept lie in faces that touch the rim (z = 0)
    z = np.asarray(dome.vertices)[np.asarray(dome.faces)][:, :, 2]
    touches_rim = (np.abs(z) < 1e-9).any(axis=1)
    assert mesh_edges.any() and touches_rim[found.faces[mesh_edges]].any(axis=1).all()
    assert (found.kind == CREASE).sum() + (found.kind == SILHOUETTE).sum() == len(found)


def _visible_contours(drawing):
    lines = drawing.lines.where(kind="silhouette", level=0)
    return [lines.polyline(i) for i in range(len(lines))]


def test_contours_inside_faces_get_their_occlusion_level(renderer):
    """A sphere of 5 120 faces, a plate in front of its left half (ortho, front view): the
    contour's samples lie inside faces, beside faces nearer the eye at a grazing angle, yet
    the right half of the outline is visible and the left half hidden by the plate's two
    faces. The
    outline's points lie on the sphere's circle to within the faces' sag."""
    sphere = trimesh.creation.icosphere(subdivisions=4)
    plate = trimesh.creation.box(extents=(1.5, 3.0, 0.05))
    plate.apply_translation((-0.75 - 0.05, 0, 2.0))
    model = assemble({"sphere": (sphere.vertices, sphere.faces), "plate": (plate.vertices, plate.faces)})
    camera = Camera(eye=(0, 0, 10), target=(0, 0, 0), up=(0, 1, 0), near=1, far=20, ortho=True, height=3.0)
    drawing = draw_vector(model, camera, SIZE, renderer=renderer)
    lines = drawing.lines.where(kind="silhouette", part=0)
    centre = 0.5 * np.array(SIZE, float)
    radius = SIZE[1] / 3.0
    for i in range(len(lines)):
        p = lines.polyline(i)
        distance = np.linalg.norm(p - centre, axis=1)
        assert np.abs(distance - radius).max() < 0.01 * radius
    right = lines.where(level=0)
    left = lines.where(level=2)
    assert len(right) + len(left) == len(lines)
    length = {}
    for name, part in (("right", right), ("left", left)):
        length[name] = sum(
            np.linalg.norm(np.diff(part.polyline(i), axis=0), axis=1).sum() for i in range(len(part))
        )
        xs = np.concatenate([part.polyline(i)[:, 0] for i in range(len(part))])
        # the plate's edge lies 0.05 units (8.5 px) left of the centre; a level is decided
        # over the 2 x 2 pixels around a point, so the visible side reaches up to 1.5 px past it
        assert (xs > centre[0] - 10).all() if name == "right" else (xs < centre[0] - 7).all()
    # each half of the circle, less what the plate's edge leaves out
    assert length["right"] > 0.95 * np.pi * radius and length["left"] > 0.9 * np.pi * radius, length


def _zigzag_of_segments(model, smooth, view="iso", size=(1024, 1024)):
    """The zigzag (``zigzag_ratio``) of the silhouettes of ``model``, hidden or not."""
    _, v, p = _matrices(model, view, size=size)
    polylines, _ = _pixel_polylines(feature_segments(model, v, p, size, smooth=smooth), v, p, size)
    return zigzag_ratio(polylines)


def test_noisy_sphere_contour_stays_smooth(renderer):
    """A generated scan of a sphere (0.6 % noise): its visible outline, drawn at 1024 x 1024,
    within 10 % of its length smoothed along the line (sigma 3 px)."""
    drawing = blueprint.draw(noisy_sphere(0.006), size=(1024, 1024), vector=True).lines
    assert zigzag_ratio(_visible_contours(drawing)) <= 1.10


def test_noisy_bust_contours_do_not_zigzag(renderer):
    """The generated bust at 1024 x 1024, iso: the mesh's silhouette edges zigzag (their
    length 12 % above their length smoothed along the line, sigma 3 px); the smooth contours,
    with the exact silhouette kept along the ridge, 7 %, and no more once drawn."""
    model = noisy_bust()[0]
    assert _zigzag_of_segments(model, smooth=False) > 1.10
    assert _zigzag_of_segments(model, smooth=True) <= 1.08
    drawing = blueprint.draw(model, size=(1024, 1024), vector=True).lines
    assert zigzag_ratio(_visible_contours(drawing)) <= 1.10


def test_stanford_bunny_contours_do_not_zigzag(renderer, shared_models):
    """The bunny's drawing at 1024 x 1024: its visible silhouettes at least 40 px long were
    17 % longer than smoothed (the ears, the hind leg), 5 % with smooth contours."""
    path = shared_models / "common-3d-test-models" / "stanford-bunny.obj"
    if not path.exists():
        pytest.skip(f"{path} is missing from the shared models")
    model = blueprint.load_model(path)
    assert _zigzag_of_segments(model, smooth=False) > 1.10
    drawing = blueprint.draw(model, size=(1024, 1024), vector=True).lines
    assert zigzag_ratio(_visible_contours(drawing)) <= 1.10


def test_bust_ridge_is_still_drawn(renderer):
    """The bust's ridge is a feature: seen from the front (both its sides towards the eye),
    its crest is drawn as a crease along its length, each crest vertex within 2 px of one."""
    model, crest = noisy_bust()
    camera, view, projection = _matrices(model, "front", size=(1024, 1024))
    drawing = draw_vector(model, camera, (1024, 1024), renderer=renderer)
    creases = drawing.lines.where(kind="crease", level=0)
    starts = np.concatenate([creases.polyline(i)[:-1] for i in range(len(creases))])
    steps = np.concatenate([np.diff(creases.polyline(i), axis=0) for i in range(len(creases))])
    crest_px = clip_to_pixels(transform(crest, projection @ view), (1024, 1024))
    # each crest vertex's distance to the nearest crease segment
    offset = crest_px[:, None] - starts[None]
    t = np.clip(np.einsum("csk,sk->cs", offset, steps) / np.einsum("sk,sk->s", steps, steps), 0, 1)
    nearest = np.linalg.norm(offset - t[..., None] * steps[None], axis=2).min(axis=1)
    assert (nearest < 2.0).all(), np.round(nearest, 1)


@pytest.mark.parametrize(("view", "least"), [("front", 0.95), ("iso", 0.99)])
def test_noisy_sphere_outline_stays_visible(renderer, view, least):
    """A noisy sphere alone: its whole outline is visible, though the contour of its
    interpolated normals lies a little behind the mesh's rim, where the noise folds the rim
    over it (``grazing_band``). Measured: 0.97 of the silhouettes' length at level 0 from the
    front, 1.0 from the iso view; 0.67 and 0.72 before the band's rule."""
    drawing = blueprint.draw(noisy_sphere(0.006), size=(1024, 1024), view=view, vector=True).lines
    silhouettes = drawing.lines.where(kind="silhouette")

    def length(part):
        return sum(np.linalg.norm(np.diff(part.polyline(i), axis=0), axis=1).sum() for i in range(len(part)))

    assert length(silhouettes.where(level=0)) >= least * length(silhouettes)
