"""Vector drawings of models kept as instances: lines found per unique mesh and placed per
instance, occlusion against the whole scene, all without flattening the model, and the same
lines, edge numbers and drawings as its flattened twin gives."""

import numpy as np
import pytest
from instanced_scenes import (
    STEP_EDGES,
    STEPPED,
    exact_scene,
    flattened,
    l_prism,
    placed,
    smooth_scene,
    stepped_scene,
    trimesh_scene,
    wedge,
)

from blueprint.errors import InputError
from blueprint.scene.camera import Camera, fit_camera
from blueprint.scene.loader import model_from_object
from blueprint.vector.drawing import draw_vector
from blueprint.vector.lines import edge_numbers, edge_segments, intersection_segments, model_segments
from blueprint.vector.linework import CREASE, INTERSECTION, SILHOUETTE

SIZE = (512, 512)


def _segments(model, twin, view):
    camera = fit_camera(twin, SIZE, view)
    return model_segments(model, camera.view_matrix(), camera.projection_matrix(), SIZE)


@pytest.mark.parametrize("view", ["iso", "front", "top"])
def test_lines_are_the_flattened_scenes(view):
    model = smooth_scene()
    twin = flattened(smooth_scene())
    ours, theirs = _segments(model, twin, view), _segments(twin, twin, view)
    assert not model.is_flat
    assert len(ours) == len(theirs)
    assert {SILHOUETTE, CREASE, INTERSECTION} <= set(ours.kind.tolist())
    # smooth contours cross faces: their two ends lie on different edges
    assert (ours.end_edges() != ours.edge).sum() > 50
    np.testing.assert_allclose(ours.points, theirs.points, atol=1e-5)
    for name in ("faces", "part", "kind", "edge"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(theirs, name), err_msg=name)
    np.testing.assert_array_equal(ours.end_edges(), theirs.end_edges())


def _stepped_camera(view: str) -> Camera:
    """An orthographic axis view of ``stepped_scene``, or ("cut") one along -z whose near plane
    cuts through the scene: lines nearer than it are dropped and the edge-on outlines there
    kept whole, as the flat path does."""
    if view == "cut":
        return Camera(eye=(1, 2, 3), target=(1, 2, 0), up=(0, 1, 0), near=1.75, far=40, ortho=True, height=12)
    return fit_camera(flattened(stepped_scene()), SIZE, view, ortho=True)


def _assert_same_segments(ours, theirs):
    assert len(ours) == len(theirs)
    np.testing.assert_allclose(ours.points, theirs.points, atol=1e-5)
    for name in ("faces", "part", "kind", "edge"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(theirs, name), err_msg=name)
    np.testing.assert_array_equal(ours.end_edges(), theirs.end_edges())


@pytest.mark.parametrize("view", ["front", "top", "back", "cut"])
def test_outlines_of_faces_seen_edge_on_are_the_flattened_scenes(view):
    model, twin = stepped_scene(), flattened(stepped_scene())
    camera = _stepped_camera(view)
    view_matrix, projection = camera.view_matrix(), camera.projection_matrix()
    ours = model_segments(model, view_matrix, projection, SIZE)
    theirs = model_segments(twin, view_matrix, projection, SIZE)
    assert not model.is_flat
    _assert_same_segments(ours, theirs)


def test_a_step_seen_edge_on_is_outlined_in_every_instance():
    """Seen along z, the step of every instance whose step stays square to z (all but the one
    turned about x) has its two long edges as silhouettes: the walls beside it face away
    from the eye in all but the one mirrored through x, and meet it at 14 degrees, so only the
    edge-on rule draws them there."""
    model = stepped_scene()
    camera = _stepped_camera("front")
    found = model_segments(model, camera.view_matrix(), camera.projection_matrix(), SIZE, intersections=False)
    outline = found.points[found.kind == SILHOUETTE]
    expected = []
    for name, transform in STEPPED:
        normal = np.linalg.inv(transform[:3, :3]).T @ [0.0, 1.0, 0.0]
        if name == "step" and normal[2] == 0.0:
            expected += list(STEP_EDGES @ transform[:3, :3].T + transform[:3, 3])
    assert len(expected) == 10
    for edge in expected:
        apart = np.minimum(
            np.abs(outline - edge).max(axis=(1, 2)), np.abs(outline - edge[::-1]).max(axis=(1, 2))
        )
        assert apart.min() < 1e-6, edge


def _by_class(drawing) -> dict:
    """(part, kind, level) to (polylines, their length in pixels)."""
    lines, out = drawing.lines, {}
    for i in range(len(lines)):
        length = float(np.linalg.norm(np.diff(lines.polyline(i), axis=0), axis=1).sum())
        key = (int(lines.part[i]), int(lines.kind[i]), int(lines.level[i]))
        count, total = out.get(key, (0, 0.0))
        out[key] = (count + 1, total + length)
    return out


@pytest.mark.parametrize("view", ["iso", "front"])
def test_drawing_is_the_flattened_scenes(renderer, view):
    model = smooth_scene()
    ours = draw_vector(model, size=SIZE, renderer=renderer, view=view)
    theirs = draw_vector(flattened(smooth_scene()), size=SIZE, renderer=renderer, view=view)
    assert not model.is_flat
    mine, twin = _by_class(ours), _by_class(theirs)
    assert len(mine) > 20 and mine.keys() == twin.keys()
    for key, (count, length) in mine.items():
        assert count == twin[key][0], key
        assert length == pytest.approx(twin[key][1], abs=0.01), key


def test_edge_numbers_are_the_flattened_scenes():
    model = exact_scene()
    twin = flattened(exact_scene())
    numbers = edge_numbers(model)
    np.testing.assert_array_equal(numbers, edge_numbers(twin))
    every = np.arange(len(numbers))
    np.testing.assert_allclose(edge_segments(model, every), edge_segments(twin, every), atol=1e-6)
    with pytest.raises(InputError, match=f"edge {len(numbers)} is no edge of the model"):
        edge_segments(model, [0, len(numbers)])
    assert not model.is_flat


def test_intersections_of_repeated_pairs_are_placed_at_each():
    # four copies of a wedge cutting through an L prism, one of them turned a quarter
    pairs = []
    for k in range(4):
        pairs += [("l", placed(None, (5.0 * k, 0, 0))), ("wedge", placed(None, (5.0 * k + 0.25, 0.25, 0.25)))]
    pairs[-2] = ("l", placed(np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]), (15.0, 0, 0)))
    scene = trimesh_scene(pairs, {"l": l_prism(), "wedge": wedge()})
    model = model_from_object(scene, name="pairs")
    twin = flattened(model_from_object(scene, name="pairs"))
    assert model.instances is not None
    ours, theirs = intersection_segments(model), intersection_segments(twin)
    assert not model.is_flat
    assert len(ours) == len(theirs) > 0
    np.testing.assert_allclose(ours.points, theirs.points, atol=1e-6)
    np.testing.assert_array_equal(ours.faces, theirs.faces)
    np.testing.assert_array_equal(ours.part, theirs.part)
    # the three alike pairs give the same lines, moved by their translation
    first = ours.part == 0
    second = ours.part == 2
    np.testing.assert_allclose(ours.points[second], ours.points[first] + [5.0, 0, 0], atol=1e-9)


def test_intersections_are_counted_before_they_are_placed():
    """Within ``instanced.placing_weighed``, the intersections' segments, every pair of each
    group of alike pairs, are told before they are placed (to be refused there)."""
    from blueprint.vector.instanced import placing_weighed

    pairs = []
    for k in range(3):
        pairs += [("l", placed(None, (5.0 * k, 0, 0))), ("wedge", placed(None, (5.0 * k + 0.25, 0.25, 0.25)))]
    model = model_from_object(trimesh_scene(pairs, {"l": l_prism(), "wedge": wedge()}), name="pairs")
    told = []
    with placing_weighed(told.append):
        found = intersection_segments(model)
    assert len(found) > 0 and told == [len(found)]

    def refuse(count):
        raise InputError(f"{count} segments")

    # (another scene: the first's intersections are kept by its content, and not placed again)
    again = model_from_object(trimesh_scene(pairs[:4], {"l": l_prism(), "wedge": wedge()}), name="again")
    with placing_weighed(refuse), pytest.raises(InputError, match=r"^\d+ segments$"):
        intersection_segments(again)


def test_intersections_on_several_threads_are_those_of_one(monkeypatch):
    """The intersections' segments placed at each pair a block at a time on the pool, and put in
    order of their faces by the pool's sort: on three threads, byte for byte those of one."""
    from blueprint import parallel, settings
    from blueprint.vector.instanced import INTERSECTIONS

    monkeypatch.setattr(parallel, "MIN_BLOCK", 8)  # blocks of a few segments
    pairs = []
    for k in range(12):
        # three placements of the wedge against the prism: three groups of alike pairs
        shift = 0.25 + 0.1 * (k % 3)
        pairs += [
            ("l", placed(None, (5.0 * k, 0, 0))),
            ("wedge", placed(None, (5.0 * k + shift, 0.25, 0.25))),
        ]
    scene = trimesh_scene(pairs, {"l": l_prism(), "wedge": wedge()})
    found = []
    for threads in (1, 3):
        monkeypatch.setattr(settings, "THREADS", threads)
        INTERSECTIONS.clear()
        lines = intersection_segments(model_from_object(scene, name="pairs"))
        found.append([lines.points, lines.faces, lines.part])
    assert len(found[0][0]) > 0
    for a, b in zip(*found, strict=True):
        assert a.tobytes() == b.tobytes()


def test_intersections_are_ordered_by_their_faces_as_lexsort_orders_them():
    """``instanced._by_faces``: pairs of faces in ``np.lexsort``'s order, rows alike in their
    own, by one key of the pool's sort where the pairs fit one, else by lexsort itself."""
    from blueprint.vector.instanced import _by_faces

    faces = np.random.default_rng(3).integers(0, 50, (5000, 2))
    want = np.lexsort((faces[:, 1], faces[:, 0]))
    np.testing.assert_array_equal(_by_faces(faces, 50), want)
    np.testing.assert_array_equal(_by_faces(faces, 1 << 32), want)


def test_points_moved_in_whole_arrays_equal_einsum_to_the_bit():
    """``instanced._moved`` and ``_dot3`` give einsum's float64 values bit for bit (zeros of
    either sign included): for points placed by blocks of transforms, for face normals by
    transposed cofactor matrices, and for the planes' dot products."""
    from blueprint.vector.instanced import _dot3, _moved, _placed

    rng = np.random.default_rng(11)
    transforms = rng.normal(size=(6, 4, 4)) * 10.0 ** rng.integers(-3, 4, (6, 1, 1))
    points = rng.normal(size=(6, 500, 3)) * 1e3
    points[:, :40] = -0.0  # every product -0: einsum's sum is +0
    transforms[0, :3, :3] = 0.0
    want = np.einsum("kij,kpj->kpi", transforms[:, :3, :3], points) + transforms[:, None, :3, 3]
    assert _placed(points, transforms).tobytes() == want.tobytes()
    cofactor = np.linalg.inv(transforms[:, :3, :3] + 3 * np.eye(3)).transpose(0, 2, 1)
    cross = np.r_[np.full((20, 3), -0.0), rng.normal(size=(300, 3))]
    normal = np.einsum("bij,fj->bfi", cofactor, cross)
    assert _moved(cofactor[:, None], cross[None], in_order=True).tobytes() == normal.tobytes()
    linear = np.ascontiguousarray(transforms[:, :3, :3])
    corner = np.einsum("bij,fj->bfi", linear, cross)
    assert _moved(linear[:, None], cross[None]).tobytes() == corner.tobytes()
    assert _dot3(normal, corner).tobytes() == np.einsum("bfi,bfi->bf", normal, corner).tobytes()


def test_blocks_of_instances_on_several_threads_find_what_one_thread_does(monkeypatch):
    """The blocks of instances run side by side (``parallel.each``): the features and the
    faces' planes, in blocks of an instance or two on three threads, equal byte for byte those
    of one thread."""
    from blueprint import settings
    from blueprint.vector import instanced
    from blueprint.vector.occlusion.levels import face_planes

    def found():
        model = smooth_scene()
        camera = fit_camera(flattened(smooth_scene()), SIZE, "iso")
        view = camera.view_matrix()
        segments = model_segments(model, view, camera.projection_matrix(), SIZE)
        return [segments.points, segments.faces, segments.kind, segments.edge, face_planes(model, view)]

    monkeypatch.setattr(instanced, "_ROWS", 64)  # a block an instance or two
    monkeypatch.setattr(settings, "THREADS", 1)
    want = found()
    monkeypatch.setattr(settings, "THREADS", 3)
    got = found()
    for a, b in zip(got, want, strict=True):
        assert a.tobytes() == b.tobytes()
    assert len(want[0]) > 100
