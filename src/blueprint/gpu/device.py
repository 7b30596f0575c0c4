"""The device: one OpenGL context and everything held on it by name (the target pool, query
sets, compiled programs), with what the context can do."""

from __future__ import annotations

import functools

from blueprint.errors import InputError
from blueprint.gpu.context import create_context, gl_info
from blueprint.gpu.queries import Queries
from blueprint.gpu.shaders import COMPUTE_VERSION, VERSION, build_compute, build_program
from blueprint.gpu.targets import TargetPool
from blueprint.gpu.uniforms import Uniforms

INTERLOCK_PROBE = """#version 430 core
#extension GL_ARB_fragment_shader_interlock : require
layout(pixel_interlock_ordered) in;
layout(binding = 0, r32ui) coherent uniform uimage2D u_count;
void main() {
    beginInvocationInterlockARB();
    imageStore(u_count, ivec2(gl_FragCoord.xy), imageLoad(u_count, ivec2(gl_FragCoord.xy)) + 1u);
    endInvocationInterlockARB();
}
"""


def current(method):
    """Make the device's context current for the call, and leave it so: a process may hold
    several contexts (a window, the API's default renderer, test fixtures), and GL calls go to
    whichever is current."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        self.make_current()
        return method(self, *args, **kwargs)

    return wrapper


class Device:
    """Owns one OpenGL context (headless unless ``ctx`` is a window's), its targets, queries
    and programs. Use as a context manager or call ``release()``.

    ``software``: the renderer is a software rasteriser (llvmpipe, softpipe).
    ``use_compute``: image passes run as compute shaders (OpenGL 4.3 on a GPU).
    ``framebuffer_fetch``: a fragment may read what the ones before it wrote to its pixel.
    ``fragment_interlock``: fragments of one pixel may run a critical section one after
    another in primitive order (GL_ARB_fragment_shader_interlock; probed by compiling one).
    """

    def __init__(self, ctx=None) -> None:
        self.ctx = ctx if ctx is not None else create_context()
        self.pool = TargetPool(self.ctx)
        self.queries = Queries(self.ctx)
        self.uniforms = Uniforms()
        self._programs: dict[tuple, object] = {}
        self._fullscreen: dict[int, object] = {}
        self.info = gl_info(self.ctx)
        self.max_texture = int(self.info["max_texture_size"])
        # on GPUs built for compute (H100, H200) only a few cores rasterise, while compute
        # shaders run on all of them
        self.software = any(name in self.info["renderer"].lower() for name in ("llvmpipe", "softpipe"))
        self.use_compute = self.ctx.version_code >= 430 and not self.software
        ext = self.ctx.extensions
        self.framebuffer_fetch = "GL_EXT_shader_framebuffer_fetch" in ext and (
            self.ctx.version_code >= 420 or "GL_ARB_shading_language_packing" in ext
        )
        self.max_draw_buffers = int(self.ctx.info["GL_MAX_DRAW_BUFFERS"])
        self.fragment_interlock = (
            self.ctx.version_code >= 430
            and "GL_ARB_fragment_shader_interlock" in ext
            and self._compiles(INTERLOCK_PROBE)
        )

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def make_current(self) -> None:
        """Direct this thread's GL calls to this device's context."""
        self.ctx.__enter__()

    def release(self) -> None:
        self.make_current()
        self.pool.release()
        self.queries.release()
        for vao in self._fullscreen.values():
            vao.release()
        for prog in self._programs.values():
            prog.release()
        self._programs.clear()
        self.ctx.release()

    def program(
        self,
        fragment: str,
        vertex: str = "fullscreen.vert",
        defines=None,
        modern: bool = False,
        geometry: str | None = None,
    ):
        """A program from shader files, built once; ``modern``: GLSL 4.30 (image load/store);
        ``geometry``: a geometry shader between the two."""
        key = (vertex, fragment, tuple(sorted((defines or {}).items())), modern, geometry)
        prog = self._programs.get(key)
        if prog is None:
            version = COMPUTE_VERSION if modern else VERSION
            prog = self._programs[key] = build_program(self.ctx, vertex, fragment, defines, version, geometry)
        return prog

    def _compiles(self, fragment_source: str) -> bool:
        """Whether the driver builds a full-screen program of this fragment shader: an
        extension listed is not always one that works."""
        vertex = "#version 430 core\nvoid main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); }\n"
        try:
            self.ctx.program(vertex_shader=vertex, fragment_shader=fragment_source).release()
        except Exception:
            return False
        return True

    def compute(self, ref: str, defines=None):
        key = ("compute", ref, tuple(sorted((defines or {}).items())))
        prog = self._programs.get(key)
        if prog is None:
            prog = self._programs[key] = build_compute(self.ctx, ref, defines)
        return prog

    def fullscreen(self, fragment: str, defines=None):
        """(program, vertex array) of a full-screen pass drawing one triangle."""
        prog = self.program(fragment, defines=defines)
        vao = self._fullscreen.get(prog.glo)
        if vao is None:
            vao = self._fullscreen[prog.glo] = self.ctx.vertex_array(prog, [])
        return prog, vao


def check_size(size: tuple[int, int], supersample: int, max_texture: int) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in size)
    except (TypeError, ValueError):
        raise InputError(f"size must be two integers W H, got {size!r}") from None
    if w < 1 or h < 1:
        raise InputError(f"size must be at least 1x1 pixels, got {w}x{h}")
    if not 1 <= supersample <= 4:
        raise InputError(f"supersample must be 1, 2, 3 or 4, got {supersample}")
    if max(w, h) * supersample > max_texture:
        limit = max_texture // supersample
        raise InputError(
            f"size {w}x{h} is too large: at supersample {supersample} this GPU allows {limit} pixels per side"
        )
    return w, h
