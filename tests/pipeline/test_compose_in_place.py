"""An edges pass that composes its batch of layers where it finds them (``Executor.composed``):
the same picture, byte for byte, as edge maps written a layer each and composed after, one draw
call fewer; taken only where the batch holds every layer drawn and nothing else reads the maps;
and the r8 rounding it mimics against the driver's own."""

from __future__ import annotations

import numpy as np
import pytest

from blueprint import examples
from blueprint.compose.lookup import get_style
from blueprint.gpu.shaders import build_program
from blueprint.pipeline import render_blueprint
from blueprint.scene.camera import fit_camera
from blueprint.scene.loader import load_model

# small enough that the gearbox's 2 144 triangles pay for the k-buffer (render.table)
SIZE = (240, 180)


@pytest.fixture
def composing(renderer):
    """Draws a frame with the in-place compose on or off: (picture, draw calls, composed)."""
    if renderer.use_compute or not renderer.software or renderer.capture_table.row("k-buffer") is None:
        pytest.skip("edges read from a k-buffer's surfaces a batch at a time: a software rasteriser's")
    ex = renderer.executor

    def draw(on: bool, model, camera=None, **options):
        ex.compose_in_place = on
        try:
            frame = render_blueprint(renderer, model, camera, **options)
        finally:
            ex.compose_in_place = True
        return frame.image, frame.draws, ex.last_run.composed

    return draw


@pytest.mark.parametrize("layers", [2, 5, 7])
@pytest.mark.parametrize("style", ["blueprint", "paper", "transparent", "wireframe", "grid"])
@pytest.mark.parametrize("view", ["iso", "front", "top"])
def test_same_picture_as_maps_composed_after(composing, layers, style, view):
    model = examples.gearbox()
    chosen = get_style("blueprint", 12.0) if style == "grid" else style
    options = dict(size=SIZE, view=view, style=chosen, max_layers=layers, supersample=1)
    after, after_draws, none = composing(False, model, **options)
    composed, draws, names = composing(True, model, **options)
    assert none is None
    assert names == ("edges", "drawing")
    assert draws == after_draws - 1
    np.testing.assert_array_equal(composed, after)
    assert (composed[..., 3] > 0).sum() > 100  # lines were drawn


def test_same_picture_of_a_dense_model_while_it_turns(composing, shared_models):
    """The rocker arm at the viewer's size and layers, from several azimuths."""
    model = load_model(shared_models / "common-3d-test-models" / "rocker-arm.obj")
    for azimuth in (0.0, 50.0, 130.0, 250.0):
        camera = fit_camera(model, (800, 600), "iso", azimuth=azimuth)
        options = dict(size=(800, 600), max_layers=5, supersample=1)
        after, _, _ = composing(False, model, camera, **options)
        composed, _, names = composing(True, model, camera, **options)
        assert names == ("edges", "drawing")
        np.testing.assert_array_equal(composed, after)


@pytest.mark.parametrize(
    "options",
    [
        {"supersample": 2},  # the composite boxes 2x2 samples a pixel
        {"line_width": 3.0},  # the lines pass reads the edges
        {"highlight": ["shaft"]},  # a sprite of its own over the layers
        {"shade": ["cover"]},
        {"min_fraction": 0.2},  # the layers drawn may be fewer than the batch found
        {"max_layers": None},  # every layer: more than one pass of the k-buffer may hold
    ],
    ids=["supersample2", "wide", "highlight", "shade", "min-fraction", "all-layers"],
)
def test_composed_after_where_more_than_the_maps_count(composing, options):
    model = examples.gearbox()
    for key in ("highlight", "shade"):
        if key in options:
            options[key] = np.array([n in options[key] for n in model.part_names])
    options = {"size": SIZE, "max_layers": 5, "supersample": 1, **options}
    after, after_draws, _ = composing(False, model, **options)
    image, draws, names = composing(True, model, **options)
    assert names is None
    assert draws == after_draws
    np.testing.assert_array_equal(image, after)


def test_stored_edge_rounds_as_an_r8_target_stores_and_a_fetch_reads(renderer, composing, tmp_path):
    """compose_batch.glsl's ``stored_edge`` against the driver: values written to an r8 target
    and fetched back, over a ramp, every rounding midpoint and its neighbours, and noise."""
    ctx = renderer.ctx
    w = h = 256
    midpoints = ((np.arange(255) + 0.5) / 255).astype(np.float32)
    rng = np.random.default_rng(7)
    values = np.concatenate(
        [
            midpoints,
            np.nextafter(midpoints, np.float32(1)),
            np.nextafter(midpoints, np.float32(0)),
            np.float32([0.0, 1.0, -0.25, 1.5]),
            rng.random(w * h, dtype=np.float32),
        ]
    )[: w * h]
    values[-30000:] = np.linspace(0, 1, 30000, dtype=np.float32)
    source = ctx.texture((w, h), 1, values.tobytes(), dtype="f4")
    stored = ctx.texture((w, h), 1)
    fetched = ctx.texture((w, h), 1, dtype="f4")
    mimicked = ctx.texture((w, h), 1, dtype="f4")
    vertex = "fullscreen.vert"
    copy = tmp_path / "copy.frag"
    copy.write_text(
        "uniform sampler2D u_in;\nout vec4 o;\n"
        "void main() { o = vec4(texelFetch(u_in, ivec2(gl_FragCoord.xy), 0).r); }\n"
    )
    mimic = tmp_path / "mimic.frag"
    mimic.write_text(
        '#include "blueprint.compose:glsl/compose_batch.glsl"\nuniform sampler2D u_in;\n'
        "void main() { o_value = vec4(stored_edge(texelFetch(u_in, ivec2(gl_FragCoord.xy), 0).r)); }\n"
    )
    programs = {f: build_program(ctx, vertex, f, {"BATCH": 1}) for f in (copy, mimic)}
    arrays = {f: ctx.vertex_array(prog, []) for f, prog in programs.items()}
    fbos = []
    for fragment, read, write in [(copy, source, stored), (copy, stored, fetched), (mimic, source, mimicked)]:
        read.use(0)
        programs[fragment]["u_in"].value = 0
        fbos.append(ctx.framebuffer([write]))
        fbos[-1].use()
        arrays[fragment].render(vertices=3)
    # (moderngl binds the framebuffer in use again whenever it makes one: never a released one)
    ctx.detect_framebuffer(0).use()
    driver = np.frombuffer(fetched.read(), np.float32)
    ours = np.frombuffer(mimicked.read(), np.float32)
    for held in (*fbos, *arrays.values(), *programs.values(), source, stored, fetched, mimicked):
        held.release()
    np.testing.assert_array_equal(ours, driver)
    # to nearest, ties to even, then times the reciprocal, in float32
    rounded = np.rint(np.clip(values, 0, 1) * np.float32(255)) * np.float32(1 / 255)
    np.testing.assert_array_equal(driver, rounded)
