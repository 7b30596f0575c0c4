"""The capture table (render/table.py): the rows a device's capabilities give it, the one
chooser's answers, and choosing a way through the renderer (``Renderer(capture=...)``,
``capture_table``) rather than flags. That each way draws the same layers is for the oracle and
the ways' own tests (test_layers_oracle.py, test_kbuffer.py, test_abuffer.py)."""

from __future__ import annotations

from dataclasses import replace

import pytest

import blueprint
from blueprint import examples, settings
from blueprint.errors import InputError
from blueprint.render.abuffer import gpu_memory_bytes
from blueprint.render.table import (
    DEFAULT_ABUFFER_BYTES,
    KBUFFER_MAX,
    ABufferRow,
    CaptureTable,
    KBufferRow,
    PeelRow,
    Request,
    capture_table,
    choose,
)


def test_a_devices_table_follows_its_capabilities(renderer):
    table = capture_table(renderer.device)
    ways = [row.way for row in table.rows]
    assert ways[-1] == "peel" and ways.count("peel") == 1
    fetch = renderer.framebuffer_fetch and renderer.max_draw_buffers >= KBUFFER_MAX
    assert ("k-buffer" in ways) == (fetch or renderer.fragment_interlock)
    assert ("A-buffer" in ways) == (renderer.ctx.version_code >= 430)
    assert table.exact_depth == renderer.snapped_depth
    kbuffer, listed = table.row("k-buffer"), table.row("A-buffer")
    if kbuffer is not None:
        assert kbuffer.interlock == (not fetch)
        assert kbuffer.min_density == (0.3 if kbuffer.interlock else 0.03)
    if listed is not None:
        assert listed.min_layers == (4 if renderer.software else 1)
        assert listed.slim == (listed.compute_from is not None) == renderer.use_compute
    # a software rasteriser draws a capped frame one k-buffer pass holds before the A-buffer
    whole = [row for row in table.rows if row.way == "k-buffer" and row.whole_frames]
    assert bool(whole) == (renderer.software and kbuffer is not None and listed is not None)
    if whole:
        assert table.rows[0] is whole[0]


def test_the_lists_may_take_a_quarter_of_the_devices_memory(renderer, monkeypatch):
    """The A-buffer's lists at most: a quarter of the GPU's memory where the driver tells it;
    on a software rasteriser, whose memory is the host's, the run's memory budget (a quarter
    of the memory available, or ``BLUEPRINT_MEMORY_LIMIT``), not a GiB whatever the host has:
    a big frame there is listed rather than peeled a geometry pass a layer."""
    if renderer.capturer.table.row("A-buffer") is None:
        pytest.skip("this renderer has no A-buffer (OpenGL below 4.3)")
    total = gpu_memory_bytes(renderer.device)
    for limit in ("3G", "300M"):
        monkeypatch.setenv(settings.MEMORY_ENV, limit)
        listed = capture_table(renderer.device).row("A-buffer")
        if total:
            assert listed.max_bytes == total // 4
        elif renderer.software:
            assert listed.max_bytes == settings.parse_size(limit) == settings.memory_budget()
        else:
            assert listed.max_bytes == DEFAULT_ABUFFER_BYTES


def _ways(table, **request) -> list[str]:
    defaults = dict(size=(64, 64), triangles=10_000)
    return [row.way for row in choose(table, Request(**{**defaults, **request}))]


def test_the_chooser_answers_in_the_tables_order_the_peel_last():
    listed = ABufferRow(min_layers=4)
    kbuffer = KBufferRow(min_density=0.5)
    table = CaptureTable((replace(kbuffer, whole_frames=True), listed, kbuffer, PeelRow()))
    # 10 000 triangles over 4 096 pixels: 2.4 a pixel, dense enough for the k-buffer
    assert _ways(table, layers=5) == ["A-buffer", "k-buffer", "peel"]
    assert _ways(table, layers=5, surfaces=True) == ["k-buffer", "A-buffer", "k-buffer", "peel"]
    assert _ways(table, layers=2) == ["k-buffer", "peel"]
    assert _ways(table, layers=None, surfaces=True) == ["A-buffer", "k-buffer", "peel"]
    assert _ways(table, layers=1) == ["peel"]
    assert _ways(table, layers=5, triangles=1000) == ["A-buffer", "peel"]
    # chosen parts and ID buffers are peeled; faces alone come from one pass for in-place readers
    assert _ways(table, layers=5, selected=True) == ["peel"]
    assert _ways(table, layers=5, normals=False) == ["peel"]
    assert _ways(table, layers=5, normals=False, surfaces=True) == ["k-buffer", "k-buffer", "peel"]
    assert _ways(table, layers=9, normals=False, surfaces=True) == ["peel"]
    assert _ways(replace(table, rows=(replace(kbuffer, interlock=True), PeelRow())), layers=5) == [
        "k-buffer",
        "peel",
    ]
    assert _ways(CaptureTable((PeelRow(),)), layers=None) == ["peel"]


def test_the_peel_culls_from_its_thresholds():
    row = PeelRow(culled_from=(100, 64 * 64))
    assert row.culled(Request((64, 64), 100), exact_depth=False)
    assert not row.culled(Request((64, 63), 100), exact_depth=False)
    assert not row.culled(Request((64, 64), 99), exact_depth=False)
    assert not row.culled(Request((64, 64), 100), exact_depth=True)
    assert not PeelRow().culled(Request((4096, 4096), 10**7), exact_depth=False)


def test_a_table_ends_with_the_peel():
    with pytest.raises(InputError, match="ends with the peel"):
        CaptureTable((ABufferRow(),))
    with pytest.raises(InputError, match="ends with the peel"):
        CaptureTable(())


@pytest.mark.parametrize("way", ["peel", "k-buffer", "A-buffer"])
def test_a_renderer_captures_the_way_it_is_told(way):
    """``Renderer(capture=way)``: every frame that way where the driver has it (whatever the
    thresholds), as ``blueprint bench`` names it; the table can be set again afterwards."""
    from blueprint.bench import time_frames

    model = examples.gearbox()
    options = dict(size=(64, 48), max_layers=3, supersample=1, style="blueprint", frames=1, warmup=0)
    with blueprint.Renderer() as probe:
        if way != "peel" and capture_table(probe.device).row(way) is None:
            pytest.skip(f"this driver has no {way}")
    with blueprint.Renderer(capture=way) as r:
        assert [row.way for row in r.capture_table.rows] == ([way, "peel"] if way != "peel" else ["peel"])
        camera = blueprint.Camera.fit(model.positions, "iso", aspect=64 / 48)
        assert time_frames(r, model, camera, **options)["capture"] == way
        r.capture_table = capture_table(r.device, "peel")
        assert time_frames(r, model, camera, **options)["capture"] == "peel"
        with pytest.raises(TypeError):
            r.capture_table = "peel"


def test_an_unknown_way_is_refused_in_one_line():
    with blueprint.Renderer() as r, pytest.raises(InputError, match="unknown capture 'fast'"):
        capture_table(r.device, "fast")
