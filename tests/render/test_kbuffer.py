"""The k-buffer peel (several layers a geometry pass, render/glsl/kbuffer.frag) finds the same
layers as the peel that draws the model once a layer: same depths, normals, triangles and parts,
in whatever order the triangles come, and over more layers than one pass holds. The ray-casting
oracle checks both ways against the geometry (test_layers_oracle.py); this checks them against
each other, normals included, and the drawings they make."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from capture_helpers import (
    CASES,
    assert_front_to_back,
    drawing_difference,
    nested_boxes,
    nested_round,
    normal_tolerance,
    peel_both_ways,
    planes,
    sphere_in_cube,
)

from blueprint import examples
from blueprint.bench import time_frames
from blueprint.render.table import (
    KBUFFER_MAX,
    KBUFFER_MAX_BYTES,
    CaptureTable,
    PeelRow,
    Request,
    capture_table,
    choose,
)
from blueprint.scene.camera import fit_camera


@pytest.fixture
def kbuffer(renderer):
    """Switches the renderer between both ways (its capture table: the k-buffer whatever the
    density, or a pass a layer; the A-buffer, test_abuffer.py, off either way)."""
    default = capture_table(renderer)
    row = default.row("k-buffer")
    if row is None:
        pytest.skip("this driver has neither framebuffer fetch nor fragment shader interlock: no k-buffer")
    saved = renderer.capture_table
    peel = default.row("peel")

    def use(on: bool) -> None:
        rows = (replace(row, min_density=0.0, whole_frames=False), peel) if on else (peel,)
        renderer.capture_table = CaptureTable(rows, default.exact_depth)

    use.interlock = row.interlock
    yield use
    renderer.capture_table = saved


@pytest.fixture
def surfaces_kbuffer(renderer, kbuffer):
    """``kbuffer``, where one k-buffer pass can leave every layer in its surfaces for the edges
    to read there: through framebuffer fetch alone (Capture, ``surfaces``)."""
    if kbuffer.interlock:
        pytest.skip("the k-buffer runs under fragment shader interlock here: its layers are unpacked")
    return kbuffer


@pytest.mark.parametrize("order", [[0, 1, 2], [2, 1, 0], [1, 0, 2], [2, 0, 1]])
def test_any_drawing_order_gives_the_layers_front_to_back(renderer, kbuffer, order):
    kbuffer(True)
    assert_front_to_back(renderer, order)


@pytest.mark.parametrize("max_layers", [None, 3, 10], ids=["all", "3", "10"])
@pytest.mark.parametrize("name", list(CASES))
def test_same_layers_as_a_pass_a_layer(renderer, kbuffer, name, max_layers):
    make, camera = CASES[name]
    fast, plain = peel_both_ways(renderer, kbuffer, make(), size=(160, 120), max_layers=max_layers, **camera)
    assert fast.depth.shape == plain.depth.shape
    covered = plain.depth < 1.0
    assert covered.sum() > 0
    same = (
        (fast.depth == plain.depth)
        & (fast.triangle == plain.triangle)
        & (fast.part == plain.part)
        & (np.abs(fast.normal - plain.normal) <= normal_tolerance(renderer)).all(axis=-1)
    )
    # two surfaces about one peeling tolerance apart may be merged either way: a handful of pixels
    assert (~same).sum() <= max(2, 1e-4 * covered.sum()), f"{(~same).sum()} of {covered.sum()} differ"


def test_more_layers_than_one_pass_holds(renderer, kbuffer):
    """Up to ten surfaces a ray: the second pass starts behind the first pass's last layer."""
    view = dict(size=(96, 96), azimuth=20.0, elevation=35.0)
    fast, plain = peel_both_ways(renderer, kbuffer, nested_round(), **view)
    assert len(plain.depth) > KBUFFER_MAX
    assert np.array_equal(fast.depth, plain.depth)
    assert np.array_equal(fast.triangle, plain.triangle)


def test_layer_counts_are_covered_pixels(renderer, kbuffer):
    model = examples.gearbox()
    kbuffer(True)
    frame = renderer.render(model, size=(128, 96), max_layers=None, supersample=1)
    layers = renderer.peel(model, size=(128, 96), max_layers=None)
    assert frame.layers == len(layers.depth)
    assert frame.layer_pixels[: frame.layers] == [int(c) for c in (layers.depth < 1.0).sum(axis=(1, 2))]
    assert frame.layer_pixels[frame.layers :] in ([], [0])


@pytest.mark.parametrize("supersample", [1, 2])
@pytest.mark.parametrize("style", ["blueprint", "paper"])
def test_same_drawing(renderer, kbuffer, style, supersample):
    diff = drawing_difference(kbuffer, style, supersample)
    if normal_tolerance(renderer) == 0.0:
        assert (diff == 0).all(), f"{(diff > 0).sum()} pixels differ"
    assert (diff > 2).mean() <= 1e-3, f"{(diff > 2).sum()} pixels differ"


def test_used_only_where_it_pays(renderer):
    """From the row's ``min_density`` triangles per G-buffer pixel, never for one layer, and not
    where its targets would take more than its ``max_bytes`` (KBUFFER_MAX_BYTES)."""
    row = capture_table(renderer).row("k-buffer")
    if row is None:
        pytest.skip("this driver has neither framebuffer fetch nor fragment shader interlock: no k-buffer")
    row = replace(row, whole_frames=False)
    model = examples.gearbox()
    mesh = renderer.mesh(model, 30.0)
    side = int(np.sqrt(mesh.triangles / row.min_density)) + 2
    assert row.max_bytes == KBUFFER_MAX_BYTES

    def kbuffered(size, batch: int, row=row) -> bool:
        request = Request(size, mesh.triangles, batch)
        return choose(CaptureTable((row, PeelRow())), request)[0].way == "k-buffer"

    assert kbuffered((64, 64), 5)
    assert not kbuffered((64, 64), 1)
    assert not kbuffered((side, side), 5)
    assert not kbuffered((64, 64), 5, replace(row, max_bytes=16 * 5 * 64 * 64 - 1))


@pytest.mark.parametrize(("supersample", "batch"), [(1, 8), (2, 8), (1, 3), (2, 1)])
def test_edges_from_the_surfaces_are_those_of_unpacked_layers(
    renderer, surfaces_kbuffer, monkeypatch, supersample, batch
):
    """Where one k-buffer pass finds every layer of a frame its edges read the surfaces, unpacked
    (edges_surfaces.frag), ``batch`` layers a pass: the same drawing, covered pixels and layers
    left as from the layers unpacked into the G-buffer, depths rounded as the 24-bit depth
    target rounds them."""
    from blueprint.pipeline.layers import LayerCapture

    surfaces_kbuffer(True)
    model = examples.gearbox()
    options = dict(size=(160, 120), max_layers=4, supersample=supersample)
    ex = renderer.executor
    monkeypatch.setattr(ex, "edge_batch", batch)
    passes = []
    run_pass = type(ex).run_pass

    def watch(self, st, name, layer, layers, span=1):
        if name in st.from_surfaces:
            passes.append(span)
        run_pass(self, st, name, layer, layers, span)

    monkeypatch.setattr(type(ex), "run_pass", watch)
    direct = renderer.render(model, **options)
    assert renderer.executor.last_run.from_surfaces == ("edges",)
    assert passes == [min(batch, 4 - k) for k in range(0, 4, batch)]
    monkeypatch.setattr(LayerCapture, "_from_surfaces", lambda self, st: ())
    unpacked = renderer.render(model, direct.camera, **options)
    assert renderer.executor.last_run.from_surfaces == ()
    assert direct.layers_left > 0
    counts = (direct.layers, direct.layer_pixels, direct.layers_left)
    assert counts == (unpacked.layers, unpacked.layer_pixels, unpacked.layers_left)
    np.testing.assert_array_equal(direct.image, unpacked.image)


@pytest.mark.parametrize("batch", [8, 3])
def test_edges_from_one_array_of_the_surfaces_are_those_from_a_sampler_each(
    renderer, surfaces_kbuffer, monkeypatch, batch
):
    """The surfaces as the slices of one array read by one sampler (``TargetPool.sliced``), or
    as textures of their own read by a sampler each: the same drawing, batches starting at
    every layer."""
    from blueprint.gpu.targets import TargetPool

    if not renderer.pool.slices_viewed:
        pytest.skip("this context makes no texture views")
    surfaces_kbuffer(True)
    monkeypatch.setattr(renderer.executor, "edge_batch", batch)
    model = examples.gearbox()
    options = dict(size=(160, 120), max_layers=6, supersample=1)
    sliced = renderer.render(model, **options)
    assert renderer.executor.last_run.groups[0].capture.source.defines["SURFACE_ARRAY"]
    monkeypatch.setattr(TargetPool, "slices_viewed", property(lambda self: False))
    apart = renderer.render(model, sliced.camera, **options)
    assert not renderer.executor.last_run.groups[0].capture.source.defines["SURFACE_ARRAY"]
    assert renderer.executor.last_run.from_surfaces == ("edges",)
    assert (sliced.layers, sliced.layer_pixels) == (apart.layers, apart.layer_pixels)
    np.testing.assert_array_equal(sliced.image, apart.image)


@pytest.mark.parametrize("cap", [2, 3, 5, 7])
def test_a_capped_frame_counts_the_layers_it_leaves_in_one_pass(renderer, surfaces_kbuffer, monkeypatch, cap):
    """The k-buffer pass that finds every layer of a capped frame counts the surfaces each pixel
    let go behind its K: no counting pass runs (remaining.py), and the layers drawn and left
    add up to those the frame draws without a cap (peeled in batches, unpacked)."""
    from blueprint.pipeline import layers

    def no_counting_pass(*args):
        raise AssertionError("a counting pass ran")

    options = dict(size=(160, 120), supersample=1)
    capped_some = False
    for model, view in ((examples.gearbox(), "iso"), (nested_round(), "front"), (sphere_in_cube(), "top")):
        surfaces_kbuffer(True)
        camera = fit_camera(model, options["size"], view)
        full = renderer.render(model, camera, max_layers=None, **options)
        if full.layers <= cap:
            continue
        capped_some = True
        with monkeypatch.context() as m:
            m.setattr(layers, "layers_left", no_counting_pass)
            capped = renderer.render(model, camera, max_layers=cap, **options)
        assert renderer.executor.last_run.from_surfaces == ("edges",)
        assert (capped.layers, capped.layers + capped.layers_left) == (cap, full.layers), view
    assert capped_some


def test_a_fragment_part_of_a_held_surface_is_no_layer_left(renderer, surfaces_kbuffer):
    """Squares at depths 0, 1 and 1 again, drawn in that order, capped at 2: the third is part
    of the second surface held, so the frame leaves no layer behind (the peel draws two)."""
    surfaces_kbuffer(True)
    model = planes([0, 1, 1])
    options = dict(size=(64, 64), supersample=1)
    camera = fit_camera(model, options["size"], "front")
    assert renderer.render(model, camera, max_layers=None, **options).layers == 2
    capped = renderer.render(model, camera, max_layers=2, **options)
    assert (capped.layers, capped.layers_left) == (2, 0)


def test_surfaces_an_earlier_frame_left_change_nothing(renderer, surfaces_kbuffer, monkeypatch):
    """Only a k-buffer's first surface and its count are cleared before a pass: the surfaces
    a deeper frame left behind a pixel's last one are never read as layers. A frame drawn over
    them is the one drawn from its layers unpacked (where the count alone says what is held)."""
    from blueprint.pipeline.layers import LayerCapture

    surfaces_kbuffer(True)
    model = examples.gearbox()
    options = dict(size=(160, 120), max_layers=5, supersample=1)
    boxes = nested_boxes()  # five layers over most of the frame
    deep = renderer.render(boxes, fit_camera(boxes, (160, 120), "front"), **options)
    over = renderer.render(model, fit_camera(model, (160, 120), "iso"), **options)
    assert renderer.executor.last_run.from_surfaces == ("edges",)
    assert deep.layers == 5
    monkeypatch.setattr(LayerCapture, "_from_surfaces", lambda self, st: ())
    unpacked = renderer.render(model, over.camera, **options)
    np.testing.assert_array_equal(over.image, unpacked.image)


def test_bench_names_the_way_the_layers_were_found(renderer, kbuffer):
    """``blueprint bench``'s ``capture`` (``Capture.way``): the k-buffer where it found the
    layers, ``peel`` where a geometry pass drew each."""
    model = examples.gearbox()
    camera = fit_camera(model, (64, 64))
    options = dict(size=(64, 64), max_layers=3, supersample=1, style="blueprint", frames=1, warmup=0)
    for on, way in ((True, "k-buffer"), (False, "peel")):
        kbuffer(on)
        assert time_frames(renderer, model, camera, **options)["capture"] == way
