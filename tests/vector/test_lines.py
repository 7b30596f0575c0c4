"""Object-space lines: features per part, part boundaries, intersections between parts, joining."""

import time

import numpy as np
import pytest

from blueprint.examples import assemble, box
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model
from blueprint.vector.lines import (
    BORDER,
    CREASE,
    INTERSECTION,
    PART_BOUNDARY,
    SILHOUETTE,
    Segments,
    _candidate_pairs,
    _candidate_triangles,
    feature_segments,
    intersection_segments,
    join_polylines,
)

SIZE = (128, 128)


def _camera(model, **kwargs):
    return Camera.fit(model.positions, "iso", aspect=1.0, **kwargs)


def _kinds(segments):
    return {k: int(n) for k, n in zip(*np.unique(segments.kind, return_counts=True), strict=True)}


def test_cube_edges_silhouettes_and_creases():
    model = assemble({"cube": box((-1, -1, -1), (1, 1, 1))})
    cam = _camera(model)
    found = feature_segments(model, cam.view_matrix(), cam.projection_matrix(), SIZE)
    # iso view of a cube: the 6 edges of the outline are silhouettes, the 3 edges at the near
    # corner and the 3 at the far corner are creases between two faces turned the same way
    assert _kinds(found) == {SILHOUETTE: 6, CREASE: 6}
    assert (found.part == 0).all()
    assert len(join_polylines(found)) == 12  # every corner joins three edges: no chains


def test_touching_solids_keep_their_own_edges_and_no_contact_diagonal():
    # two unit boxes pressed together along x = 1: their shared square must not become
    # non-manifold silhouettes, and its diagonal (an edge of both) must not be drawn at all
    model = assemble({"a": box((0, 0, 0), (1, 1, 1)), "b": box((1, 0, 0), (2, 1, 1))})
    cam = _camera(model)
    found = feature_segments(model, cam.view_matrix(), cam.projection_matrix(), SIZE)
    on_contact = np.all(np.isclose(found.points[:, :, 0], 1.0), axis=1)
    diagonal = on_contact & ~np.any(np.isclose(np.abs(np.diff(found.points, axis=1))[:, 0, 1:], 0), axis=1)
    assert not diagonal.any()
    assert len(intersection_segments(model)) == 0  # touching is not cutting
    # both boxes keep 12 edges each; joining drops the four that coincide
    assert len(found) == 24
    assert len(join_polylines(found)) == 20


def test_surface_split_into_parts_draws_the_seam_once_as_part_boundary():
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    model = Model.from_arrays(positions, faces, np.array([0, 0, 1, 1]), ("left", "right"))
    cam = Camera.fit(model.positions, "front", aspect=1.0)
    found = feature_segments(model, cam.view_matrix(), cam.projection_matrix(), SIZE)
    seam = np.all(np.isclose(found.points[:, :, 0], 1.0), axis=1)
    assert seam.sum() == 2 and (found.kind[seam] == PART_BOUNDARY).all()
    assert (found.kind[~seam] == BORDER).all()
    lines = join_polylines(found)
    # the outer rim of each half is one chain; the seam, shared by both parts, comes out once
    total = sum(
        np.linalg.norm(np.diff(lines.points[a:b], axis=0), axis=1).sum()
        for a, b in zip(lines.offsets[:-1], lines.offsets[1:], strict=True)
    )
    assert total == pytest.approx(7.0)


def test_intersection_lines_of_two_boxes_cutting_through_each_other():
    # b pokes out of a through a's faces x = 1 and y = 1: on each face the crossing is a
    # U of length 1 + 1 + 1 (b's faces y = 0 / x = 0 and z = +-0.5), 6 in all
    model = assemble({"a": box((-1, -1, -1), (1, 1, 1)), "b": box((0, 0, -0.5), (2, 2, 0.5))})
    found = intersection_segments(model)
    assert (found.kind == INTERSECTION).all() and (found.part == 0).all()
    length = np.linalg.norm(found.points[:, 1] - found.points[:, 0], axis=1).sum()
    assert length == pytest.approx(6.0, abs=1e-9)
    # every point lies on a's surface and on b's surface
    p = found.points.reshape(-1, 3)

    def on_box(lo, hi):
        inside = np.all((p >= np.array(lo) - 1e-9) & (p <= np.array(hi) + 1e-9), axis=1)
        face = np.any(np.isclose(p, lo) | np.isclose(p, hi), axis=1)
        return inside & face

    assert on_box((-1, -1, -1), (1, 1, 1)).all() and on_box((0, 0, -0.5), (2, 2, 0.5)).all()
    # each face's U joins into one chain (the corners at x = y = 1 are shared by both)
    lines = join_polylines(found)
    assert 1 <= len(lines) <= 2


def test_grid_broad_phase_finds_exactly_the_overlapping_boxes():
    rng = np.random.default_rng(7)
    n = 600
    centre = rng.uniform(0, 10, (n, 3))
    size = rng.uniform(0.05, 1.5, (n, 3)) ** 2
    lo, hi = centre - size, centre + size
    part = rng.integers(0, 5, n)
    i, j = _candidate_pairs(lo, hi, part, 0.0)
    got = {(min(a, b), max(a, b)) for a, b in zip(i.tolist(), j.tolist(), strict=True)}
    assert len(got) == len(i)  # no pair twice
    overlap = np.all((lo[:, None] <= hi[None]) & (lo[None] <= hi[:, None]), axis=2)
    overlap &= part[:, None] != part[None]
    a, b = np.nonzero(np.triu(overlap, 1))
    assert got == set(zip(a.tolist(), b.tolist(), strict=True))


def test_candidate_triangles_are_those_meeting_another_parts_box():
    rng = np.random.default_rng(3)
    for parts, slack in ((5, 0.0), (70, 0.05), (150, 0.0)):  # one, two and three words of parts
        n = 600
        # each part's triangles about a place of its own
        part = rng.integers(0, parts, n)
        centre = rng.uniform(0, 1.2 * parts ** (1 / 3), (parts, 3))[part] + rng.normal(0, 0.3, (n, 3))
        size = rng.uniform(0.01, 0.2, (n, 3))
        lo, hi = centre - size, centre + size
        # two more parts that hold no triangle
        got = _candidate_triangles(lo, hi, part, parts + 2, slack)
        box_lo, box_hi = np.full((parts, 3), np.inf), np.full((parts, 3), -np.inf)
        np.minimum.at(box_lo, part, lo)
        np.maximum.at(box_hi, part, hi)
        meets = np.all((lo[:, None] <= box_hi[None] + slack) & (hi[:, None] >= box_lo[None] - slack), axis=2)
        meets[np.arange(n), part] = False
        assert got.tolist() == np.flatnonzero(meets.any(axis=1)).tolist()
        assert 0 < len(got) < n


def test_join_chains_and_closes_loops():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    loop = np.stack([square, np.roll(square, -1, axis=0)], axis=1)
    tail = np.array([[[1, 1, 0], [2, 2, 0]], [[2, 2, 0], [3, 2, 0]]], float)
    # the loop's corner (1, 1) meets the tail: a junction of three, so the tail is one chain
    segments = Segments(
        np.concatenate([loop[[2, 0, 3, 1]], tail]),
        np.full((6, 2), -1),
        np.zeros(6, np.int32),
        np.full(6, CREASE, np.uint8),
        np.arange(6),
    )
    lines = join_polylines(segments)
    lengths = sorted(np.diff(lines.offsets).tolist())
    assert lengths == [3, 5]  # the tail (3 points) and the loop (4 edges, first point repeated)
    loop_line = next(
        lines.points[a:b] for a, b in zip(lines.offsets[:-1], lines.offsets[1:], strict=True) if b - a == 5
    )
    np.testing.assert_array_equal(loop_line[0], loop_line[-1])


def test_joining_in_blocks_is_joining_at_once(monkeypatch):
    """``join_polylines`` keys the points, finds the segments' directions and writes the
    polylines a block at a time on the pool: cut into blocks of a few rows over four threads,
    the polylines are those joined in one block, bit for bit (segments drawn twice, walked
    backwards, ending on other edges, meeting at junctions)."""
    from blueprint import parallel, settings
    from blueprint.vector import lines as lines_module

    rng = np.random.default_rng(5)
    grid = rng.integers(0, 6, (300, 2, 3)).astype(float) * 0.5
    grid = np.concatenate([grid, grid[:40, ::-1]])  # some twice, the other way round
    n = len(grid)
    segments = Segments(
        grid,
        rng.integers(-1, 50, (n, 2)),
        rng.integers(0, 3, n).astype(np.int32),
        rng.choice([CREASE, SILHOUETTE, BORDER], n).astype(np.uint8),
        rng.integers(-1, 99, n),
        rng.integers(-1, 99, n),
    )
    monkeypatch.setattr(settings, "THREADS", 1)
    whole = join_polylines(segments)
    monkeypatch.setattr(settings, "THREADS", 4)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)
    monkeypatch.setattr(lines_module, "_ROWS", 5)
    blocks = join_polylines(segments)
    for name in ("points", "offsets", "faces", "part", "kind", "edge"):
        a, b = getattr(whole, name), getattr(blocks, name)
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), name
    assert 10 < len(whole) < n


def test_intersections_stay_bounded_on_the_engine(shared_models):
    from blueprint.scene.loader import load_model

    model = load_model(shared_models / "glTF-Sample-Models" / "2CylinderEngine.glb")
    start = time.perf_counter()
    found = intersection_segments(model)
    elapsed = time.perf_counter() - start
    assert len(found) > 1000  # bolts through plates, pistons in cylinders, ...
    assert elapsed < 15.0, f"{elapsed:.1f} s for {model.triangle_count} triangles"


def test_view_independent_lines_are_found_again_for_the_same_mesh():
    """A second Model of the same mesh (a batch loading a file again) reuses the adjacency and
    the intersection lines; a mesh moved by a hair does not."""
    from blueprint.vector.lines import adjacency

    def two_boxes(shift=0.0):
        return assemble({"a": box((0, 0, 0), (2, 2, 2)), "b": box((1 + shift, 1, 1), (3, 3, 3))})

    first, again, moved = two_boxes(), two_boxes(), two_boxes(1e-3)
    assert first is not again
    assert intersection_segments(again) is intersection_segments(first)
    assert adjacency(again) is adjacency(first)
    assert len(intersection_segments(first)) > 0
    assert intersection_segments(moved) is not intersection_segments(first)


def test_an_edge_where_a_face_seen_edge_on_meets_a_tangent_one_is_a_silhouette():
    """Two faces meeting at 10 degrees along the x axis, seen from the top: one hangs down
    edge-on (its normal 1e-12 off square with the view, turned to the eye by rounding), the
    other rises towards the eye. Both face the eye and the angle is under the crease angle, so
    the faces alone make no line there; but ``n . v`` is zero on the edge-on face, so the
    outline runs along the edge (a fillet seen along its axis, where it meets a blend)."""
    rise = np.tan(np.radians(10.0))
    positions = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1e-12, -1.0], [0.0, -rise, 1.0]])
    model = assemble({"fold": (positions, np.array([[0, 1, 2], [1, 0, 3]]))})
    cam = Camera(eye=(0.5, 0, 10), target=(0.5, 0, 0), up=(0, 1, 0), near=1, far=20, ortho=True, height=3.0)
    found = feature_segments(model, cam.view_matrix(), cam.projection_matrix(), SIZE, smooth=False)
    shared = np.all(found.points[:, :, 1:] == 0.0, axis=(1, 2))
    assert shared.sum() == 1
    assert found.kind[shared][0] == SILHOUETTE
    assert sorted(found.faces[shared][0]) == [0, 1]


def test_point_ids_rank_the_rounded_points_as_unique_does():
    """``lines._point_ids`` numbers points equal after rounding by their rank among the
    distinct rounded points (ordered by z, then y, then x), as ``np.unique``'s inverse of the
    rounded rows does."""
    from blueprint.vector.lines import _point_ids

    rng = np.random.default_rng(2)
    grid = rng.integers(0, 10, (3000, 3)) * 0.25
    points = grid + rng.uniform(-0.004, 0.004, grid.shape)  # within half a quantum of the grid
    ids = _point_ids(points, 0.01)
    rounded = np.round((points - points.min(axis=0)) / 0.01).astype(np.int64)
    want = np.unique(rounded[:, ::-1], axis=0, return_inverse=True)[1].reshape(-1)
    np.testing.assert_array_equal(ids, want)
    assert ids.max() < len(points) - 100  # repeats did meet


def test_pair_ends_given_the_nodes_order_pairs_as_without_it():
    """``chain.pair_ends`` with the half-ends' order by node handed in pairs as it does sorting
    them itself, on nodes of two to six half-ends (junctions with ties of straightness), and
    with the directions as a function of the half-ends as with them all in an array."""
    from blueprint.sorting import stable_argsort
    from blueprint.vector.chain import pair_ends

    rng = np.random.default_rng(4)
    node = rng.integers(0, 900, 4000)
    leaving = rng.integers(-1, 2, (4000, 3)).astype(float)  # few directions: ties
    leaving /= np.maximum(np.linalg.norm(leaving, axis=1), 1e-300)[:, None]
    want = pair_ends(node, leaving, np.cos(np.radians(30)))
    got = pair_ends(node, leaving, np.cos(np.radians(30)), stable_argsort(node))
    np.testing.assert_array_equal(got, want)
    # the directions read only where asked, as the pieces' own turned at their ends
    ahead = leaving[0::2]
    leaving[1::2] = -ahead
    want = pair_ends(node, leaving, np.cos(np.radians(30)))
    asked = lambda h: np.where((h & 1)[:, None] == 1, -ahead[h >> 1], ahead[h >> 1])  # noqa: E731
    np.testing.assert_array_equal(pair_ends(node, asked, np.cos(np.radians(30))), want)
    assert (want >= 0).sum() > 500
    np.testing.assert_array_equal(want[want[want >= 0]], np.flatnonzero(want >= 0))


def test_face_cosines_are_kept_for_the_last_view_without_keeping_its_mesh():
    """The faces' |cos| of one view are made once for the outlines, contours and grazing band
    that ask, and let go with the adjacency they were made of: the cache holds it weakly."""
    import gc
    import weakref

    from blueprint.silhouette import build_adjacency
    from blueprint.vector import lines

    positions, faces = box((-1, -1, -1), (1, 2, 3))
    camera = Camera.fit(positions, "iso", aspect=1.0)
    view, projection = camera.view_matrix(), camera.projection_matrix()
    adj = build_adjacency(positions, faces)
    first = lines._face_cosines(adj, view, projection)
    assert lines._face_cosines(adj, view, projection) is first
    turned = Camera.fit(positions, "top", aspect=1.0).view_matrix()
    assert lines._face_cosines(adj, turned, projection) is not first
    held = weakref.ref(adj)
    del adj
    gc.collect()
    assert held() is None and lines._COSINES[0] is None
