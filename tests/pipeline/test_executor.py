"""The executor on the GPU: user pipelines with user shaders, the attribute pass against the
renderer's peel, the blueprint preset and Renderer.render against the golden frames, target
reuse, texel sizes, dumps and image inputs."""

from __future__ import annotations

import functools
import textwrap

import numpy as np
import pytest
from golden_helpers import MODELS, assert_frame_pinned, assert_like_golden, case, skip_unless_pinned
from golden_helpers import SIZE as SIZE_GOLDEN
from PIL import Image

from blueprint import examples, render
from blueprint.api.files import run_pipeline
from blueprint.errors import InputError, ShaderError
from blueprint.pipeline import load_pipeline, render_blueprint
from blueprint.pipeline.executor import part_color
from blueprint.scene.camera import fit_camera

SIZE = (64, 48)


@pytest.fixture(scope="module")
def ex(renderer):
    return renderer.executor


@pytest.fixture(scope="module")
def gearbox(renderer):
    model = examples.gearbox()
    yield model
    renderer.forget(model)


def write(folder, name, text):
    path = folder / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


# -- user pipelines --------------------------------------------------------------------------------
USER_SHADER = """
// a user's own pass: gain on the colour, and the texel sizes the executor sets
#include "helpers.glsl"
uniform sampler2D u_src;
uniform float u_gain;
uniform vec3 u_tint;
uniform vec2 u_texel;
uniform vec2 u_src_texel;
out vec4 o_value;
void main() {
    vec4 c = texelFetch(u_src, ivec2(gl_FragCoord.xy), 0);
    o_value = vec4(scaled(c.r, u_gain) * u_tint.r, u_texel.x, u_texel.y, u_src_texel.x);
}
"""

USER_PIPELINE = """
[pipeline]
output = "tinted"
[variables]
gain = 0.5
[images.photo]
format = "rgba32f"
[passes.tinted]
shader = "tint.frag"
inputs = { src = "photo" }
format = "rgba32f"
params = { gain = "= gain * 2", tint = [0.5, 1.0, 1.0] }
[passes.tinted.uniforms]
gain = { type = "float", default = 1.0, min = 0.0, max = 4.0 }
tint = { type = "vec3", default = [1.0, 1.0, 1.0], min = 0.0, max = 1.0 }
"""


def test_user_pipeline_with_user_shader(tmp_path, ex):
    write(tmp_path, "helpers.glsl", "float scaled(float v, float k) { return v * k; }\n")
    write(tmp_path, "tint.frag", USER_SHADER)
    spec = load_pipeline(str(write(tmp_path, "mine.toml", USER_PIPELINE)))
    image = np.random.default_rng(1).integers(0, 256, (6, 8, 3), dtype=np.uint8)
    out = ex.run(spec, images={"photo": image}).output
    assert out.shape == (6, 8, 4) and out.dtype == np.float32
    np.testing.assert_allclose(out[..., 0], image[..., 0] / 255.0 * 1.0 * 0.5, atol=1e-6)
    np.testing.assert_allclose(out[..., 1:], np.broadcast_to([1 / 8, 1 / 6, 1 / 8], (6, 8, 3)), atol=1e-7)
    # another size: the texel uniforms follow it
    out = ex.run(spec, images={"photo": np.zeros((4, 16, 3), np.uint8)}, variables={"gain": 1.0}).output
    np.testing.assert_allclose(out[0, 0, 1:], [1 / 16, 1 / 4, 1 / 16], atol=1e-7)
    # the output at a given size, the image resized to it
    out = ex.run(spec, images={"photo": image}, size=(4, 3)).output
    assert out.shape == (3, 4, 4)


def test_user_shader_compile_error_names_file_and_line(tmp_path, ex):
    write(tmp_path, "helpers.glsl", "float scaled(float v, float k) { return v * k; }\n")
    write(tmp_path, "tint.frag", USER_SHADER.replace("o_value = vec4(", "o_value = vec4(undeclared + "))
    spec = load_pipeline(str(write(tmp_path, "mine.toml", USER_PIPELINE)))
    with pytest.raises(ShaderError, match=r"tint\.frag:12: error"):
        ex.run(spec, images={"photo": np.zeros((4, 4, 3), np.uint8)})


def test_image_file_input_and_chain_reuse(tmp_path, ex, renderer):
    rng = np.random.default_rng(2)
    picture = rng.integers(0, 256, (10, 12, 3), dtype=np.uint8)
    Image.fromarray(picture).save(tmp_path / "in.png")
    text = "[pipeline]\noutput = 'p4'\n[images.photo]\nfile = 'in.png'\n"
    previous = "photo"
    for k in range(1, 5):
        text += f'[passes.p{k}]\nop = "invert"\ninputs = {{ source = "{previous}" }}\n'
        previous = f"p{k}"
    spec = load_pipeline(str(write(tmp_path, "chain.toml", text)))
    result = ex.run(spec, dumps=("p1",))
    np.testing.assert_array_equal(result.output[..., :3], picture)  # inverted four times
    np.testing.assert_array_equal(result.dumps["p1"][..., :3], 255 - picture)
    names = {n for n in renderer.pool._textures if n.startswith("pipeline.F") and n.endswith(".rgba8.1")}
    assert len(names) <= 3  # two ping-pong targets (and the pinned dump)


def test_missing_model_and_image(tmp_path, ex):
    with pytest.raises(InputError, match="give a model"):
        ex.run(load_pipeline("edges-sobel"))
    spec = load_pipeline(str(write(tmp_path, "p.toml", "[pipeline]\noutput='photo'\n[images.photo]\n")))
    with pytest.raises(InputError, match="images.photo: no file given"):
        ex.run(spec)


# -- attributes --------------------------------------------------------------------------------------
ATTRIBUTES = """
[pipeline]
output = "layer"
layers = 3
[attributes]
depth = {}
ids = {}
triangle = {}
part = {}
layer = {}
linear_depth = {}
position = {}
base_color = {}
uv = {}
[passes.mark]
op = "id_edges"
inputs = { ids = "triangle" }
per_layer = true
"""


def test_attribute_pass_matches_the_peel(tmp_path, ex, renderer, gearbox):
    spec = load_pipeline(str(write(tmp_path, "attrs.toml", ATTRIBUTES)))
    camera = fit_camera(gearbox, SIZE)
    names = ("depth", "triangle", "part", "linear_depth", "position", "base_color", "uv", "ids", "mark")
    result = ex.run(spec, gearbox, camera, size=SIZE, dumps=names)
    peel = renderer.peel(gearbox, camera, size=SIZE, max_layers=3)
    d = result.dumps
    n = len(peel.depth)
    assert n == 3 and result.layers == 3
    np.testing.assert_array_equal(d["depth"][..., 0], peel.depth)
    covered = peel.depth < 1
    np.testing.assert_array_equal(d["triangle"][..., 0], peel.triangle)
    np.testing.assert_array_equal(d["part"][..., 0], peel.part)
    np.testing.assert_array_equal(result.output[..., 0], np.where(covered, np.arange(n)[:, None, None], -1))
    np.testing.assert_array_equal(d["ids"][..., 0], np.where(covered, peel.triangle + 1, 0))
    # linear depth and position against the window depth, through the camera's matrices
    near, far = camera.near, camera.far
    eye_depth = near * far / (far - peel.depth * (far - near))
    np.testing.assert_allclose(d["linear_depth"][..., 0][covered], eye_depth[covered], rtol=2e-4)
    assert (d["linear_depth"][~covered] == 0).all()
    pos = d["position"]
    assert (pos[..., 3][covered] == 1).all() and (pos[~covered] == 0).all()
    clip = np.einsum("ij,...j->...i", peel.projection @ peel.view, pos[..., :4].astype(np.float64))
    with np.errstate(invalid="ignore", divide="ignore"):
        window = (clip[..., 2] / clip[..., 3] + 1) / 2
    np.testing.assert_allclose(window[covered], peel.depth[covered], atol=2e-5)
    color = d["base_color"]
    expected = np.round(part_color(peel.part) * 255)
    assert np.abs(color[..., :3][covered].astype(int) - expected[covered]).max() <= 1
    assert (color[..., 3][covered] == 255).all() and (color[~covered] == 0).all()
    uv = d["uv"]
    assert (uv[covered] >= -1e-6).all() and (uv[covered] <= 1 + 1e-6).all() and (uv[~covered] == 0).all()
    # a per-layer pass ran on every layer: ID edges of each layer's triangles
    assert d["mark"].shape == (3, SIZE[1], SIZE[0], 1) and d["mark"][1].any()


def test_attributes_at_two_scales(tmp_path, ex, gearbox):
    text = """
    [pipeline]
    output = "small"
    [attributes]
    depth = { scale = 2 }
    base_color = { scale = 1 }
    [passes.big]
    op = "invert"
    inputs = { source = "depth" }
    [passes.small]
    op = "downsample"
    inputs = { source = "big" }
    [passes.mixed]
    op = "mix"
    inputs = { a = "small", b = "base_color" }
    """
    spec = load_pipeline(
        str(write(tmp_path, "two.toml", text.replace('output = "small"', 'output = "mixed"')))
    )
    result = ex.run(spec, gearbox, size=SIZE, dumps=("base_color", "small"))
    assert result.output.shape == (SIZE[1], SIZE[0], 1)
    covered_small = result.dumps["small"][..., 0] > 0.0
    covered_color = result.dumps["base_color"][..., 3] > 0
    assert (covered_small == covered_color).mean() > 0.97


# -- the blueprint --------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def golden_models(renderer):
    models = {name: build() for name, build in MODELS.items()}
    yield models
    for model in models.values():
        renderer.forget(model)


def render_golden_case(render, golden_models, name):
    model, options = case(name)
    return render(golden_models[model], size=SIZE_GOLDEN, **options)


@pytest.mark.parametrize(
    "name",
    [
        "blueprint",
        "paper",
        "transparent",
        "wireframe",
        "blueprint_line2",
        "blueprint_ss1_all_layers",
        "blueprint_crease50",
        "sleeve_crease50_all_layers",
    ],
)
@pytest.mark.parametrize("form", ["Renderer.render", "preset"])
def test_blueprint_matches_its_golden_frame(renderer, golden_models, artifacts, name, form):
    """Renderer.render and the `blueprint` preset against the frames today's code drew
    (tests/test_golden.py), not against each other: the same picture, the same layers."""
    skip_unless_pinned(renderer)
    if form == "preset":
        frame = render_golden_case(functools.partial(render_blueprint, renderer), golden_models, name)
    else:
        frame = render_golden_case(renderer.render, golden_models, name)
    assert_frame_pinned(name, frame)
    assert_like_golden(name, frame.image, artifacts, label=f"{name}.{form}")


def test_blueprint_file_run_writes_png_and_dumps(tmp_path, renderer, gearbox):
    out = tmp_path / "bp.png"
    model = tmp_path / "gearbox.glb"
    model.write_bytes(examples.example_path().read_bytes())
    result = run_pipeline("blueprint", model, out, size=SIZE, dump=("edges", "normal"), renderer=renderer)
    image = np.asarray(Image.open(out))
    assert image.shape == (SIZE[1], SIZE[0], 4)
    layers = result.layers
    assert sorted(p.name for p in tmp_path.glob("bp.edges.*.png")) == [
        f"bp.edges.{k}.png" for k in range(layers)
    ]
    normal = np.load(tmp_path / "bp.normal.npz")
    assert (
        normal["data"].shape == (layers, SIZE[1] * 2, SIZE[0] * 2, 4) and str(normal["format"]) == "rgba16f"
    )


@pytest.mark.parametrize("name", ["blueprint", "blueprint_layers10_line2_5", "transparent"])
def test_blueprint_compute_form_matches_its_golden_frame(
    renderer, golden_models, monkeypatch, artifacts, name
):
    """Where the renderer runs image passes as compute shaders (GL 4.3 GPUs; forced here on
    llvmpipe), the executor keeps the per-layer edges in 8-slice arrays and composes with the
    renderer's compute shader: the picture and the layers of the fragment passes' golden."""
    if renderer.ctx.version_code < 430:
        pytest.skip("compute shaders need OpenGL 4.3")
    skip_unless_pinned(renderer)
    monkeypatch.setattr(renderer, "use_compute", True)
    frame = render_golden_case(functools.partial(render_blueprint, renderer), golden_models, name)
    assert renderer.executor.last_run.arrays is not None
    assert_frame_pinned(name, frame)
    assert_like_golden(name, frame.image, artifacts, label=f"{name}.compute")


# -- attributes of chosen parts, accumulating passes, stop rules ------------------------------------
PARTS_PIPELINE = """
[pipeline]
output = "index"
layers = 0
[attributes]
depth = {}
shaft = { of = "depth", parts = "shaft" }
[passes.index]
op = "shade_layer"
inputs = { surface = "shaft", depth = "depth" }
per_layer = true
accumulate = true
"""


def test_shade_layer_accumulates_the_layer_each_surface_lies_in(tmp_path, renderer, ex, gearbox):
    """An accumulating pass over every layer against the peel read back: where the shaft's own
    front surface (drawn alone) is layer k of the whole model, the pass holds 1 + k."""
    spec = load_pipeline(str(write(tmp_path, "parts.toml", PARTS_PIPELINE)))
    shaft = np.array([n == "shaft" for n in gearbox.part_names])
    result = ex.run(spec, gearbox, size=SIZE, parts={"shaft": shaft}, dumps=("shaft",))
    index = np.round(result.output[..., 0].astype(np.float64)).astype(int)
    surface = result.dumps["shaft"][..., 0]
    layers = renderer.peel(gearbox, result.camera, size=SIZE)
    assert result.layers == len(layers.depth)
    cam = result.camera

    def eye(z):
        ndc = 2.0 * z.astype(np.float64) - 1.0
        return 2.0 * cam.near * cam.far / (cam.far + cam.near - ndc * (cam.far - cam.near))

    eps = 1e-5 * (cam.far - cam.near)
    near = np.abs(eye(layers.depth) - eye(surface)[None]) <= eps
    near &= (layers.depth < 1.0) & (surface < 1.0)[None]
    expected = np.where(near.any(axis=0), near.argmax(axis=0) + 1, 0)
    # the layer is the last one within the tolerance (each layer overwrites): ties are few
    last = np.where(near.any(axis=0), len(near) - near[::-1].argmax(axis=0), 0)
    assert ((index == expected) | (index == last)).all()
    assert (index > 0).sum() == (surface < 1.0).sum() > 50
    assert len(set(np.unique(index)) - {0}) >= 3  # hidden behind the cover, the blocks and bearings


def test_parts_must_be_given(tmp_path, ex, gearbox):
    spec = load_pipeline(str(write(tmp_path, "parts.toml", PARTS_PIPELINE)))
    with pytest.raises(InputError, match=r"attributes\.shaft: give the parts 'shaft'"):
        ex.run(spec, gearbox, size=SIZE)


def test_reveal_stop_rule_of_a_pipeline(tmp_path, renderer, ex, gearbox):
    """A declared reveal rule peels as Renderer.render's depth masking does."""
    text = PARTS_PIPELINE.replace("layers = 0", "layers = 0\n") + (
        '[stop.reveal]\ndepth = "shaft"\nfraction = 0.9\n'
    )
    spec = load_pipeline(str(write(tmp_path, "reveal.toml", text)))
    shaft = np.array([n == "shaft" for n in gearbox.part_names])
    result = ex.run(spec, gearbox, size=SIZE, parts={"shaft": shaft})
    frame = renderer.render(gearbox, result.camera, size=SIZE, supersample=1, highlight=shaft, reveal=0.9)
    assert result.layers == frame.layers and result.revealed == pytest.approx(frame.revealed)
    assert (
        0.9 <= result.revealed and result.layers < renderer.render(gearbox, size=SIZE, max_layers=None).layers
    )


# -- streams ------------------------------------------------------------------------------------------
def test_stream_gives_what_single_runs_give(ex, gearbox):
    """Frames read back while the next is drawn: the same pictures and layers, in order."""
    from blueprint.scene.camera import fit_camera

    spec = load_pipeline("blueprint")
    cameras = [fit_camera(gearbox, SIZE, azimuth=a) for a in (0.0, 40.0, 80.0)]
    single = [ex.run(spec, gearbox, c, size=SIZE) for c in cameras]
    streamed = list(ex.stream(spec, gearbox, ({"camera": c} for c in cameras), size=SIZE))
    assert len(streamed) == 3
    for a, b in zip(single, streamed, strict=True):
        assert b.pending is None and b.camera == a.camera
        np.testing.assert_array_equal(a.output, b.output)
        assert (a.layers, a.layer_pixels) == (b.layers, b.layer_pixels)
        assert b.ms > 0
    assert not np.array_equal(streamed[0].output, streamed[1].output)
    # smaller frames through the pixel buffers the larger ones left
    (small,) = ex.stream(spec, gearbox, [{"camera": cameras[0]}], size=(32, 24))
    np.testing.assert_array_equal(small.output, ex.run(spec, gearbox, cameras[0], size=(32, 24)).output)


def test_frames_in_a_row_follow_their_options(renderer, ex, gearbox):
    """A frame asking for the last frame's options again reuses what was made of them (the run
    arguments, the plan); one asking for others, or the same values in a new dict, draws
    what a first frame of them draws."""
    camera = fit_camera(gearbox, SIZE)

    def frame(**options):
        return render_blueprint(renderer, gearbox, camera, size=SIZE, **options).image

    thin, thick = frame(line_width=1.0), frame(line_width=3.0)
    assert not np.array_equal(thin, thick)
    np.testing.assert_array_equal(frame(line_width=1.0), thin)
    spec = load_pipeline("blueprint")
    variables = {"line_width": 1.0}
    first = ex.run(spec, gearbox, camera, size=SIZE, variables=variables).output
    variables["line_width"] = 3.0  # changed in place: not the plan of the frame before
    second = ex.run(spec, gearbox, camera, size=SIZE, variables=variables).output
    assert not np.array_equal(first, second)


def test_a_run_read_later_holds_its_output_until_collected(tmp_path, ex, gearbox):
    spec = load_pipeline(str(write(tmp_path, "parts.toml", PARTS_PIPELINE)))
    shaft = np.array([n == "shaft" for n in gearbox.part_names])
    buffer = ex.ctx.buffer(reserve=SIZE[0] * SIZE[1])
    later = ex.run(spec, gearbox, size=SIZE, parts={"shaft": shaft}, read_later=lambda tex: buffer)
    now = ex.run(spec, gearbox, size=SIZE, parts={"shaft": shaft})
    assert later.output is None and later.pending is not None
    np.testing.assert_array_equal(later.collected().output, now.output)
    buffer.release()


def test_pipeline_file_run_takes_parts_as_renderer_render_does(tmp_path, renderer, capsys):
    """``pipeline run blueprint --set highlight=true --set reveal=0.9 --parts highlight=gear``
    draws what ``blueprint.render(highlight=..., reveal=0.9)`` draws."""
    from blueprint.cli import main

    model = tmp_path / "gearbox.glb"
    model.write_bytes(examples.example_path().read_bytes())
    out = tmp_path / "masked.png"
    args = ["pipeline", "run", "blueprint", str(model), "-o", str(out), "--size", "96", "72"]
    args += ["--set", "highlight=true", "--set", "reveal=0.9", "--parts", "highlight=gear"]
    with pytest.raises(SystemExit) as done:
        main(args)
    assert done.value.code == 0 and "5 layers" in capsys.readouterr().out
    expected = render(str(model), size=(96, 72), highlight="gear", reveal=0.9, renderer=renderer)
    np.testing.assert_array_equal(np.asarray(Image.open(out)), expected)
    with pytest.raises(SystemExit) as failed:
        main([*args[:-2], "-o", str(tmp_path / "none.png")])
    error = capsys.readouterr().err
    assert failed.value.code == 2 and "--parts highlight=GLOBS" in error and error.count("\n") == 1
    assert not (tmp_path / "none.png").exists()


@pytest.mark.parametrize("style", ["blueprint", "transparent"])
def test_frame_left_on_the_gpu_is_the_frame_read_back(renderer, style):
    """``on_gpu`` (the viewer's frames) leaves the picture in its target, unread: the same
    premultiplied pixels the read-back frame was made from, and the same layers; the layers a
    cap left are not counted there (a read-back: a stall the viewer never shows)."""
    from blueprint.render.renderer import straight_alpha

    model = examples.gearbox()
    options = dict(size=(96, 72), style=style, supersample=1, max_layers=4)
    read = renderer.render(model, **options)
    kept = renderer.render(model, read.camera, on_gpu=True, **options)
    assert kept.image is None
    rgba = np.frombuffer(kept.texture.read(), np.uint8).reshape(72, 96, 4)[::-1]
    assert (rgba[..., 3] < 255).any() == (style == "transparent")
    np.testing.assert_array_equal(straight_alpha(rgba), read.image)
    assert (kept.layers, kept.layer_pixels) == (read.layers, read.layer_pixels)
    assert read.layers_left > 0 and kept.layers_left == 0
