"""Occlusion levels checked edge by edge on shapes whose answer is known by hand."""

import math
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np
import pytest
from helpers import project
from vector_helpers import (
    SVG,
    box_edges,
    boxes_in_front,
    point_segment_distance,
    split_at_corners,
)

from blueprint.examples import assemble, box, prism
from blueprint.render.table import CaptureTable, capture_table
from blueprint.scene.camera import Camera
from blueprint.vector import draw_vector, vector_style

SIZE = (256, 256)


def _pieces(drawing):
    """(part name, level, points) of every stretch of polyline between corners: lines chain
    through corners, the checks below look edge by edge."""
    return [
        (drawing.part_names[drawing.part[i]], int(drawing.level[i]), stretch)
        for i in range(len(drawing))
        for stretch in split_at_corners(drawing.polyline(i))
    ]


def _edge_of(points, edges2d, tol=0.35):
    """Index of the projected edge a polyline lies on (every point within `tol` pixels)."""
    dist = point_segment_distance(points, edges2d).max(axis=0)
    best = int(np.argmin(dist))
    assert dist[best] <= tol, f"polyline {points.round(1).tolist()} lies on no edge ({dist[best]:.2f} px)"
    return best


def _length(points):
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def test_cube_nine_visible_edges_and_three_hidden(renderer):
    """Hand-checked: a cube seen from above a corner shows its 6 outline edges and the 3 edges
    at the nearest corner; the 3 edges meeting at the farthest corner are behind one face."""
    lo, hi = (-1, -1, -1), (1, 1, 1)
    model = assemble({"cube": box(lo, hi)})
    cam = Camera.fit(model.positions, "iso", aspect=1.0)
    drawing = draw_vector(model, cam, SIZE, renderer=renderer)
    edges = box_edges(lo, hi)
    edges2d = np.stack([project(e, cam.view_matrix(), cam.projection_matrix(), SIZE) for e in edges])
    far = np.argmax(np.linalg.norm(edges.reshape(-1, 3) - np.array(cam.eye), axis=1))
    far_corner = edges.reshape(-1, 3)[far]
    expected = [1 if np.any(np.all(np.isclose(e, far_corner), axis=1)) else 0 for e in edges]
    assert sorted(expected) == [0] * 9 + [1] * 3
    covered = np.zeros((12, 2))
    for _, level, points in _pieces(drawing):
        k = _edge_of(points, edges2d)
        assert level == expected[k], f"edge {k}: level {level}, expected {expected[k]}"
        covered[k, level] += _length(points)
    for k in range(12):
        full = _length(edges2d[k])
        assert covered[k, expected[k]] == pytest.approx(full, abs=0.5)


def test_nested_boxes_levels_edge_by_edge(renderer):
    """A box inside a box, orthographic view from azimuth 30, elevation 20.

    By hand: the outer box's 6 outline edges and 3 near edges are visible (level 0); every
    edge of the inner box is behind the outer front faces, its outline and near edges at
    level 1 and the 3 edges at its far corner at level 2 (outer front, inner front). The outer
    box's 3 far edges are behind one outer face (level 1), except where they pass behind the
    inner box: there the inner box's two faces add up to level 3. Where that switch happens is
    checked against an independent count of the box faces crossed on the way to the eye.
    """
    outer, inner = ((-1, -1, -1), (1, 1, 1)), ((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5))
    model = assemble({"outer": box(*outer), "inner": box(*inner)})
    cam = Camera.fit(model.positions, "iso", azimuth=30, elevation=20, ortho=True, aspect=1.0)
    view, proj = cam.view_matrix(), cam.projection_matrix()
    drawing = draw_vector(model, cam, SIZE, renderer=renderer)
    toward_eye = np.linalg.inv(view)[:3, 2]  # orthographic: every ray runs along the camera's +z

    edges = {"outer": box_edges(*outer), "inner": box_edges(*inner)}
    edges2d = {n: np.stack([project(e, view, proj, SIZE) for e in es]) for n, es in edges.items()}
    per_level = {(n, k): {} for n in edges for k in range(4)}
    for name, level, points in _pieces(drawing):
        k = _edge_of(points, edges2d[name])
        per_level[(name, level)][k] = per_level[(name, level)].get(k, 0.0) + _length(points)
        # the oracle at points along the piece, away from its ends (a switch is within a pixel)
        a, b = edges2d[name][k]
        direction = (b - a) / np.linalg.norm(b - a)
        s = (points - a) @ direction
        for t in np.linspace(s.min(), s.max(), 9)[1:-1]:
            if min(t - s.min(), s.max() - t) < 1.5:
                continue
            p3 = edges[name][k][0] + (edges[name][k][1] - edges[name][k][0]) * t / np.linalg.norm(b - a)
            assert boxes_in_front(p3, toward_eye, [outer, inner]) == level, (name, k, level)

    levels = {
        n: {
            k: sorted(level for (m, level), got in per_level.items() if m == n and k in got)
            for k in range(12)
        }
        for n in edges
    }
    outer_levels = sorted(tuple(v) for v in levels["outer"].values())
    inner_levels = sorted(tuple(v) for v in levels["inner"].values())
    assert outer_levels == [(0,)] * 9 + [(1, 3)] * 3
    assert inner_levels == [(1,)] * 9 + [(2,)] * 3
    # every edge is drawn over its whole projected length
    for name in edges:
        for k in range(12):
            drawn = sum(per_level[(name, level)].get(k, 0.0) for level in range(4))
            assert drawn == pytest.approx(_length(edges2d[name][k]), abs=1.0)


def test_cylinder_only_the_back_of_the_bottom_rim_is_hidden(renderer):
    """A 64-sided upright prism seen from above in perspective: the outline, the top rim and
    the front half of the bottom rim are visible; the back half of the bottom rim is behind
    the side wall. Its curved wall must not hide its own silhouettes (perspective tolerance)."""
    model = assemble({"can": prism([1.0], 2.0, 64, axis=1)})
    cam = Camera.fit(model.positions, "iso", fov=40, aspect=1.0)
    drawing = draw_vector(model, cam, SIZE, renderer=renderer)
    view, proj = cam.view_matrix(), cam.projection_matrix()
    eye = np.array(cam.eye)
    ring = np.stack([np.cos(np.linspace(0, 2 * math.pi, 513)), np.sin(np.linspace(0, 2 * math.pi, 513))], 1)
    bottom3d = np.column_stack([ring[:, 1], np.full(513, -1.0), ring[:, 0]])
    bottom = project(bottom3d, view, proj, SIZE)
    hidden_length = 0.0
    for _, level, points in _pieces(drawing):
        assert level in (0, 1)
        if level == 1:
            # on the bottom rim, on the side turned away from the eye
            near = point_segment_distance(points, np.stack([bottom[:-1], bottom[1:]], 1)).min(axis=1)
            assert near.max() < 1.0
            hidden_length += _length(points)
    # the rim's back half: points whose outward normal faces away from the eye (horizontally)
    outward = bottom3d * np.array([1, 0, 1])
    away = np.einsum("ij,ij->i", outward, eye - bottom3d) < 0
    expected = np.linalg.norm(np.diff(bottom, axis=0), axis=1)[away[:-1] & away[1:]].sum()
    assert hidden_length == pytest.approx(expected, rel=0.05)


def test_view_that_sees_nothing_gives_an_empty_drawing(renderer):
    model = assemble({"cube": box((-1, -1, -1), (1, 1, 1))})
    away = Camera(eye=(0, 0, 10), target=(0, 0, 20), up=(0, 1, 0), near=0.1, far=100.0)
    drawing = draw_vector(model, away, (64, 64), renderer=renderer)
    assert len(drawing) == 0 and drawing.layers == 0 and drawing.lines_per_level() == {}


def test_seam_between_touching_solids_of_one_part_is_not_drawn(renderer):
    """A lid box sitting flush on a base box, both in one part: their faces continue one plane
    at the seam, so the drawing (like the raster) shows no line there; the outline stays."""
    base, lid = box((0, 0, 0), (2, 1, 1)), box((0, 1, 0), (2, 1.25, 1))
    model = assemble({"body": (np.vstack([base[0], lid[0]]), np.vstack([base[1], lid[1] + 8]))})
    cam = Camera.fit(model.positions, "iso", azimuth=30, elevation=25, aspect=1.0)
    view, proj = cam.view_matrix(), cam.projection_matrix()
    drawing = draw_vector(model, cam, SIZE, renderer=renderer)
    # the seam's visible stretches: the front and right edges of the plane y = 1
    seam = np.array([[[0, 1, 1], [2, 1, 1]], [[2, 1, 1], [2, 1, 0]]], float)
    seam2d = np.stack([project(s, view, proj, SIZE) for s in seam])
    visible = [p for _, level, p in _pieces(drawing) if level == 0]
    on_seam = sum(_length(p) for p in visible if point_segment_distance(p, seam2d).min(axis=1).max() < 0.5)
    assert on_seam < 2.0
    # while the outline of the whole is all there: the lid's top edges, for one
    top = project(np.array([[0, 1.25, 1], [2, 1.25, 1]], float), view, proj, SIZE)
    assert sum(
        _length(p) for p in visible if point_segment_distance(p, top[None]).max() < 0.5
    ) == pytest.approx(_length(top), abs=1.0)


def test_layers_gathered_at_the_probed_pixels_give_the_same_drawing(renderer):
    """A drawing peels its layers' triangles only at the pixels occlusion probes
    (``Renderer.triangles_at``); with every pixel of the layers it comes out the same."""
    import blueprint
    from blueprint import examples

    model = examples.gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    layers = blueprint.peel(model, camera=camera, size=SIZE, max_layers=8, renderer=renderer, normals=False)
    gathered = draw_vector(model, camera, SIZE, renderer=renderer)
    full = draw_vector(model, camera, SIZE, renderer=renderer, layers=layers)
    assert len(gathered) > 50 and gathered.layers == full.layers == len(layers.depth)
    assert np.array_equal(gathered.level, full.level)
    assert np.array_equal(gathered.offsets, full.offsets)
    assert np.array_equal(gathered.points, full.points)


@pytest.mark.parametrize("max_layers", [None, 3, 8])
@pytest.mark.parametrize("way", ["k-buffer", "A-buffer", "peel"])
def test_triangles_at_pixels_are_the_peeled_layers_there(renderer, way, max_layers):
    """Up to eight layers come from one k-buffer pass where the driver has one, read as the
    pass leaves them, and every layer from an A-buffer's lists read at the pixels in place;
    the same faces as the layers peeled one at a time."""
    import blueprint
    from blueprint import examples

    default = capture_table(renderer)
    row = default.row(way)
    if way == "k-buffer" and (row is None or row.interlock):
        pytest.skip("the faces-only k-buffer needs framebuffer fetch, which this driver lacks")
    if way == "A-buffer":
        if row is None:
            pytest.skip("the A-buffer needs OpenGL 4.3")
        row = replace(row, min_layers=1)
    model = examples.gearbox()
    camera = Camera.fit(model.positions, "front", aspect=4 / 3)
    size = (96, 72)
    saved = renderer.capture_table
    peeled = CaptureTable((default.row("peel"),), default.exact_depth)
    renderer.capture_table = peeled
    layers = blueprint.peel(
        model, camera=camera, size=size, renderer=renderer, normals=False, max_layers=max_layers
    )
    pixels = np.random.default_rng(1).choice(size[0] * size[1], 500, replace=False)
    if way != "peel":
        renderer.capture_table = CaptureTable((row, default.row("peel")), default.exact_depth)
    try:
        faces = renderer.triangles_at(model, camera, pixels, size=size, max_layers=max_layers)
    finally:
        renderer.capture_table = saved
    expected = layers.triangle.reshape(len(layers.depth), -1)[:, pixels]
    assert faces.shape == expected.shape and (faces[:3] >= 0).any(axis=1).all()
    assert np.array_equal(faces, expected)
    with pytest.raises(blueprint.BlueprintError):
        renderer.triangles_at(model, camera, [size[0] * size[1]], size=size)


def test_faces_read_from_the_lists_in_blocks_are_read_whole(renderer, monkeypatch):
    """The A-buffer's faces at many pixels come back a block of pixels a dispatch: split into
    blocks of seven pixels, the same faces as read in one."""
    from blueprint import examples
    from blueprint.render import abuffer

    default = capture_table(renderer)
    row = default.row("A-buffer")
    if row is None:
        pytest.skip("the A-buffer needs OpenGL 4.3")
    model = examples.gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    pixels = np.random.default_rng(2).choice(64 * 64, 300, replace=False)
    saved = renderer.capture_table
    renderer.capture_table = CaptureTable(
        (replace(row, min_layers=1), default.row("peel")), default.exact_depth
    )
    try:
        whole = renderer.triangles_at(model, camera, pixels, size=(64, 64))
        monkeypatch.setattr(abuffer, "FACES_BYTES", 4 * len(whole) * 7)
        blocks = renderer.triangles_at(model, camera, pixels, size=(64, 64))
    finally:
        renderer.capture_table = saved
    assert len(whole) >= 4 and (whole[3] >= 0).any()
    assert np.array_equal(blocks, whole)


def test_depth_masking_peels_only_until_the_parts_show(renderer):
    """reveal: the same layers as the raster's depth masking, and no line deeper than them."""
    from blueprint import examples
    from blueprint.api import render_frame
    from blueprint.errors import InputError

    model = examples.gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    full = draw_vector(model, camera, SIZE, renderer=renderer)
    masked = draw_vector(model, camera, SIZE, highlight="gea*", reveal=0.6, renderer=renderer)
    frame = render_frame(
        model, camera=camera, size=SIZE, supersample=1, highlight="gear", reveal=0.6, renderer=renderer
    )
    assert masked.layers == frame.layers < full.layers
    assert masked.level.max() == masked.layers - 1 < full.level.max()
    assert masked.highlight == {model.part_names.index("gear")}
    with pytest.raises(InputError, match="reveal needs parts"):
        draw_vector(model, camera, SIZE, reveal=0.6, renderer=renderer)
    with pytest.raises(InputError, match=r"reveal must be in \(0, 1\]"):
        draw_vector(model, camera, SIZE, highlight="gear", reveal=1.5, renderer=renderer)


def test_highlight_by_a_second_model_on_the_command_line(tmp_path):
    """--highlight-model: the parts a second file lies on, drawn in the highlight colour."""
    import subprocess
    import sys
    from pathlib import Path

    import trimesh

    from blueprint import examples

    model = examples.gearbox()
    index = model.part_names.index("gear")
    trimesh.Trimesh(model.positions, model.faces[model.face_part == index]).export(tmp_path / "gear.stl")
    out = tmp_path / "hl.svg"
    exe = Path(sys.executable).with_name("blueprint")
    args = [exe, "render", examples.example_path(), "-o", out, "--size", "160", "120"]
    done = subprocess.run(
        [*args, "--highlight-model", tmp_path / "gear.stl", "--up", "y"], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    root = ET.parse(out).getroot()
    group = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "gear")
    colour = "#" + "".join(f"{round(c * 255):02x}" for c in vector_style("blueprint").highlight_color)
    # the stroke on each level's group (a kind's path repeats it only where it differs)
    assert {g.get("stroke") for g in group.findall(f"{SVG}g")} == {colour}
    assert {p.get("stroke") for p in group.iter(f"{SVG}path")} <= {colour, None}
    other = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "cover")
    assert colour not in {g.get("stroke") for g in other.iter(f"{SVG}g")}


@pytest.mark.parametrize("block", [1, 3, 7, None])
def test_samples_of_polylines_equal_those_made_segment_by_segment(block, monkeypatch):
    """``sample_polylines`` lays out every sample in its final place, a block of points at a
    time (of one point, three, seven and the default here, so blocks end inside polylines
    and at their ends): each equals, bit for bit, the samples made polyline by polyline and
    segment by segment (``count`` samples from a segment's first point, the polyline's last
    point after them with its last segment's faces, kind and edge), lines partly behind the
    eye included."""
    from blueprint.scene.camera import clip_to_pixels, transform
    from blueprint.vector.lines import Polylines
    from blueprint.vector.occlusion import samples
    from blueprint.vector.occlusion.samples import sample_polylines

    if block is not None:
        monkeypatch.setattr(samples, "_POINTS", block)

    rng = np.random.default_rng(8)
    sizes = rng.integers(2, 6, 40)
    offsets = np.r_[0, np.cumsum(sizes)]
    points = rng.normal(size=(offsets[-1], 3)) * [1.0, 1.0, 2.0]
    lines = Polylines(
        points,
        offsets,
        rng.integers(0, 99, (offsets[-1], 2)),
        np.zeros(40, np.int32),
        rng.integers(0, 5, offsets[-1]).astype(np.uint8),
        rng.integers(-1, 999, offsets[-1]),
    )
    camera = Camera(
        eye=(0.0, 0.0, 3.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), near=0.1, far=9.0, fov=60.0
    )
    view, projection = camera.view_matrix(), camera.projection_matrix()
    got = sample_polylines(lines, view, projection, (64, 64), 1.5)
    pix = clip_to_pixels(transform(points, projection @ view), (64, 64))
    w = transform(points, projection @ view)[:, 3]
    model, rows, vertex, line = [], [], [], []
    for i in range(40):
        for j in range(offsets[i], offsets[i + 1] - 1):
            length = float(np.linalg.norm(pix[j + 1] - pix[j]))
            length = length if w[j] > 0 and w[j + 1] > 0 and math.isfinite(length) else 0.0
            count = min(max(math.ceil(length / 1.5), 1), 1 << 16)
            for k in range(count):
                model.append(points[j] + (k / count) * (points[j + 1] - points[j]))
                rows.append(j), vertex.append(k == 0), line.append(i)
        model.append(points[offsets[i + 1] - 1])
        rows.append(offsets[i + 1] - 2), vertex.append(True), line.append(i)
    eye = transform(np.array(model), view)
    assert got.eye.tobytes() == eye[:, :3].tobytes()
    clip = eye @ projection.T
    assert got.pixel.tobytes() == clip_to_pixels(clip, (64, 64)).tobytes()
    w_s = clip[:, 3]
    inside = (
        (w_s > 0) & (np.abs(clip[:, 2]) <= w_s) & (np.abs(clip[:, 0]) <= w_s) & (np.abs(clip[:, 1]) <= w_s)
    )
    np.testing.assert_array_equal(got.inside, inside)
    assert 0 < inside.sum() < len(inside)
    np.testing.assert_array_equal(got.faces, lines.faces[rows])
    np.testing.assert_array_equal(got.kind, lines.kind[rows])
    np.testing.assert_array_equal(got.edge, lines.edge[rows])
    np.testing.assert_array_equal(got.vertex, vertex)
    np.testing.assert_array_equal(got.line, line)
    assert len(got.line) > 2 * len(points)


@pytest.mark.parametrize("threads", [1, 4])
def test_the_direction_across_each_line_found_once_equals_that_of_its_neighbours(threads, monkeypatch):
    """``Samples.across`` finds every sample's unit vector across its line at once (a block of
    samples a thread: blocks of 16 over four threads here, ending inside lines and at their
    ends); at each sample it equals the one from its neighbours on the same line (itself at a
    line's ends), and samples whose neighbours lie on them have none."""
    from blueprint import parallel, settings
    from blueprint.vector.occlusion.samples import Samples

    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)

    rng = np.random.default_rng(6)
    line = np.repeat(np.arange(50), rng.integers(1, 9, 50))
    pixel = np.round(rng.normal(size=(len(line), 2)) * 3.0)  # repeated points: no direction
    pixel[5:8] = pixel[6]
    n = len(line)
    zeros = np.zeros(n, np.int64)
    samples = Samples(np.zeros((n, 3)), pixel, np.zeros((n, 2), np.int64), zeros, zeros, line, zeros, zeros)
    good, across = samples.across
    for i in range(n):
        ahead = pixel[i + 1] if i + 1 < n and line[i + 1] == line[i] else pixel[i]
        behind = pixel[i - 1] if i > 0 and line[i - 1] == line[i] else pixel[i]
        tangent = ahead - behind
        length = float(np.hypot(*tangent))
        assert good[i] == (length > 0)
        if length > 0:
            np.testing.assert_allclose(across[i], [-tangent[1] / length, tangent[0] / length], rtol=1e-15)
    assert 0 < good.sum() < n


def test_probed_pixels_marked_in_blocks_on_several_threads_are_one_threads(monkeypatch):
    """The pixels the occlusion probes, marked a block of samples a thread: over blocks of a
    few samples on three threads, those of one."""
    from blueprint import parallel, settings
    from blueprint.examples import gearbox
    from blueprint.vector.lines import join_polylines, model_segments
    from blueprint.vector.occlusion.pixels import probe_pixels
    from blueprint.vector.occlusion.samples import sample_polylines

    model = gearbox()
    camera = Camera.fit(model.positions, "iso", aspect=1.0)
    view, projection = camera.view_matrix(), camera.projection_matrix()
    lines = join_polylines(model_segments(model, view, projection, (256, 256)))
    samples = sample_polylines(lines, view, projection, (256, 256))
    monkeypatch.setattr(settings, "THREADS", 1)
    want = probe_pixels(samples, (256, 256))
    monkeypatch.setattr(settings, "THREADS", 3)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 64)
    np.testing.assert_array_equal(probe_pixels(samples, (256, 256)), want)
    assert len(samples.pixel) > 1000 and len(want) > 1000
