"""The A-buffer capture (every layer from one geometry pass, render/abuffer.py) finds the same
layers as the peel that draws the model once a layer: same depths (as the depth buffer holds
them), normals, triangles and parts, in whatever order the triangles come, for lists short
enough to sort in registers and for longer ones, with too little room (drawn again) and with
too little memory (peeled instead); and it counts the layers a capped frame left exactly. Each
test runs with whole fragments and with slim ones (depth and face, the rest found by the resolve:
``ABufferRow.slim``), whose normals may differ from the geometry pass's in a half's last place. The
ray-casting oracle checks the peel against the geometry (test_layers_oracle.py)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from capture_helpers import (
    CASES,
    DEPTH_STEP,
    assert_front_to_back,
    drawing_difference,
    nested_round,
    normal_tolerance,
    peel_both_ways,
    planes,
    slim_normal_tolerance,
)
from helpers import SNAPPED_GEOMETRY

import blueprint
from blueprint import examples
from blueprint.pipeline.blueprint import stream_blueprint
from blueprint.pipeline.layers import LayerCapture
from blueprint.render.abuffer import (
    BINDING_ALIGNMENT,
    FIRST_ROOM,
    MOST_LAYERS,
    NODE_BYTES,
    SURFACE_BYTES,
    ABufferSource,
    projected_fragments,
    spare_room,
)
from blueprint.render.capture import Capture, gbuffer
from blueprint.render.table import (
    KBUFFER_MAX,
    CaptureTable,
    KBufferRow,
    Request,
    capture_table,
    choose,
)
from blueprint.scene.camera import fit_camera


@pytest.fixture(params=[False, True], ids=["whole", "slim"])
def abuffer(renderer, request):
    """Switches the renderer between the A-buffer (with whole or slim fragments, by the
    parameter: ``abuffer.slim``) and peeling (a pass a layer), through its capture table."""
    if renderer.ctx.version_code < 430:
        pytest.skip("the A-buffer needs OpenGL 4.3 (storage buffers in fragment shaders)")
    saved = renderer.capture_table
    default = capture_table(renderer)
    peel = default.row("peel")
    room = dict(renderer.abuffer_room)
    # each test's frames start with no room known: what earlier tests drew at a size decides
    # whether a frame reads its counts at once or late, and so which path it takes
    renderer.abuffer_room.clear()

    def use(on: bool, max_bytes: int = 1 << 28) -> None:
        listed = replace(default.row("A-buffer"), max_bytes=max_bytes, min_layers=1, slim=request.param)
        renderer.capture_table = CaptureTable((listed, peel) if on else (peel,), default.exact_depth)

    use.slim = request.param
    yield use
    renderer.capture_table = saved
    renderer.abuffer_room.clear()
    renderer.abuffer_room.update(room)


def _differ(fast, plain, renderer, slim: bool) -> np.ndarray:
    tolerance = slim_normal_tolerance(renderer) if slim else normal_tolerance(renderer)
    same = (
        (np.abs(fast.depth - plain.depth) <= DEPTH_STEP)
        & (fast.triangle == plain.triangle)
        & (fast.part == plain.part)
        & (np.abs(fast.normal - plain.normal) <= tolerance).all(axis=-1)
    )
    return ~same


@pytest.mark.parametrize("order", [[0, 1, 2], [2, 1, 0], [1, 0, 2], [2, 0, 1]])
def test_any_drawing_order_gives_the_layers_front_to_back(renderer, abuffer, order):
    abuffer(True)
    assert_front_to_back(renderer, order)


def test_of_coincident_faces_the_first_drawn_wins(renderer, abuffer):
    """Two squares in one plane and a third behind: one layer of the first square's faces,
    then the third, as a depth test that keeps the first of equal depths draws them."""
    model = planes([0, 0, 1])
    camera = blueprint.Camera.fit(model.positions, "front", aspect=1.0, ortho=True)
    fast, plain = [], []
    for on, out in ((True, fast), (False, plain)):
        abuffer(on)
        out.append(renderer.peel(model, camera, size=(32, 32)))
    assert len(fast[0].depth) == len(plain[0].depth) == 2
    assert set(np.unique(fast[0].triangle[0])) - {-1} == {0, 1}
    assert np.array_equal(fast[0].triangle, plain[0].triangle)


@pytest.mark.parametrize("max_layers", [None, 1, 3, 10], ids=["all", "1", "3", "10"])
@pytest.mark.parametrize("name", list(CASES))
def test_same_layers_as_a_pass_a_layer(renderer, abuffer, name, max_layers):
    make, camera = CASES[name]
    fast, plain = peel_both_ways(renderer, abuffer, make(), size=(160, 120), max_layers=max_layers, **camera)
    assert fast.depth.shape == plain.depth.shape
    covered = plain.depth < 1.0
    assert covered.sum() > 0
    # two surfaces about one peeling tolerance apart may be merged either way (the depth buffer
    # a peel compares with rounds as its driver does), moving that pixel's deeper layers: a
    # handful of pixels
    differ = _differ(fast, plain, renderer, abuffer.slim).any(axis=0)
    pixels = covered.any(axis=0).sum()
    assert differ.sum() <= max(3, 1e-4 * pixels), f"{differ.sum()} of {pixels} pixels differ"


def test_lists_too_long_to_sort_in_registers(renderer, abuffer):
    """60 squares one behind the other: every list is longer than the resolve sorts in
    registers (SORTED in abuffer_resolve.comp), so each layer is found by walking it."""
    order = [int(v) for v in np.random.default_rng(3).permutation(60)]
    model = planes(order)
    camera = blueprint.Camera.fit(model.positions, "front", aspect=1.0, ortho=True)
    fast, plain = peel_both_ways(renderer, abuffer, model, camera=camera, size=(24, 24), max_layers=None)
    assert len(plain.depth) == 60
    assert not _differ(fast, plain, renderer, abuffer.slim).any()


def test_lists_of_hundreds_are_merged_in_runs(renderer, abuffer):
    """400 squares one behind the other: each list is sorted SORTED fragments at a time into
    nine runs, and the runs merged (walked once a layer, a list this long ran past llvmpipe's
    65 535 turns of a loop and lost every layer). The first ``MOST_LAYERS`` layers are the
    nearest squares, in order, at every pixel."""
    order = [int(v) for v in np.random.default_rng(5).permutation(400)]
    model = planes(order)
    camera = blueprint.Camera.fit(model.positions, "front", aspect=1.0, ortho=True)
    abuffer(True)
    layers = renderer.peel(model, camera, size=(8, 8), max_layers=None)
    assert len(layers.depth) == MOST_LAYERS
    inside = layers.depth[0] < 1.0
    assert inside.sum() > 32
    for k in range(MOST_LAYERS):
        assert set(np.unique(layers.triangle[k][inside])) <= {2 * order.index(k), 2 * order.index(k) + 1}
    assert (np.diff(layers.depth[:, inside], axis=0) > 0).all()
    # the dispatches over every group and over the listed tiles give the same layers
    mesh = renderer.mesh(model, 30.0)
    plain, _ = _tiled_layers(renderer, mesh, camera, (8, 8), False)
    tiled, _ = _tiled_layers(renderer, mesh, camera, (8, 8), True)
    assert len(plain) == MOST_LAYERS
    _assert_same_layers(tiled, plain)


def test_a_list_longer_than_a_software_sort_takes_is_peeled(renderer, abuffer):
    """2 000 squares one behind the other: a software rasteriser ends an invocation's loops after
    65 535 turns, which sorting lists this long would pass (every layer was lost): there the
    frame is peeled instead. Either way the layers are the nearest squares, in order."""
    order = [int(v) for v in np.random.default_rng(7).permutation(2000)]
    model = planes(order)
    camera = blueprint.Camera.fit(model.positions, "front", aspect=1.0, ortho=True)
    abuffer(True)
    layers = renderer.peel(model, camera, size=(8, 8), max_layers=6)
    assert len(layers.depth) == 6
    inside = layers.depth[0] < 1.0
    assert inside.sum() > 32
    for k in range(6):
        assert set(np.unique(layers.triangle[k][inside])) <= {2 * order.index(k), 2 * order.index(k) + 1}


def test_too_little_room_is_drawn_again(renderer, abuffer):
    model = nested_round()
    abuffer(True)
    options = dict(size=(96, 96), azimuth=20.0, elevation=35.0, max_layers=None)
    renderer.abuffer_room[(96, 96)] = 10
    fast = blueprint.peel(model, renderer=renderer, **options)
    room = renderer.abuffer_room[(96, 96)]
    abuffer(False)
    plain = blueprint.peel(model, renderer=renderer, **options)
    assert room > (plain.depth < 1.0).sum()
    assert not _differ(fast, plain, renderer, abuffer.slim).any()


def test_more_than_the_memory_allows_is_peeled(renderer, abuffer):
    """Lists that would take more than the row's ``max_bytes`` are not drawn: the frame is peeled
    a pass a layer instead, the same layers."""
    model = examples.gearbox()
    mesh = renderer.mesh(model, 30.0)
    camera = fit_camera(model, (64, 64))
    abuffer(True, max_bytes=NODE_BYTES * 64 * 64 * 8)
    renderer.abuffer_room[(64, 64)] = 64 * 64 * 4
    assert (
        Capture(renderer.capturer, mesh, camera, gbuffer(renderer.pool, (64, 64), "test.ab"), layers=5).way
        == "A-buffer"
    )
    # the gearbox has more fragments than 8 a pixel once counted
    renderer.abuffer_room[(64, 64)] = 64 * 64 * 9
    assert (
        Capture(renderer.capturer, mesh, camera, gbuffer(renderer.pool, (64, 64), "test.ab"), layers=5).way
        == "peel"
    )
    renderer.abuffer_room.pop((64, 64))

    def short(on: bool) -> None:
        abuffer(on, max_bytes=NODE_BYTES * 10)

    fast, plain = peel_both_ways(renderer, short, model, size=(64, 64))
    assert np.array_equal(fast.triangle, plain.triangle)


def test_projected_fragments_are_the_faces_areas_in_pixels():
    """Two faces of a square seen head on, its side a quarter of the picture's height: a
    sixteenth of the picture's pixels (a camera of aspect 1 over a picture of any shape), either
    winding; none where the square lies behind the eye."""
    half = np.sqrt(0.5)
    square = np.array([[0, -half, 0], [half, 0, 0], [0, half, 0], [-half, 0, 0]], np.float32) / 4
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    camera = blueprint.Camera(eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), near=1, far=9, ortho=True)
    assert projected_fragments(square, faces, camera, (64, 48)) == pytest.approx(64 * 48 / 16)
    assert projected_fragments(square, faces[::-1, ::-1], camera, (64, 48)) == pytest.approx(64 * 48 / 16)
    away = blueprint.Camera(eye=(0, 0, -1), target=(0, 0, -2), up=(0, 1, 0), near=0.1, far=9)
    assert projected_fragments(square, faces, away, (64, 48)) is None
    # a copy wholly off the picture draws nothing; one across its edge counts whole
    for shift, copies in ((10.0, 1), (0.5, 2)):
        both = np.r_[square, square + [shift, 0, 0]]
        twice = np.r_[faces, faces + 4]
        assert projected_fragments(both, twice, camera, (64, 48)) == pytest.approx(copies * 64 * 48 / 16)


def test_a_deep_first_frame_is_drawn_once(renderer, abuffer, monkeypatch):
    """Lists of a size not drawn before, for a frame of more than ``FIRST_ROOM`` fragments a
    pixel, take the room its faces foretell: one geometry pass, not a second one with the
    room the first found too small."""
    if not renderer.software:
        pytest.skip("the lists live in the host's memory on a software rasteriser alone")
    abuffer(True)
    model = planes(list(range(3 * FIRST_ROOM)))
    camera = blueprint.Camera.fit(model.positions, "front", aspect=1.0, ortho=True)
    size = (48, 48)
    renderer.abuffer_room.pop(size, None)
    passes = []
    fragments = ABufferSource.fragments

    def counted(self, *args):
        passes.append(1)
        return fragments(self, *args)

    monkeypatch.setattr(ABufferSource, "fragments", counted)
    layers = renderer.peel(model, camera, size=size, max_layers=None)
    assert len(layers.depth) == 3 * FIRST_ROOM
    assert len(passes) == 1


def test_first_lists_are_sized_by_the_projected_fragments(renderer, abuffer, monkeypatch):
    """On a software rasteriser the lists of a size not drawn before hold the fragments the
    faces' areas foretell, with a counted room's spare; the fragments drawn are within a
    hundredth of them, so one geometry pass holds them."""
    if not renderer.software:
        pytest.skip("the lists live in the host's memory on a software rasteriser alone")
    abuffer(True)
    model = examples.gearbox()
    size = (200, 150)
    camera = fit_camera(model, size)
    renderer.abuffer_room.pop(size, None)
    foretold = projected_fragments(model.positions, model.faces, camera, size)
    assert foretold < FIRST_ROOM * size[0] * size[1]
    rooms = []
    buffers = ABufferSource._buffers

    def listed(self, name, room=None):
        rooms.append(room)
        return buffers(self, name, room)

    monkeypatch.setattr(ABufferSource, "_buffers", listed)
    renderer.peel(model, camera, size=size, max_layers=None)
    drawn = (renderer.abuffer_room[size] - 1024) / 1.25
    assert [r for r in rooms if r is not None] == [spare_room(foretold)]
    assert drawn == pytest.approx(foretold, rel=0.01)


def test_layer_counts_and_layers_left(renderer, abuffer):
    """Each layer's count is its covered pixels, and a capped frame's layers left are those an
    uncapped one draws (exact here: the lists hold them all)."""
    model = examples.gearbox()
    abuffer(True)
    frame = renderer.render(model, size=(128, 96), max_layers=None, supersample=1)
    layers = renderer.peel(model, size=(128, 96), max_layers=None)
    assert frame.layers == len(layers.depth)
    assert frame.layer_pixels[: frame.layers] == [int(c) for c in (layers.depth < 1.0).sum(axis=(1, 2))]
    capped = renderer.render(model, size=(128, 96), max_layers=3, supersample=1)
    assert capped.layers == 3
    assert capped.layers + capped.layers_left == frame.layers
    assert capped.layers_shown == f"3 of {frame.layers} layers"


@pytest.mark.parametrize("supersample", [1, 2])
@pytest.mark.parametrize("style", ["blueprint", "paper"])
def test_same_drawing(renderer, abuffer, style, supersample):
    diff = drawing_difference(abuffer, style, supersample)
    assert (diff > 2).mean() <= 1e-3, f"{(diff > 2).sum()} pixels differ"


def test_used_only_where_it_pays(renderer, abuffer):
    """Not below the row's ``min_layers`` (llvmpipe's: only frames of many layers pay for
    sorting every fragment), nor for captures of chosen parts or without normals (ID passes)."""
    model = examples.gearbox()
    mesh = renderer.mesh(model, 30.0)
    abuffer(True)
    table = renderer.capture_table

    def listed(layers, min_layers: int = 1, **options) -> bool:
        rows = (replace(table.row("A-buffer"), min_layers=min_layers), table.row("peel"))
        request = Request((64, 64), mesh.triangles, layers, **options)
        return choose(replace(table, rows=rows), request)[0].way == "A-buffer"

    assert listed(1)
    assert listed(5, 2)
    assert not listed(1, 2)
    assert not listed(8, 16)
    assert listed(16, 16)
    assert listed(None, 16)
    assert not listed(5, 2, selected=True)
    assert not listed(5, 2, normals=False)


def test_after_a_kbuffer_pass_that_holds_every_layer(renderer, abuffer):
    """With a k-buffer row of ``whole_frames`` before the A-buffer (llvmpipe's table) a capped
    frame whose layers one k-buffer pass finds, for readers that read them where they lie
    (``surfaces``), is drawn so; every other goes to the A-buffer."""
    if not renderer.framebuffer_fetch or renderer.max_draw_buffers < KBUFFER_MAX:
        pytest.skip("one k-buffer pass leaves a frame's layers to readers through framebuffer fetch alone")
    model = examples.gearbox()
    mesh = renderer.mesh(model, 30.0)
    abuffer(True)
    listed, peel = renderer.capture_table.row("A-buffer"), renderer.capture_table.row("peel")
    kbuffer = KBufferRow(min_density=0.0)

    def first(table, layers, surfaces):
        request = Request((64, 64), mesh.triangles, layers, surfaces=surfaces)
        return choose(table, request)[0], request

    for after in (True, False):
        rows = ((replace(kbuffer, whole_frames=True),) if after else ()) + (listed, kbuffer, peel)
        table = CaptureTable(rows)
        held, request = first(table, 5, True)
        assert (held.way == "k-buffer") == after
        assert held.way == "A-buffer" or held.holds_frame(request)
        for batch, surfaces in ((5, False), (KBUFFER_MAX, True), (None, True)):
            assert first(table, batch, surfaces)[0].way == "A-buffer"


def _tiled_layers(renderer, mesh, camera, size, tiles: bool) -> tuple[list, Capture]:
    """Every layer's (depth, normal, ids) of a capture, zero where the layer has no fragment."""
    gb = gbuffer(renderer.pool, size, f"test.ab.tiles{tiles}")
    capture = Capture(renderer.capturer, mesh, camera, gb, layers=None, tiles=tiles)
    assert capture.way == "A-buffer"
    got = []
    layer = 0
    while layer == 0 or layer < capture.deepest():
        capture.draw(layer, renderer.queries("test.ab")[0])
        depth = np.frombuffer(gb.layer_depth(layer).read(), np.float32).reshape(size[::-1])
        covered = depth < 1
        normal = np.frombuffer(gb.normal.read(), np.float16).reshape(size[1], size[0], 4)
        ids = np.frombuffer(gb.ids.read(), np.int32).reshape(size[1], size[0], 2)
        got.append(
            (depth.copy(), np.where(covered[..., None], normal, 0), np.where(covered[..., None], ids, 0))
        )
        layer += 1
    return got, capture


def _assert_same_layers(a: list, b: list) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        for u, v in zip(x, y, strict=True):
            np.testing.assert_array_equal(u, v)


def test_tiled_unpack_draws_the_same_layers(renderer, abuffer):
    """With ``tiles`` each layer is unpacked only in the tiles that have it and the rest of its
    depth is cleared: the same layers, pixel for pixel, as unpacking every pixel; and each
    tile's count is the most layers of its pixels."""
    model = examples.gearbox()
    mesh = renderer.mesh(model, 30.0)
    size = (100, 70)  # not a whole number of tiles
    camera = fit_camera(model, size)
    abuffer(True)
    plain, _ = _tiled_layers(renderer, mesh, camera, size, False)
    tiled, capture = _tiled_layers(renderer, mesh, camera, size, True)
    counts = np.zeros(size[::-1], int)
    for depth, _, _ in tiled:
        counts += depth < 1
    th, tw = capture.tile_layers.shape
    most = np.zeros((th, tw), int)
    for i in range(th):
        for j in range(tw):
            most[i, j] = counts[i * 16 : (i + 1) * 16, j * 16 : (j + 1) * 16].max()
    np.testing.assert_array_equal(capture.tile_layers, most)
    assert len(tiled) > 8
    _assert_same_layers(tiled, plain)


def test_tiles_a_frame_leaves_empty_hold_nothing_of_it(renderer, abuffer):
    """The tiled resolve runs only where a frame has fragments: a frame that covers less than
    the one before at the same size (a zoom out) finds none of the earlier frame's layers in
    the tiles it leaves empty."""
    model = examples.gearbox()
    mesh = renderer.mesh(model, 30.0)
    size = (96, 96)
    abuffer(True)
    _tiled_layers(renderer, mesh, fit_camera(model, size), size, True)
    small = fit_camera(model, size, margin=0.35)
    tiled, capture = _tiled_layers(renderer, mesh, small, size, True)
    plain, _ = _tiled_layers(renderer, mesh, small, size, False)
    assert (capture.tile_layers == 0).sum() > capture.tile_layers.size // 2
    _assert_same_layers(tiled, plain)


@pytest.fixture
def gpu_form(renderer, monkeypatch):
    """The renderer drawing as it does on a GPU: nothing looks at a layer before the next is
    issued (not a software rasteriser's eager peel, no tiles), image passes in compute form."""
    monkeypatch.setattr(renderer, "software", False)
    monkeypatch.setattr(renderer, "use_compute", True)
    monkeypatch.setattr(renderer.executor, "tiled", False)


def _sources_made(monkeypatch, attribute: str) -> list:
    """The ``attribute`` of each A-buffer source made from here on, in order."""
    seen = []
    made = ABufferSource.__init__

    def watch(self, *args, **kwargs):
        made(self, *args, **kwargs)
        seen.append(getattr(self, attribute))

    monkeypatch.setattr(ABufferSource, "__init__", watch)
    return seen


@pytest.mark.parametrize("max_layers", [5, 30, None])  # the gearbox has 15 layers here
def test_counts_read_late_draw_the_same(renderer, abuffer, monkeypatch, max_layers):
    """Where the CPU should not wait for the capture (a GPU's frames), the counts are read only
    once the layers are issued (a capped frame: once the whole frame is): the same frame, layer
    counts and layers left as reading them at once; a capture that then proves short of room is
    drawn again, the room raised."""
    model = examples.gearbox()
    options = dict(size=(120, 90), max_layers=max_layers, supersample=1)
    abuffer(True)
    at_once = renderer.render(model, **options)
    monkeypatch.setattr(renderer, "software", False)  # a GPU's frame: nothing looks per layer
    monkeypatch.setattr(renderer.executor, "tiled", False)
    deferred = _sources_made(monkeypatch, "defer")
    for room in (None, 10):
        if room is not None:
            renderer.abuffer_room[(120, 90)] = room
        late = renderer.render(model, **options)
        np.testing.assert_array_equal(late.image, at_once.image)
        assert (late.layers, late.layers_left) == (at_once.layers, at_once.layers_left)
        assert late.layer_pixels == at_once.layer_pixels
    assert renderer.abuffer_room[(120, 90)] > 10
    # the second frame was drawn twice: short of room, then with room. A capped frame was
    # issued whole before its counts (blind) and drawn again deferred; an uncapped one looked
    # after its first 8 layers and was drawn again reading its counts at once.
    assert deferred == ([True, True, True] if max_layers else [True, True, False])


@pytest.mark.parametrize(
    "options",
    [
        dict(max_layers=6, supersample=1),
        dict(max_layers=None, supersample=2, style="paper", line_width=2.0),
    ],
)
def test_edges_from_the_lists_draw_the_same(renderer, abuffer, gpu_form, monkeypatch, options):
    """In the compute form the edges of every layer are read straight from the sorted lists,
    no layer unpacked: the same drawing, pixel for pixel, as edges of unpacked layers."""
    model = examples.gearbox()
    abuffer(True)
    listed = _watch_lists(renderer, monkeypatch)
    from_lists = renderer.render(model, size=(160, 120), **options)
    assert listed == ["edges"]
    monkeypatch.setattr(LayerCapture, "_from_lists", lambda self, st: ())
    unpacked = renderer.render(model, size=(160, 120), **options)
    assert listed == ["edges"]
    assert from_lists.layers == unpacked.layers >= 6
    np.testing.assert_array_equal(from_lists.image, unpacked.image)


def test_nodes_past_one_binding_in_a_second(renderer, abuffer, gpu_form, monkeypatch):
    """Where one storage binding holds fewer nodes than the lists may (a GPU's 2 GiB against a
    quarter of its memory), the nodes past it are read and written in a second binding of the
    nodes' buffer: the same drawing and layers as lists in one binding."""
    model = examples.gearbox()
    options = dict(size=(120, 90), max_layers=None, supersample=1)
    abuffer(True)
    whole = renderer.render(model, **options)
    room = renderer.abuffer_room[(120, 90)]
    splits = _sources_made(monkeypatch, "split")
    # a binding of two thirds of the room's nodes: the frame's fragments (``spare_room``: four
    # fifths of the room, less its spare) pass it, two such bindings and the slim fragments' one
    # hold them
    monkeypatch.setattr(renderer.device, "storage_bytes", SURFACE_BYTES * (room * 2 // 3) + BINDING_ALIGNMENT)
    split = renderer.render(examples.gearbox(), **options)  # a mesh of its own: programs anew
    assert renderer.executor.last_run.groups[0].capture.way == "A-buffer"
    assert splits and all(0 < at < (room - 1024) * 4 // 5 for at in splits)
    assert split.layers == whole.layers > 8
    assert split.layer_pixels == whole.layer_pixels
    np.testing.assert_array_equal(split.image, whole.image)


@pytest.mark.parametrize("form", ["gpu_form", "software_form"])
def test_edges_from_the_lists_wait_for_the_capture_once(renderer, abuffer, monkeypatch, request, form):
    """The first batch of layers read from the lists waits for every write of the capture (a
    full barrier); each later batch only for the cursors the batch before it left (the image
    barrier), in the compute form and a batch at a time alike: a full barrier a batch cost
    a GPU's frame of many layers the time the house had cost (benchmarks/notes/h200-scale.md)."""
    request.getfixturevalue(form)
    model = examples.gearbox()
    abuffer(True)
    ctx = renderer.ctx
    barriers: list = []
    bind = ABufferSource.bind

    def watched(self, prog, layer, step):
        real = ctx.memory_barrier

        def barrier(*bits):
            barriers.append((layer, bits))
            real(*bits)

        monkeypatch.setattr(ctx, "memory_barrier", barrier)
        try:
            bind(self, prog, layer, step)
        finally:
            monkeypatch.setattr(ctx, "memory_barrier", real)

    monkeypatch.setattr(ABufferSource, "bind", watched)
    frame = renderer.render(model, size=(160, 120), max_layers=None, supersample=1)
    assert frame.layers > 8 and len(barriers) >= 2 and barriers[0] == (0, ())
    image = (ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT,)
    assert all(layer > 0 and bits == image for layer, bits in barriers[1:])


@pytest.mark.parametrize("options", [dict(shade=True), dict(id_silhouettes=True), dict(highlight=True)])
def test_edges_from_the_lists_only_where_they_read_nothing_else(
    renderer, abuffer, gpu_form, monkeypatch, options
):
    """Shaded parts read the layers' depths, triangle-ID silhouettes their faces: those frames
    unpack every layer. Highlighted parts read a capture of their own: the lists still serve."""
    model = examples.gearbox()
    abuffer(True)
    listed = _watch_lists(renderer, monkeypatch)
    parts = np.zeros(len(model.part_names), bool)
    parts[0] = True
    kind = next(iter(options))
    if kind in ("shade", "highlight"):
        options = {kind: parts}
    renderer.render(model, size=(96, 72), max_layers=4, supersample=1, **options)
    assert listed == (["edges"] if kind == "highlight" else [])


@pytest.fixture
def software_form(renderer, monkeypatch):
    """The renderer drawing as it does on a software rasteriser: each layer looked at before
    its passes run, those drawn over the tiles the layer covers, image passes as fragment
    passes."""
    monkeypatch.setattr(renderer, "software", True)
    monkeypatch.setattr(renderer, "use_compute", False)
    monkeypatch.setattr(renderer.executor, "tiled", True)


@pytest.mark.parametrize(
    "options",
    [
        dict(max_layers=6, supersample=1),
        dict(max_layers=None, supersample=2, style="paper", line_width=2.0),
    ],
)
@pytest.mark.parametrize("batch", [1, 3, 8])
def test_edges_from_the_lists_a_layer_at_a_time_draw_the_same(
    renderer, abuffer, software_form, monkeypatch, options, batch
):
    """Where passes run a layer at a time, the edges of each batch of layers are read from the
    sorted lists as it comes, no layer unpacked: the same drawing, pixel for pixel, whatever
    the batch (the last one cut short by the cap or the last layer). Where lines are widened,
    each layer's edges go through one target to the pass that widens them: a layer a pass."""
    model = examples.gearbox()
    abuffer(True)
    monkeypatch.setattr(renderer.executor, "edge_batch", batch)
    step = 1 if "line_width" in options else batch
    listed = _watch_lists(renderer, monkeypatch, "_bind_in_place")
    from_lists = renderer.render(model, size=(160, 120), **options)
    assert set(listed) == {"edges"} and len(listed) == -(-from_lists.layers // step)
    monkeypatch.setattr(LayerCapture, "_from_lists", lambda self, st: ())
    unpacked = renderer.render(model, size=(160, 120), **options)
    assert len(listed) == -(-from_lists.layers // step)
    assert from_lists.layers == unpacked.layers >= 6
    np.testing.assert_array_equal(from_lists.image, unpacked.image)


@pytest.mark.parametrize("options", [dict(shade=True), dict(id_silhouettes=True), dict(reveal=0.5)])
def test_edges_a_layer_at_a_time_unpack_where_others_read_the_layers(
    renderer, abuffer, software_form, monkeypatch, options
):
    """Shaded parts read the layers' depths, triangle-ID silhouettes their faces, depth masking
    each layer's depth as it comes: there every layer is unpacked."""
    model = examples.gearbox()
    abuffer(True)
    listed = _watch_lists(renderer, monkeypatch, "_bind_in_place")
    parts = np.zeros(len(model.part_names), bool)
    parts[0] = True
    if "shade" in options:
        options = {"shade": parts}
    elif "reveal" in options:
        options = {"highlight": parts, **options}
    renderer.render(model, size=(96, 72), max_layers=4, supersample=1, **options)
    assert listed == []


def _watch_lists(renderer, monkeypatch, method: str = "run_in_place") -> list[str]:
    """The passes the renderer's executor runs from the lists (by ``method``), as it runs them."""
    ex = renderer.executor
    listed: list[str] = []
    run_lists = getattr(type(ex), method)

    def watch(st, name, *args):
        listed.append(name)
        run_lists(ex, st, name, *args)

    monkeypatch.setattr(ex, method, watch)
    return listed


def test_streamed_frames_count_their_layers_a_frame_late(renderer, abuffer, gpu_form):
    """Streamed frames issued whole are counted when collected, after the next frame is
    issued (each frame's counts in a buffer of its own): the pictures, layers, layer counts and
    layers left of single frames; a first frame short of room is drawn again when collected."""
    model = examples.gearbox()
    abuffer(True)
    cameras = [fit_camera(model, (96, 72), azimuth=a) for a in (0.0, 40.0, 80.0, 120.0)]
    options = dict(size=(96, 72), max_layers=5, supersample=1)
    single = [renderer.render(model, c, **options) for c in cameras]
    assert len({s.layers_left for s in single}) > 1  # frames that count differently
    renderer.abuffer_room[(96, 72)] = 10
    streamed = list(stream_blueprint(renderer, model, cameras, **options))
    assert renderer.abuffer_room[(96, 72)] > 10
    for a, b in zip(single, streamed, strict=True):
        np.testing.assert_array_equal(a.image, b.image)
        assert (a.layers, a.layer_pixels, a.layers_left) == (b.layers, b.layer_pixels, b.layers_left)


def test_slim_normals_are_taken_at_the_pixel_centre(renderer, abuffer, monkeypatch):
    """Corners snapped to 1/256 px in the vertex shader (as the H200's rasteriser snaps them:
    tests/glsl/snapped_geometry.vert) move the samples of whole fragments' normals off the pixel
    centres, and on faces seen edge-on their normals with them; slim fragments' normals come
    from the true corners at the centre, the same with or without the snap."""
    from blueprint.render import mesh

    abuffer(True)
    make, camera = CASES["gearbox"]
    options = dict(size=(160, 120), max_layers=None, **camera)
    monkeypatch.setattr(renderer, "capture_table", replace(renderer.capture_table, exact_depth=True))
    plain = blueprint.peel(make(), renderer=renderer, **options)
    monkeypatch.setattr(mesh, "GEOMETRY_VERT", SNAPPED_GEOMETRY)
    snapped = blueprint.peel(make(), renderer=renderer, **options)
    # the snap moves which face covers a pixel beside an edge: compare where it does not
    same = (snapped.triangle == plain.triangle) & (plain.triangle >= 0)
    assert same.sum() > 0.99 * (plain.triangle >= 0).sum()
    moved = np.abs(snapped.normal.astype(np.float64) - plain.normal).max(axis=-1)[same]
    if abuffer.slim:
        assert moved.max() <= 2.0**-11
    elif not renderer.snapped_depth:
        # (a driver that snaps corners itself moves them either way: nothing to compare)
        assert (moved > 2e-3).sum() > 0
