"""The A-buffer's fragments listed by the compute rasteriser (render/raster.py,
``ABufferRow.compute_from``) against the graphics pipeline's: the same fragments, and the
same layers at every pixel but where two faces tie in depth (coincident faces: there the
rasteriser's rounding and ours each pick one), with the bins' room short (drawn again)
and in views it must leave to the graphics pipeline (a corner of the model behind the eye). The
ray-casting oracle checks it against the geometry (test_layers_oracle.py, a-buffer-compute)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from capture_helpers import nested_boxes, nested_round, peel_both_ways

import blueprint
from blueprint import examples
from blueprint.bench import time_frames
from blueprint.render import raster
from blueprint.render.abuffer import ABufferSource
from blueprint.render.gbuffer import abuffer_uniforms, depth_tolerance
from blueprint.render.raster import REACH, ComputeRaster
from blueprint.render.table import CaptureTable, capture_table
from blueprint.scene.camera import Camera, fit_camera

# window depths of the two rasterisers at one surface: the plane through the projected corners
# against the driver's interpolation from corners snapped to 1/256 px, apart by the snap times
# the depth's slope a pixel (the gearbox: 1.2e-5 at most, beyond 1e-6 at 1 % of its surfaces).
# The depths' own accuracy is the oracle's to judge (test_layers_oracle.py).
DEPTH_APART = 1e-4


@pytest.fixture
def capture(renderer):
    """Switches the renderer's A-buffer (always on, whole fragments) between the graphics
    pipeline's fragments and the compute rasteriser's, through its capture table; ``capture.
    start(pixels)`` lists G-buffers from that size in compute."""
    if renderer.ctx.version_code < 430:
        pytest.skip("the A-buffer needs OpenGL 4.3 (storage buffers and compute shaders)")
    saved = renderer.capture_table
    default = capture_table(renderer)
    rooms = dict(renderer.compute_raster.rooms)

    def start(pixels: int | None) -> None:
        listed = replace(default.row("A-buffer"), max_bytes=1 << 28, min_layers=2, compute_from=pixels)
        renderer.capture_table = CaptureTable((listed, default.row("peel")), default.exact_depth)

    def use(compute: bool) -> None:
        start(0 if compute else None)

    use.start = start
    yield use
    renderer.capture_table = saved
    renderer.compute_raster.rooms.clear()
    renderer.compute_raster.rooms.update(rooms)


@pytest.mark.parametrize(
    "make, view",
    [
        (nested_boxes, dict(azimuth=30.0, elevation=25.0)),
        (nested_round, dict(azimuth=20.0, elevation=35.0)),
        (examples.gearbox, {}),
        (examples.gearbox, dict(view="front", ortho=True)),
    ],
    ids=["nested-boxes", "nested-round", "gearbox", "gearbox-front-ortho"],
)
def test_compute_lists_the_graphics_pipelines_layers(renderer, capture, make, view):
    model = make()
    compute, graphics = peel_both_ways(renderer, capture, model, size=(96, 80), **view)
    assert len(compute.depth) == len(graphics.depth) >= 2
    count = (compute.depth < 1).sum(0), (graphics.depth < 1).sum(0)
    other = count[0] != count[1]
    # two surfaces about the peel's tolerance apart are one layer or two by rounding: on a face
    # seen edge-on the driver's depth from corners snapped to 1/256 px and the true plane's
    # differ by the snap times the slope (the gearbox: one pixel of 7 680)
    assert other.sum() <= 1e-3 * (count[1] > 0).sum(), f"{other.sum()} pixels with other layer counts"
    covered = (graphics.depth < 1) & ~other
    apart = np.abs(compute.depth - graphics.depth)[covered]
    assert apart.max() <= DEPTH_APART
    # faces that tie in depth (coincident faces: the same depth within rounding) are the ones
    # whose order either rasteriser's rounding decides
    same_face = compute.triangle == graphics.triangle
    assert same_face[covered].mean() >= 0.998
    assert np.array_equal(compute.part[covered & same_face], graphics.part[covered & same_face])


def test_set_up_in_rows_of_workgroups(renderer, capture, monkeypatch):
    """Models of more triangles than one dispatch dimension's workgroups (a driver may allow
    only 65535) are set up over rows of workgroups: forced here with rows of three, the layers
    are the one-row dispatch's."""
    model = examples.gearbox()
    options = dict(size=(96, 80))
    capture(True)
    one_row = blueprint.peel(model, renderer=renderer, **options)
    monkeypatch.setattr(raster, "ACROSS", 3)
    rows = blueprint.peel(model, renderer=renderer, **options)
    assert -(-model.triangle_count * raster.ROWS // 64) > 3 * 3
    assert len(one_row.depth) >= 2
    assert np.array_equal(rows.depth, one_row.depth)
    assert np.array_equal(rows.triangle, one_row.triangle)


def test_short_bins_are_drawn_again(renderer, capture):
    model = nested_round()
    options = dict(size=(96, 96), azimuth=20.0, elevation=35.0)
    capture(True)
    full = blueprint.peel(model, renderer=renderer, **options)
    renderer.compute_raster.rooms[(96, 96)] = 8  # far fewer triangle-tile pairs than it lists
    again = blueprint.peel(model, renderer=renderer, **options)
    assert renderer.compute_raster.rooms[(96, 96)] > 8
    assert np.array_equal(again.depth, full.depth)
    assert np.array_equal(again.triangle, full.triangle)


def test_views_it_cannot_draw_go_to_the_graphics_pipeline(renderer, capture, monkeypatch):
    """A camera inside the model (corners of its bounds behind the eye: the graphics pipeline
    clips them) is drawn by the graphics pipeline, its layers the same."""
    model = nested_boxes()
    camera = Camera(eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0), near=0.05, far=20.0)
    listed = []
    fragments = ComputeRaster.fragments
    monkeypatch.setattr(ComputeRaster, "fragments", lambda *a: listed.append(1) or fragments(*a))
    compute, graphics = peel_both_ways(renderer, capture, model, size=(64, 64), camera=camera)
    assert not listed
    assert np.array_equal(compute.depth, graphics.depth)
    compute, graphics = peel_both_ways(renderer, capture, model, size=(64, 64))
    assert listed, "a view from outside the model is listed in compute"


def test_what_it_sees(renderer):
    raster = renderer.compute_raster
    model = nested_boxes()
    size = (256, 256)

    def uniforms(camera):
        return abuffer_uniforms(camera, depth_tolerance(camera, model.bounds))

    assert raster.sees(model.bounds, uniforms(fit_camera(model, size)), size)
    inside = Camera(eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0), near=0.05, far=20.0)
    assert not raster.sees(model.bounds, uniforms(inside), size)
    # in front of the eye, but projected past the range its edge tests stay exact in
    near = Camera(eye=(0.0, 0.0, 2.0 + 1e-4), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), near=1e-5, far=20.0)
    assert not raster.sees(model.bounds, uniforms(near), (4096, 4096))
    assert REACH <= 1 << 17


def test_frames_below_its_size_stay_with_the_graphics_pipeline(renderer, capture, monkeypatch):
    """``ABufferRow.compute_from`` is the G-buffer size from which the compute rasteriser lists a
    frame: smaller frames cost it more than the graphics pipeline (the H200: the crank case)."""
    listed = []
    fragments = ComputeRaster.fragments
    monkeypatch.setattr(ComputeRaster, "fragments", lambda *a: listed.append(a[2]) or fragments(*a))
    capture(True)
    model = nested_boxes()
    capture.start(64 * 64 + 1)
    blueprint.peel(model, renderer=renderer, size=(64, 64))
    assert not listed
    capture.start(64 * 64)
    blueprint.peel(model, renderer=renderer, size=(64, 64))
    assert listed == [(64, 64)]


def test_lists_that_fit_without_its_buffers_are_drawn_by_the_graphics_pipeline(
    renderer, capture, monkeypatch
):
    """Where the lists fit ``max_bytes`` but the rasteriser's buffers (some 150 bytes a
    triangle: a hundred million triangles' take more than their lists) would not fit beside
    them, the graphics pipeline lists the frame: the A-buffer's layers, not the peel's passes."""
    model = nested_boxes()
    options = dict(size=(64, 64), max_layers=None, supersample=1, style="blueprint", frames=2, warmup=1)
    camera = fit_camera(model, (64, 64))
    held = []
    list_bytes = ABufferSource._list_bytes
    monkeypatch.setattr(
        ABufferSource, "_list_bytes", lambda self, room: held.append(list_bytes(self, room)) or held[-1]
    )
    capture(True)
    assert time_frames(renderer, model, camera, **options)["capture"] == "A-buffer, compute rasteriser"
    lists, buffers = held[-1], renderer.compute_raster.bytes((64, 64), model.triangle_count)
    table = renderer.capture_table
    for max_bytes, way in (
        (lists + buffers, "A-buffer, compute rasteriser"),
        (lists + buffers - 1, "A-buffer"),
        (lists, "A-buffer"),
        (lists - 1, "peel"),
    ):
        listed = replace(table.row("A-buffer"), max_bytes=max_bytes)
        renderer.capture_table = CaptureTable((listed, table.row("peel")), table.exact_depth)
        assert time_frames(renderer, model, camera, **options)["capture"] == way, (max_bytes, lists, buffers)


def test_bench_names_the_way_the_layers_were_found(renderer, capture):
    """``blueprint bench``'s ``capture`` (``Capture.way``) names the compute rasteriser where it
    listed the fragments, and the A-buffer alone where the graphics pipeline did: by choice, or
    for a view the rasteriser cannot draw (the camera inside the model)."""
    model = nested_boxes()
    options = dict(size=(64, 64), max_layers=None, supersample=1, style="blueprint", frames=1, warmup=0)
    outside = fit_camera(model, (64, 64))
    inside = Camera(eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), up=(0.0, 1.0, 0.0), near=0.05, far=20.0)
    for compute, camera, way in (
        (True, outside, "A-buffer, compute rasteriser"),
        (True, inside, "A-buffer"),
        (False, outside, "A-buffer"),
    ):
        capture(compute)
        assert time_frames(renderer, model, camera, **options)["capture"] == way


def test_faces_drawn_a_chunk_at_a_time(renderer, capture, monkeypatch):
    """The faces are set up, binned and rasterised a chunk at a time (a chunk's set-up fills a
    storage binding at most), each chunk appending to the lists the ones before it left: with
    chunks of a thousand faces the layers are those of one chunk, and the bins' room is that of
    the chunk with the most triangle-tile pairs."""
    model = examples.gearbox()
    options = dict(size=(400, 300))
    capture(True)
    rooms = renderer.compute_raster.rooms
    rooms.clear()
    whole = blueprint.peel(model, renderer=renderer, **options)
    (size, whole_room), *_ = rooms.items()
    monkeypatch.setattr(renderer.compute_raster, "chunk", 1000)
    rooms.clear()
    chunked = blueprint.peel(model, renderer=renderer, **options)
    assert model.triangle_count > 2 * 1000
    assert len(whole.depth) >= 2
    assert np.array_equal(chunked.depth, whole.depth)
    assert np.array_equal(chunked.triangle, whole.triangle)
    assert np.array_equal(chunked.part, whole.part)
    # (a room is the pairs listed and a quarter more, and 1 024)
    assert 1024 < rooms[size] < 0.75 * whole_room
    # bins short for the first chunks (the last has 144 faces): drawn again with room for them
    rooms[size] = 8
    again = blueprint.peel(model, renderer=renderer, **options)
    assert np.array_equal(again.depth, whole.depth)
    assert np.array_equal(again.triangle, whole.triangle)


def test_a_chunk_fills_a_storage_binding_at_most(renderer):
    """A chunk's set-up (the largest of its buffers, ``SETUP_BYTES`` a face) takes
    ``CHUNK_BYTES`` at most, and fits the driver's storage binding limit, never 2 GiB; bins past
    a binding send the frame to the graphics pipeline."""
    computing = renderer.compute_raster
    limit = int(renderer.ctx.info["GL_MAX_SHADER_STORAGE_BLOCK_SIZE"])
    assert computing.binding == renderer.device.storage_bytes == min(limit, (1 << 31) - 1)
    most = min(computing.binding, raster.CHUNK_BYTES)
    assert raster.SETUP_BYTES * computing.chunk <= most
    assert raster.SETUP_BYTES * (computing.chunk + 1) > most
    assert computing.binding < 1 << 31
    size = (64, 64)
    assert computing.bytes(size, 10 * computing.chunk) == computing.bytes(size, computing.chunk)
    assert computing.holds(size, 10 * computing.chunk)
    computing.rooms[size] = computing.binding // raster.BIN_BYTES + 1
    try:
        assert not computing.holds(size, 1)
    finally:
        del computing.rooms[size]
