"""GPU state: the context factory, shader loading (includes, defines, file-and-line errors),
the render-target pool, and size checks that run before any rendering."""

from __future__ import annotations

import sys
import uuid
from pathlib import Path

import numpy as np
import pytest

import blueprint
from blueprint import examples
from blueprint.errors import GLUnavailableError, InputError, ShaderError
from blueprint.gpu import TargetPool, build_program, create_context, gl_info, preprocess
from blueprint.gpu.device import SNAPPED_DEPTH_PX, check_size
from blueprint.gpu.shaders import _explain, package_files
from blueprint.render.table import capture_table

# -- a throw-away shader package ------------------------------------------------------------------
# build_program loads "package:path" references from the package's folder (package_files), so a
# package made in a temporary folder (and put on sys.path) exercises the real loader without a file
# under src/.

SHADERS = {
    "helper.glsl": "float helper(float x) {\n    return x * 2.0;\n}\n",
    "main.frag": (
        "out vec4 o_color;\n"
        '#include "helper.glsl"\n'
        '#include "depth.glsl"\n'
        "void main() {\n"
        "    o_color = vec4(helper(eye_depth(0.5)) * float(SCALE) * float(FLAG));\n"
        "}\n"
    ),
    # line 4 of the main file, after an include: checks the #line that resumes the file
    "syntax_main.frag": (
        'out vec4 o_color;\n#include "helper.glsl"\nvoid main() {\n    o_color = vec4(1.0) +;\n}\n'
    ),
    "bad_syntax.glsl": "float broken(float x) {\n    float y = x;\n    return y +;\n}\n",
    "syntax_include.frag": (
        'out vec4 o_color;\n#include "bad_syntax.glsl"\nvoid main() {\n    o_color = vec4(broken(1.0));\n}\n'
    ),
    "bad_ident.glsl": "float broken(float x) {\n    float y = x;\n    return y * not_declared;\n}\n",
    "ident_include.frag": (
        'out vec4 o_color;\n#include "bad_ident.glsl"\nvoid main() {\n    o_color = vec4(broken(1.0));\n}\n'
    ),
    "bad.vert": "void main() {\n    gl_Position = vec4(1.0) +;\n}\n",
    "cycle_a.frag": 'out vec4 o_color;\n#include "cycle_b.glsl"\nvoid main() {}\n',
    "cycle_b.glsl": '#include "cycle_a.frag"\n',
    "missing_include.frag": 'out vec4 o_color;\n#include "nothere.glsl"\nvoid main() {}\n',
}


@pytest.fixture(scope="module")
def shader_pkg(tmp_path_factory) -> str:
    """Name of an importable package holding SHADERS (unique: loaders cache by package name)."""
    name = f"bp_shadertest_{uuid.uuid4().hex[:8]}"
    root = tmp_path_factory.mktemp("shaders")
    folder = root / name
    folder.mkdir()
    (folder / "__init__.py").write_text("")
    for file, text in SHADERS.items():
        (folder / file).write_text(text)
    sys.path.insert(0, str(root))
    yield name
    sys.path.remove(str(root))
    sys.modules.pop(name, None)


def depth_glsl() -> str:
    path = Path(blueprint.__file__).parent / "gpu" / "glsl" / "depth.glsl"
    return path.read_text(encoding="utf-8")


# -- context ---------------------------------------------------------------------------------------


def test_context_factory_reports_missing_backend_in_one_line(monkeypatch):
    monkeypatch.setenv("BLUEPRINT_GL_BACKEND", "no-such-backend")
    with pytest.raises(GLUnavailableError) as info:
        create_context()
    message = str(info.value)
    assert "\n" not in message
    assert "no usable OpenGL 3.3 context" in message and "no-such-backend" in message


def test_context_is_made_without_searching_for_the_gl_libraries(monkeypatch):
    import ctypes.util

    def searched(name):
        raise AssertionError(f"find_library({name!r}) runs ldconfig at every start")

    monkeypatch.setattr(ctypes.util, "find_library", searched)
    ctx = create_context()
    try:
        assert ctx.version_code >= 330 and ctx.info["GL_RENDERER"]
    finally:
        ctx.release()


def test_gl_info_smoke(renderer):
    data = gl_info(renderer.ctx)
    assert set(data) == {"renderer", "vendor", "version", "max_texture_size"}
    assert data["renderer"] and int(data["max_texture_size"]) >= 1024
    assert renderer.max_texture == int(data["max_texture_size"])


# -- shader preprocessing --------------------------------------------------------------------------


def test_depth_snap_probe(renderer):
    """Two triangles on one plane, drawn one after the other, are as far apart in depth as the
    driver's snapping makes them: nothing but rounding on llvmpipe (1.5e-5 px), about 2e-3 px
    on the H200 (1/256-px corners), never more than the 1/16 px the GL spec allows."""
    px = renderer.depth_snap_px()
    assert 0.0 <= px < 1 / 16
    assert renderer.snapped_depth == (px > SNAPPED_DEPTH_PX)
    assert capture_table(renderer).exact_depth == renderer.snapped_depth
    if renderer.software:
        assert not renderer.snapped_depth, px
    assert renderer.ctx.error == "GL_NO_ERROR"


def test_preprocess_resolves_includes_defines_and_line_directives(shader_pkg):
    source, files = preprocess(f"{shader_pkg}:main.frag", {"SCALE": 2, "FLAG": True})
    expected = (
        "#version 330 core\n"
        "#define SCALE 2\n"
        "#define FLAG 1\n"
        "#line 1 0\n"
        "out vec4 o_color;\n"
        "#line 100001 1\n" + SHADERS["helper.glsl"] + "#line 3 0\n"
        "#line 200001 2\n" + depth_glsl().rstrip("\n") + "\n"
        "#line 4 0\n"
        "void main() {\n"
        "    o_color = vec4(helper(eye_depth(0.5)) * float(SCALE) * float(FLAG));\n"
        "}\n"
    )
    assert source == expected
    assert files == [f"{shader_pkg}/main.frag", f"{shader_pkg}/helper.glsl", "blueprint/gpu/glsl/depth.glsl"]


def test_package_files_are_a_folder_or_a_zip_archives_resources(tmp_path):
    import zipfile

    import blueprint.ops

    assert package_files("blueprint.ops") == Path(blueprint.ops.__file__).parent
    name = f"bp_zipshaders_{uuid.uuid4().hex[:8]}"
    archive = tmp_path / "shaders.zip"
    with zipfile.ZipFile(archive, "w") as zf:
        zf.writestr(f"{name}/__init__.py", "")
        zf.writestr(f"{name}/glsl/main.frag", SHADERS["main.frag"])
        zf.writestr(f"{name}/glsl/helper.glsl", SHADERS["helper.glsl"])
    sys.path.insert(0, str(archive))
    try:
        files = package_files(name)
        assert not isinstance(files, Path) and files.joinpath("glsl/helper.glsl").is_file()
        source, names = preprocess(f"{name}:glsl/main.frag", {"SCALE": 1, "FLAG": 1})
    finally:
        sys.path.remove(str(archive))
        sys.modules.pop(name, None)
    assert names == [f"{name}/glsl/main.frag", f"{name}/glsl/helper.glsl", "blueprint/gpu/glsl/depth.glsl"]
    assert "return x * 2.0;" in source and "float eye_depth(" in source


def test_preprocessed_shader_compiles(renderer, shader_pkg):
    prog = build_program(renderer.ctx, "fullscreen.vert", f"{shader_pkg}:main.frag", {"SCALE": 2, "FLAG": 1})
    assert "u_depth_range" in prog
    prog.release()


def test_include_cycle_is_a_shader_error(shader_pkg):
    with pytest.raises(ShaderError, match="#include cycle"):
        preprocess(f"{shader_pkg}:cycle_a.frag")


def test_missing_include_names_the_file(shader_pkg):
    with pytest.raises(ShaderError, match=r"nothere\.glsl not found"):
        preprocess(f"{shader_pkg}:missing_include.frag")


@pytest.mark.parametrize(
    "vertex, fragment, where",
    [
        ("fullscreen.vert", "syntax_main.frag", "syntax_main.frag:4"),
        ("fullscreen.vert", "syntax_include.frag", "bad_syntax.glsl:3"),
        ("bad.vert", "main.frag", "bad.vert:2"),
    ],
    ids=["fragment-main-file", "fragment-include", "vertex"],
)
def test_compile_error_names_file_and_line(renderer, shader_pkg, vertex, fragment, where):
    vertex = f"{shader_pkg}:{vertex}" if vertex.startswith("bad") else vertex
    with pytest.raises(ShaderError) as info:
        build_program(renderer.ctx, vertex, f"{shader_pkg}:{fragment}", {"SCALE": 1, "FLAG": 1})
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"shader error: {shader_pkg}/{where}: "), message
    assert "error" in message.split(where, 1)[1]


def test_undeclared_identifier_in_include_names_the_include(renderer, shader_pkg):
    """Mesa reports some errors with source-string number 0 whatever ``#line N S`` said: here
    "0:3(13): error: `not_declared' undeclared" (a later message on the same line says "1:3(2)"),
    so the user is sent to ident_include.frag:3, the wrong file, instead of bad_ident.glsl:3."""
    with pytest.raises(ShaderError) as info:
        build_program(renderer.ctx, "fullscreen.vert", f"{shader_pkg}:ident_include.frag")
    assert f"{shader_pkg}/bad_ident.glsl:3:" in str(info.value), str(info.value)


def test_explain_maps_mesa_and_nvidia_locations():
    files = ["pkg/a.frag", "pkg/b.glsl"]
    # line numbers carry the file (LINE_BASE), whatever source string the compiler reports
    mesa = (
        "GLSL Compiler failed\n\nfragment_shader\n===============\n"
        "0:100007(12): error: `x' undeclared\n0:9(3): error: something else\n"
    )
    assert _explain(mesa, files) == "pkg/b.glsl:7: error: `x' undeclared"
    assert _explain("0:12(3): error: syntax error", files) == "pkg/a.frag:12: error: syntax error"
    nvidia = '0(100012) : error C1008: undefined variable "x"'
    assert _explain(nvidia, files) == 'pkg/b.glsl:12: error C1008: undefined variable "x"'
    # a file number the preprocessor never issued is left as it is
    assert _explain("0:500002(1): error: odd", files) == "0:500002(1): error: odd"


# -- the target pool --------------------------------------------------------------------------------


def _released(gl_object) -> bool:
    return type(gl_object.mglo).__name__ == "InvalidObject"


@pytest.fixture
def pool(renderer):
    p = TargetPool(renderer.ctx)
    yield p
    p.release()


def test_pool_reuses_texture_for_same_name_size_format(pool):
    a = pool.texture("t", (8, 4), "r32f")
    assert pool.texture("t", (8, 4), "r32f") is a
    assert a.size == (8, 4) and a.components == 1 and a.dtype == "f4"
    other = pool.texture("u", (8, 4), "r32f")
    assert other is not a


@pytest.mark.parametrize("change", [{"size": (16, 4)}, {"fmt": "rgba8"}], ids=["resize", "format"])
def test_pool_recreates_texture_on_change_and_releases_old(pool, change):
    old = pool.texture("t", (8, 4), "r32f")
    fbo = pool.framebuffer((old,))
    assert pool.framebuffer((old,)) is fbo
    args = {"size": (8, 4), "fmt": "r32f", **change}
    new = pool.texture("t", args["size"], args["fmt"])
    assert new is not old and new.size == args["size"]
    assert _released(old) and _released(fbo)
    new_fbo = pool.framebuffer((new,))
    assert new_fbo is not fbo and new_fbo.size == args["size"]


def test_pool_depth_buffer_reused_and_recreated(pool):
    z = pool.depth("z", (8, 4))
    assert pool.depth("z", (8, 4)) is z
    color = pool.texture("c", (8, 4), "rgba8")
    fbo = pool.framebuffer((color,), z)
    bigger = pool.depth("z", (16, 8))
    assert bigger is not z and bigger.size == (16, 8)
    assert _released(z) and _released(fbo)
    assert not _released(color)


def test_pool_release_releases_everything(renderer):
    p = TargetPool(renderer.ctx)
    tex = p.texture("t", (4, 4), "rgba8")
    z = p.depth("z", (4, 4))
    fbo = p.framebuffer((tex,), z)
    p.release()
    assert _released(tex) and _released(z) and _released(fbo)


def test_pool_unknown_format_keeps_the_held_texture(pool):
    """The format is validated after the held texture was already dropped: a rejected request
    must not destroy a target other passes still borrow."""
    held = pool.texture("t", (8, 4), "r32f")
    with pytest.raises(ValueError, match="unknown target format 'bogus'"):
        pool.texture("t", (8, 4), "bogus")
    assert not _released(held)
    assert pool.texture("t", (8, 4), "r32f") is held


def test_pool_sliced_array_is_drawn_a_slice_at_a_time_and_read_whole(renderer, pool):
    """Each slice of a ``SlicedArray`` a render target of its own; one sampler of the array
    reads them all back; a new size drops the old array, its slices and their framebuffer."""
    if not pool.slices_viewed:
        pytest.skip("this context makes no texture views")
    ctx = renderer.ctx
    w, h, k = 24, 10, 5
    array = pool.sliced("s", (w, h), "rgba32ui", k)
    assert pool.sliced("s", (w, h), "rgba32ui", k) is array
    assert [t.size for t in array.slices] == [(w, h)] * k
    fbo = pool.framebuffer(array.slices)
    fbo.use()
    vertex = (
        "#version 330\nvoid main() { vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);"
        " gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }"
    )
    draw = ctx.program(
        vertex_shader=vertex,
        fragment_shader="#version 330\n"
        + "".join(f"layout(location = {i}) out uvec4 o{i};\n" for i in range(k))
        + "void main() { uvec2 p = uvec2(gl_FragCoord.xy);"
        + "".join(f" o{i} = uvec4(p, {i}u, {100 + i}u);" for i in range(k))
        + " }",
    )
    read = ctx.program(
        vertex_shader=vertex,
        fragment_shader="#version 330\nuniform usampler2DArray u_array; uniform int u_slice; out uvec4 o;"
        " void main() { o = texelFetch(u_array, ivec3(ivec2(gl_FragCoord.xy), u_slice), 0); }",
    )
    vaos = [ctx.vertex_array(draw, []), ctx.vertex_array(read, [])]
    vaos[0].render(vertices=3)
    out = pool.texture("out", (w, h), "rgba32ui")
    pool.framebuffer((out,)).use()
    array.use(3)
    read["u_array"].value = 3
    ys, xs = np.mgrid[0:h, 0:w]
    for i in range(k):
        read["u_slice"].value = i
        vaos[1].render(vertices=3)
        got = np.frombuffer(out.read(), np.uint32).reshape(h, w, 4)
        want = np.stack([xs, ys, np.full_like(xs, i), np.full_like(xs, 100 + i)], axis=-1)
        np.testing.assert_array_equal(got, want)
    for held in (*vaos, draw, read):
        held.release()
    names = [t.glo for t in array.slices] + [array.glo]
    bigger = pool.sliced("s", (w + 8, h), "rgba32ui", k)
    assert bigger is not array and bigger.slices[0].size == (w + 8, h)
    assert _released(fbo) and not array.slices
    # a driver may give the released names to the bigger array's textures
    reused = {t.glo for t in bigger.slices} | {bigger.glo}
    assert not any(pool._gl.glIsTexture(name) for name in names if name not in reused)


# -- sizes are checked before any rendering ---------------------------------------------------------


def test_check_size_exact():
    assert check_size((640, 480), 2, 4096) == (640, 480)
    assert check_size((2048, 1), 2, 4096) == (2048, 1)
    for size in [(0, 0), (0, 10), (10, -5)]:
        with pytest.raises(InputError, match="at least 1x1"):
            check_size(size, 2, 4096)
    with pytest.raises(InputError, match="this GPU allows 2048 pixels per side"):
        check_size((2049, 1), 2, 4096)
    with pytest.raises(InputError, match="two integers"):
        check_size(("wide", 3), 2, 4096)
    for ss in (0, 5):
        with pytest.raises(InputError, match="supersample"):
            check_size((8, 8), ss, 4096)


def _pool_state(renderer) -> dict:
    return {name: id(tex) for name, (_, tex) in renderer.pool._textures.items()}


@pytest.mark.parametrize("how", ["render", "peel"])
def test_bad_sizes_rejected_before_any_gpu_work(renderer, how):
    model = blueprint.Model.from_arrays(*examples.box((0, 0, 0), (1, 1, 1)))
    call = {"render": blueprint.render_frame, "peel": blueprint.peel}[how]
    too_large = renderer.max_texture + 1
    before = _pool_state(renderer)
    meshes = dict(renderer.capturer._meshes)
    for size in [(0, 0), (64, 0), (too_large, 8), (8, too_large)]:
        with pytest.raises(InputError, match="size"):
            call(model, size=size, renderer=renderer)
    assert _pool_state(renderer) == before, "targets were (re)allocated for a rejected size"
    assert dict(renderer.capturer._meshes) == meshes, "the model was uploaded for a rejected size"


@pytest.mark.parametrize(
    "options, message",
    [
        ({"max_layers": 0}, "max_layers"),
        ({"max_layers": 257}, "max_layers"),
        ({"min_fraction": -0.1}, "min_fraction"),
        ({"min_fraction": 1.5}, "min_fraction"),
        ({"crease_angle": -1.0}, "crease_angle"),
        ({"crease_angle": 181.0}, "crease_angle"),
        ({"line_width": 0.5}, "line_width"),
        ({"line_width": 17.0}, "line_width"),
        ({"supersample": 0}, "supersample"),
        ({"fov": 0.0}, "field of view"),
        ({"fov": 180.0}, "field of view"),
        ({"view": "sideways"}, "unknown view"),
        ({"style": "neon"}, "unknown style"),
        ({"depth_threshold": 0.0}, "depth_threshold"),
    ],
    ids=lambda v: "-".join(f"{k}={x}" for k, x in v.items()) if isinstance(v, dict) else None,
)
def test_frame_arguments_rejected_before_rendering(renderer, options, message):
    model = blueprint.Model.from_arrays(*examples.box((0, 0, 0), (1, 1, 1)))
    before = _pool_state(renderer)
    with pytest.raises(InputError, match=message):
        blueprint.render_frame(model, size=(16, 16), renderer=renderer, **options)
    assert _pool_state(renderer) == before


def test_render_smoke_tiny_box(renderer):
    """A box seen from the front, orthographic: its outline is drawn, the middle is paper."""
    model = blueprint.Model.from_arrays(*examples.box((0, 0, 0), (1, 1, 1)))
    frame = blueprint.render_frame(model, size=(32, 32), view="front", ortho=True, renderer=renderer)
    assert frame.image.shape == (32, 32, 4) and frame.image.dtype == np.uint8
    assert frame.layers == 2  # front face, back face
    paper = np.array([0x12, 0x45, 0x7A, 255], np.uint8)
    np.testing.assert_array_equal(frame.image[0, 0], paper)
    np.testing.assert_array_equal(frame.image[16, 16], paper)
    # the silhouette is at 5 % margin: columns 1..2 and 29..30 carry ink on the middle row
    row = frame.image[16, :, 0].astype(int)
    assert row[:4].max() > 150 and row[-4:].max() > 150


def test_capability_probes_compile_what_they_claim(renderer):
    """A feature counts only where the driver builds a shader using it: an extension name
    alone is not enough, and a shader it cannot build is no capability."""
    from blueprint.gpu.device import INTERLOCK_PROBE

    trivial = "#version 430 core\nout vec4 o;\nvoid main() { o = vec4(1.0); }\n"
    broken = "#version 430 core\nvoid main() { undeclared = 1; }\n"
    assert renderer.device._compiles(trivial) == (renderer.ctx.version_code >= 430)
    assert not renderer.device._compiles(broken)
    listed = "GL_ARB_fragment_shader_interlock" in renderer.ctx.extensions
    assert renderer.fragment_interlock == (listed and renderer.device._compiles(INTERLOCK_PROBE))
    # where both exist, framebuffer fetch holds the k-buffer; interlock only where fetch is missing
    row = capture_table(renderer).row("k-buffer")
    interlock = renderer.fragment_interlock and not renderer.framebuffer_fetch
    assert (row is not None and row.interlock) == interlock
