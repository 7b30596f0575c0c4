"""Occlusion levels from the compute pass over the faces k-buffer: equal to the CPU reference,
and right against ray casting at the sample points."""

import dataclasses
import time

import numpy as np
import pytest
import trimesh
from scan_helpers import noisy_sphere

from blueprint.examples import gearbox
from blueprint.render.gbuffer import depth_tolerance
from blueprint.scene.camera import Camera
from blueprint.vector import draw_vector
from blueprint.vector.lines import grazing_band, join_polylines, model_segments
from blueprint.vector.occlusion import (
    DepthTest,
    PixelLayers,
    classify_samples,
    draw_faces,
    drop_phantoms,
    face_planes,
    gpu_levels,
    probe_pixels,
    sample_polylines,
    stack_levels,
    verify_creases,
)

SIZE = (256, 256)


@pytest.fixture(params=["k-buffer", "a-pass-a-layer"])
def source(request, renderer, monkeypatch):
    """Where the pass reads the faces: the faces k-buffer, or layers peeled a pass a layer and
    copied on the GPU (what a renderer without the k-buffer does)."""
    if request.param == "a-pass-a-layer":
        monkeypatch.setattr(renderer, "face_kbuffer", lambda *a, **k: None)
    else:
        row = renderer.capture_table.row("k-buffer")
        if row is None or row.interlock:
            pytest.skip(
                "this driver draws no faces k-buffer (framebuffer fetch alone holds one): "
                "it reads them a pass a layer, the other case"
            )
    return request.param


def _setup(renderer, model, camera):
    view, proj = camera.view_matrix(), camera.projection_matrix()
    lines = join_polylines(model_segments(model, view, proj, SIZE))
    samples = sample_polylines(lines, view, proj, SIZE)
    planes = face_planes(model, view)
    footprint = camera.pixel_angle(SIZE[1])
    test = DepthTest(camera.ortho, footprint, depth_tolerance(camera, model.bounds))
    got = gpu_levels(renderer, model, camera, samples, planes, SIZE, max_layers=8, test=test)
    if got is None:
        pytest.skip(
            "this renderer draws no faces k-buffer (it peels a pass a layer): occlusion runs on the CPU"
        )
    return samples, planes, footprint, got


def test_faces_drawn_ahead_read_as_drawn_in_place(renderer, source, monkeypatch):
    """The faces k-buffer set drawing before the lines are found (draw_faces) gives the levels
    of one drawn by gpu_levels itself, and is not drawn again."""
    model = gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    samples, planes, footprint, in_place = _setup(renderer, model, camera)
    drawn = draw_faces(renderer, model, camera, SIZE, 8)
    assert (drawn.surfaces is None) == (source == "a-pass-a-layer")

    def drawn_again(*args, **kwargs):
        raise AssertionError("the faces k-buffer was drawn again")

    monkeypatch.setattr(renderer, "face_kbuffer", drawn_again)
    ahead = gpu_levels(
        renderer,
        model,
        camera,
        samples,
        planes,
        SIZE,
        max_layers=8,
        test=DepthTest(camera.ortho, footprint, depth_tolerance(camera, model.bounds)),
        drawn=drawn,
    )
    assert ahead.layers == in_place.layers
    np.testing.assert_array_equal(ahead.level, in_place.level)
    np.testing.assert_array_equal(ahead.sides, in_place.sides)
    assert ahead.peel_seconds >= drawn.seconds


@pytest.mark.parametrize("ortho", [False, True], ids=["perspective", "orthographic"])
def test_gpu_levels_equal_the_cpu_reference(renderer, source, ortho):
    model = gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0, ortho=ortho)
    samples, planes, footprint, got = _setup(renderer, model, camera)
    pixels = probe_pixels(samples, SIZE)
    faces = renderer.triangles_at(model, camera, pixels, size=SIZE, max_layers=8)
    peeled = PixelLayers(
        pixels, np.ascontiguousarray(faces.T), (faces >= 0).sum(axis=0), len(faces), *SIZE[::-1]
    )
    assert got.layers == len(faces)
    test = DepthTest(camera.ortho, footprint, depth_tolerance(camera, model.bounds))
    cpu = classify_samples(samples, peeled, planes, test)
    assert len(cpu) > 5000 and len(set(cpu.tolist())) >= 5
    np.testing.assert_array_equal(got.level, cpu)
    # the crease check from the faces the pass saw to either side of the lines
    rows = np.flatnonzero(got.checked & (got.level >= 0))
    gpu_final = drop_phantoms(
        samples,
        got.level,
        rows,
        got.sides[rows, 0],
        got.sides[rows, 1],
        planes,
        model.face_part,
        test,
    )
    cpu_final = verify_creases(samples, cpu, peeled, planes, model.face_part, test)
    np.testing.assert_array_equal(gpu_final, cpu_final)


def test_gpu_levels_match_ray_casting_at_sample_points(renderer, source):
    """At every sample whose answer does not change within 1.5 pixels (off the outlines of
    occluders, where the 2 x 2 minimum decides), the level is the number of surfaces a ray from
    the sample towards the eye crosses, found by trimesh's ray caster in float64."""
    model = gearbox()
    camera = Camera.fit(model.positions, "iso", azimuth=35, elevation=25, aspect=1.0, ortho=True)
    samples, _, footprint, got = _setup(renderer, model, camera)
    mesh = trimesh.Trimesh(model.positions.astype(np.float64), model.faces, process=False)
    caster = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)
    view = np.asarray(camera.view_matrix(), np.float64)
    to_model = np.linalg.inv(view)
    toward_eye = to_model[:3, 2]
    inside = np.flatnonzero(samples.inside)[::3]
    counts = []
    for dx, dy in [(0, 0), (-1.5, -1.5), (1.5, -1.5), (-1.5, 1.5), (1.5, 1.5)]:
        # rays start 3 pixel footprints towards the eye (past the depth tolerance, clear of the
        # line's own surfaces), then moved across the screen for the neighbourhood
        eye = samples.eye[inside] + np.array([dx, dy, 3.0]) * footprint
        origin = eye @ to_model[:3, :3].T + to_model[:3, 3]
        where, ray, _ = caster.intersects_location(
            origin, np.broadcast_to(toward_eye, origin.shape), multiple_hits=True
        )
        distance = np.einsum("ij,j->i", where - origin[ray], toward_eye)
        # hits of one ray within a hair of each other are one surface (an edge of two faces)
        order = np.lexsort((distance, ray))
        ray, distance = ray[order], distance[order]
        new = np.r_[True, (ray[1:] != ray[:-1]) | (np.diff(distance) > 1e-6 * footprint)]
        counts.append(np.bincount(ray[new & (distance > 0)], minlength=len(inside)))
    counts = np.stack(counts)
    stable = np.all(counts == counts[0], axis=0) & (counts[0] <= 7)
    assert stable.sum() > 500
    level = got.level[inside][stable]
    agree = level == counts[0][stable]
    # the rest, off by one, are rays grazing a faceted shaft's silhouette, where hits and
    # misses change within a hair of the line
    assert agree.mean() >= 0.98, f"{(~agree).sum()} of {stable.sum()} samples disagree"


def test_setting_the_faces_drawing_counts_to_the_peel_alone(renderer, source, monkeypatch):
    """The faces set drawing before the lines are found count to the peel, and the occlusion
    after the lines is not short of that time: no stage is negative, and they add up to the
    drawing's."""
    model = gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    draw_vector(model, camera, SIZE, renderer=renderer)
    set_drawing = renderer.face_kbuffer

    def slowly(*args, **kwargs):
        time.sleep(0.3)
        return set_drawing(*args, **kwargs)

    monkeypatch.setattr(renderer, "face_kbuffer", slowly)
    start = time.perf_counter()
    drawing = draw_vector(model, camera, SIZE, renderer=renderer)
    took = time.perf_counter() - start
    assert drawing.seconds["peel"] >= 0.3
    assert min(drawing.seconds.values()) >= 0.0, drawing.seconds
    assert sum(drawing.seconds.values()) <= took


def test_a_drawing_reads_back_levels_only(renderer, source, monkeypatch):
    """No layer leaves the GPU: ``triangles_at`` is never asked, and the drawing is the one the
    CPU reference makes."""
    import blueprint.vector.drawing

    model = gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    with monkeypatch.context() as patch:
        patch.setattr(renderer, "triangles_at", lambda *a, **k: pytest.fail("layers were read back"))
        on_gpu = draw_vector(model, camera, SIZE, renderer=renderer)
    with monkeypatch.context() as patch:
        patch.setattr(blueprint.vector.drawing, "gpu_levels", lambda *a, **k: None)
        patch.setattr(blueprint.vector.drawing, "stack_levels", lambda *a, **k: None)
        on_cpu = draw_vector(model, camera, SIZE, renderer=renderer)
    assert len(on_gpu) > 100 and on_gpu.layers == on_cpu.layers
    np.testing.assert_array_equal(on_gpu.offsets, on_cpu.offsets)
    np.testing.assert_array_equal(on_gpu.points, on_cpu.points)
    np.testing.assert_array_equal(on_gpu.level, on_cpu.level)


@pytest.mark.parametrize(("shape", "max_layers"), [("gears", 3), ("gears", 8), ("box", 8)])
def test_layer_count_is_the_deepest_pixels_surfaces(renderer, shape, max_layers):
    """The deepest pixel's surfaces (deepest.comp) and the first empty layer of the per-layer
    counts (layer_counts.comp, asked with a fraction too small to stop anything) against the
    k-buffer read back, where a model's layers run out before the cap and where they do not."""
    from blueprint.scene.loader import model_from_object
    from blueprint.vector.occlusion.gpu import _layer_count

    model = gearbox() if shape == "gears" else model_from_object(trimesh.creation.box())
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    surfaces = renderer.face_kbuffer(model, camera, size=SIZE, max_layers=max_layers)
    if surfaces is None:
        pytest.skip("this renderer draws no faces k-buffer")
    faces = np.stack([np.frombuffer(t.read(), np.uint32)[1::2] for t in surfaces])
    # a pixel's surfaces run up to its first empty one; deeper targets hold older frames'
    deepest = int(np.cumprod(faces != 0, axis=0).sum(axis=0).max())
    assert deepest == (2 if shape == "box" else max_layers)
    assert _layer_count(renderer, surfaces, SIZE, 0.0) == deepest
    assert _layer_count(renderer, surfaces, SIZE, 1e-9) == deepest


@pytest.mark.parametrize(
    ("ortho", "max_layers", "whole"),
    [(False, None, False), (True, None, False), (False, 3, False), (False, None, True)],
    ids=["perspective", "orthographic", "three-layers", "whole-layers"],
)
def test_stack_levels_equal_the_cpu_reference(renderer, ortho, max_layers, whole):
    """Layers read back (at the pixels probed, or whole), any number of them, classified by the
    compute pass: the CPU reference's levels and, through the faces to either side, its crease
    check, sample for sample."""
    from blueprint.vector.occlusion import stack_levels

    if renderer.ctx.version_code < 430:
        pytest.skip("this renderer runs no compute passes")
    model = gearbox()
    camera = Camera.fit(model.positions, "iso", azimuth=20, aspect=1.0, ortho=ortho)
    view, proj = camera.view_matrix(), camera.projection_matrix()
    samples = sample_polylines(join_polylines(model_segments(model, view, proj, SIZE)), view, proj, SIZE)
    planes = face_planes(model, view)
    test = DepthTest(camera.ortho, camera.pixel_angle(SIZE[1]), depth_tolerance(camera, model.bounds))
    if whole:
        faces = renderer.peel(model, camera, size=SIZE, max_layers=max_layers).triangle
        peeled = PixelLayers.from_layers(faces)
    else:
        pixels = probe_pixels(samples, SIZE)
        faces = renderer.triangles_at(model, camera, pixels, size=SIZE, max_layers=max_layers)
        peeled = PixelLayers(
            pixels, np.ascontiguousarray(faces.T), (faces >= 0).sum(axis=0), len(faces), *SIZE[::-1]
        )
    # more layers than the passes over textures bind (gpu.MAX_LAYERS), or a cap
    assert peeled.layers == 3 if max_layers == 3 else peeled.layers > 8
    got = stack_levels(renderer, samples, planes, peeled, test=test)
    cpu = classify_samples(samples, peeled, planes, test)
    assert len(set(cpu.tolist())) >= 4
    np.testing.assert_array_equal(got.level, cpu)
    assert got.layers == peeled.layers
    rows = np.flatnonzero(got.checked & (got.level >= 0))
    sides = got.sides[rows]
    gpu_final = drop_phantoms(
        samples, got.level, rows, sides[:, 0], sides[:, 1], planes, model.face_part, test
    )
    cpu_final = verify_creases(samples, cpu, peeled, planes, model.face_part, test)
    assert (cpu_final != cpu).sum() > 0
    np.testing.assert_array_equal(gpu_final, cpu_final)


@pytest.mark.parametrize("shade", [None, "gear*"], ids=["lines", "shaded"])
def test_a_drawing_of_every_layer_classified_by_the_pass_is_the_cpu_one(renderer, monkeypatch, shade):
    """Every layer peeled (more than the k-buffer holds), read back at the probed pixels and
    classified by the compute pass: the drawing the CPU reference makes, shaded parts too."""
    import blueprint.vector.drawing

    if renderer.ctx.version_code < 430:
        pytest.skip("this renderer runs no compute passes")
    model = gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    drawings = []
    for cpu in (False, True):
        with monkeypatch.context() as patch:
            patch.setattr(blueprint.vector.drawing, "gpu_levels", lambda *a, **k: None)
            if cpu:
                patch.setattr(blueprint.vector.drawing, "stack_levels", lambda *a, **k: None)
            drawings.append(draw_vector(model, camera, SIZE, renderer=renderer, max_layers=None, shade=shade))
    on_gpu, on_cpu = drawings
    assert len(on_gpu) > 100 and on_gpu.layers == on_cpu.layers > 8
    np.testing.assert_array_equal(on_gpu.offsets, on_cpu.offsets)
    np.testing.assert_array_equal(on_gpu.points, on_cpu.points)
    np.testing.assert_array_equal(on_gpu.level, on_cpu.level)
    assert shade is None or on_gpu.lines.behind.any()
    np.testing.assert_array_equal(on_gpu.lines.behind, on_cpu.lines.behind)


def test_a_sample_a_hair_above_a_pixel_row_looks_at_the_rows_the_cpu_does(renderer):
    """A sample at y = 1.49999997 lies above the centres of pixel row 1 (single precision
    rounds it to 1.5, on them): its 2 x 2 pixels are rows 0 and 1, and row 0, which shows no
    surface, gives a silhouette's level 0, where rows 1 and 2 would both show the face in front
    of it."""
    from blueprint.vector.lines import SILHOUETTE
    from blueprint.vector.occlusion import Samples, stack_levels

    if renderer.ctx.version_code < 430:
        pytest.skip("this renderer runs no compute passes")
    assert np.float32(1.49999997) == 1.5
    triangle = np.zeros((1, 4, 4), np.int32)
    triangle[0, 0] = -1
    peeled = PixelLayers.from_layers(triangle)
    # face 0 the plane z = -1 in eye space, before the sample at depth 5
    planes = np.array([[0.0, 0.0, 1.0, -1.0], [0.0, 0.0, 0.0, 0.0]])
    one = np.ones(1, bool)
    samples = Samples(
        np.array([[0.0, 0.0, -5.0]]),
        np.array([[1.5, 1.49999997]]),
        np.full((1, 2), -1, np.int64),
        np.array([SILHOUETTE], np.uint8),
        np.full(1, -1, np.int64),
        np.zeros(1, np.int64),
        one,
        one,
    )
    test = DepthTest(False, 1e-3, 1e-4)
    assert classify_samples(samples, peeled, planes, test).tolist() == [0]
    samples_lower = dataclasses.replace(samples, pixel=np.array([[1.5, 1.5]]))
    assert classify_samples(samples_lower, peeled, planes, test).tolist() == [1]
    assert stack_levels(renderer, samples, planes, peeled, test=test).level.tolist() == [0]
    assert stack_levels(renderer, samples_lower, planes, peeled, test=test).level.tolist() == [1]


@pytest.mark.parametrize("through", ["faces", "stacks"])
def test_grazing_band_equal_on_the_cpu_and_the_gpu(renderer, source, through):
    """The band where a noisy smooth surface folds over its own contour (``grazing_band``):
    its faces hide a smooth contour's samples only from their reach in front, alike in the
    compute pass (from the faces k-buffer or the peel's copies, and from the stacks read
    back) and in the CPU reference; and the rule changes the levels of contour samples
    alone."""
    model = noisy_sphere(0.006)
    camera = Camera.fit(model.positions, "front", aspect=1.0)
    view, proj = camera.view_matrix(), camera.projection_matrix()
    lines = join_polylines(model_segments(model, view, proj, SIZE))
    samples = sample_polylines(lines, view, proj, SIZE)
    planes = face_planes(model, view)
    plain = DepthTest(camera.ortho, camera.pixel_angle(SIZE[1]), depth_tolerance(camera, model.bounds))
    test = dataclasses.replace(plain, band=grazing_band(model, view, proj))
    assert (test.band > 0).sum() > 100 and test.band[-1] == 0
    pixels = probe_pixels(samples, SIZE)
    faces = renderer.triangles_at(model, camera, pixels, size=SIZE, max_layers=8)
    peeled = PixelLayers(
        pixels, np.ascontiguousarray(faces.T), (faces >= 0).sum(axis=0), len(faces), *SIZE[::-1]
    )
    cpu = classify_samples(samples, peeled, planes, test)
    if through == "faces":
        got = gpu_levels(renderer, model, camera, samples, planes, SIZE, max_layers=8, test=test)
    else:
        got = stack_levels(renderer, samples, planes, peeled, test=test)
    if got is None:
        pytest.skip("this renderer runs the levels on the CPU alone here")
    np.testing.assert_array_equal(got.level, cpu)
    before = classify_samples(samples, peeled, planes, plain)
    contour = test.contour_samples(samples, np.arange(len(samples.line)))
    changed = before != cpu
    assert changed.sum() > 100 and not changed[~contour].any()
    assert (cpu[changed] < before[changed]).all()


def test_the_occlusion_split_over_threads_draws_what_one_thread_does(renderer, monkeypatch):
    """The samples packed for the pass, the coincident search's rows and the crease check's
    phantoms worked a block of rows a thread, a few rows at a time, and the pass's samples
    uploaded and read in steps of a few rows: the same pieces, point for point, as in one
    thread at once."""
    from blueprint import parallel, settings
    from blueprint.vector.occlusion import gpu

    model = gearbox()
    camera = Camera.fit(model.positions, "iso", azimuth=20, aspect=1.0)
    monkeypatch.setattr(settings, "THREADS", 1)
    one = draw_vector(model, camera, SIZE, renderer=renderer).lines
    monkeypatch.setattr(settings, "THREADS", 3)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 64)
    monkeypatch.setattr(parallel, "STEP", 37)
    monkeypatch.setattr(gpu, "_STEP_ROWS", 1000)
    split = draw_vector(model, camera, SIZE, renderer=renderer).lines
    assert len(one.offsets) > 100
    for name in ("points", "offsets", "level", "kind", "part", "edges"):
        np.testing.assert_array_equal(getattr(split, name), getattr(one, name))
