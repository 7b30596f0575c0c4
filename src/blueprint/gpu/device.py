"""The device: one OpenGL context and everything held on it by name (the target pool, query
sets, compiled programs), with what the context can do."""

from __future__ import annotations

import functools

import numpy as np

from blueprint.errors import InputError
from blueprint.gpu.context import create_context, gl_flush, gl_info
from blueprint.gpu.queries import Queries
from blueprint.gpu.shaders import COMPUTE_VERSION, VERSION, build_compute, build_program
from blueprint.gpu.targets import TargetPool
from blueprint.gpu.uniforms import Uniforms

# workgroups along a dispatch's x at most (every dimension holds 65535 at least)
MAX_GROUPS = 65535


def run_over(prog, count: int, group: int) -> None:
    """Run compute ``prog`` (``group`` invocations a workgroup along x) over ``count``
    invocations, its groups in rows of at most ``MAX_GROUPS``: invocation
    ``gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x *
    gl_WorkGroupSize.x``, those from ``count`` on returning at once."""
    groups = -(-count // group)
    if groups:
        across = min(groups, MAX_GROUPS)
        prog.run(across, -(-groups // across))


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

# Two triangles on one steep plane, corners in pixels of a 64x64 target, off the sub-pixel
# grids rasterisers snap to: where the driver takes depth from the plane through the snapped
# corners, the two differ in depth where they overlap.
_SNAP_PLANE = (0.3, 0.2)  # NDC depth = 0.3 x + 0.2 y
_SNAP_TRIANGLES = (
    (3.3017, 2.7123, 61.1931, 5.4409, 30.5553, 60.8847),
    (1.9087, 58.2331, 62.6719, 59.0173, 33.1277, 1.3391),
)
_SNAP_VERTEX = f"""#version 330
in vec2 in_px;
void main() {{
    vec2 ndc = in_px / 32.0 - 1.0;
    gl_Position = vec4(ndc, {_SNAP_PLANE[0]} * ndc.x + {_SNAP_PLANE[1]} * ndc.y, 1.0);
}}
"""
_SNAP_FRAGMENT = "#version 330\nout float o_depth;\nvoid main() { o_depth = gl_FragCoord.z; }\n"
# Apart by more than this many pixels' worth of the plane's slope, the two triangles' depths
# come from snapped corners: llvmpipe's differ by 1.5e-5 px (rounding), a rasteriser snapping
# to 1/256 px by up to about 4e-3.
SNAPPED_DEPTH_PX = 5e-4


def current(method):
    """Make the device's context current for the call, and leave it so: a process may hold
    several contexts (a window, the API's default renderer, test fixtures), and GL calls go to
    whichever is current."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        self.make_current()
        return method(self, *args, **kwargs)

    return wrapper


# bytes a storage buffer is bound with at most, whatever the driver allows: byte offsets past it
# would not fit a signed 32-bit integer, which a driver's address arithmetic may use
MOST_BINDING = (1 << 31) - 1


def storage_bytes(ctx) -> int:
    """Bytes one storage buffer binding of ``ctx`` holds at most: the driver's
    ``GL_MAX_SHADER_STORAGE_BLOCK_SIZE`` (none below OpenGL 4.3), never past ``MOST_BINDING``."""
    limit = int(ctx.info.get("GL_MAX_SHADER_STORAGE_BLOCK_SIZE") or 0)
    return min(limit, MOST_BINDING) if limit > 0 else 0


class Device:
    """Owns one OpenGL context (headless unless ``ctx`` is a window's), its targets, queries
    and programs. Use as a context manager or call ``release()``.

    ``software``: the renderer is a software rasteriser (llvmpipe, softpipe).
    ``use_compute``: image passes run as compute shaders (OpenGL 4.3 on a GPU).
    ``framebuffer_fetch``: a fragment may read what the ones before it wrote to its pixel.
    ``fragment_interlock``: fragments of one pixel may run a critical section one after
    another in primitive order (GL_ARB_fragment_shader_interlock; probed by compiling one).
    ``subgroup_ballot``: a shader may count and rank the invocations of its subgroup, helper
    invocations told apart (GL_ARB_shader_ballot, 64-bit integers for its masks,
    GL_ARB_ES3_1_compatibility for gl_HelperInvocation).
    ``storage_bytes``: the most bytes one storage buffer binding holds (``storage_bytes``).
    ``snapped_depth``: a fragment's depth comes from the plane through its triangle's corners
    as snapped to the sub-pixel grid, not as projected (measured by ``depth_snap_px``), so
    coincident triangles with different corners differ in depth by up to the slope times the
    snap.
    """

    def __init__(self, ctx=None) -> None:
        self.ctx = ctx if ctx is not None else create_context()
        self.pool = TargetPool(self.ctx)
        self.queries = Queries(self.ctx)
        self.uniforms = Uniforms()
        self._programs: dict[tuple, object] = {}
        # the same programs by their arguments as given, defines in the caller's order: found
        # without sorting them (a streamed frame looks up a dozen programs)
        self._given: dict[tuple, object] = {}
        self._fullscreen: dict[int, object] = {}
        self.info = gl_info(self.ctx)
        self.max_texture = int(self.info["max_texture_size"])
        # on GPUs built for compute only a few cores rasterise, while compute shaders run on
        # all of them
        self.software = any(name in self.info["renderer"].lower() for name in ("llvmpipe", "softpipe"))
        self.use_compute = self.ctx.version_code >= 430 and not self.software
        ext = self.ctx.extensions
        self.framebuffer_fetch = "GL_EXT_shader_framebuffer_fetch" in ext and (
            self.ctx.version_code >= 420 or "GL_ARB_shading_language_packing" in ext
        )
        self.max_draw_buffers = int(self.ctx.info["GL_MAX_DRAW_BUFFERS"])
        self.storage_bytes = storage_bytes(self.ctx)
        self.fragment_interlock = (
            self.ctx.version_code >= 430
            and "GL_ARB_fragment_shader_interlock" in ext
            and self._compiles(INTERLOCK_PROBE)
        )
        self.subgroup_ballot = all(
            e in ext
            for e in ("GL_ARB_shader_ballot", "GL_ARB_gpu_shader_int64", "GL_ARB_ES3_1_compatibility")
        )
        self.snapped_depth = self.depth_snap_px() > SNAPPED_DEPTH_PX

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def make_current(self) -> None:
        """Direct this thread's GL calls to this device's context."""
        self.ctx.__enter__()

    @current
    def flush(self) -> None:
        """Start the driver on what has been drawn so far and go on (``context.gl_flush``)."""
        gl_flush()

    def release(self) -> None:
        self.make_current()
        self.pool.release()
        self.queries.release()
        for vao in self._fullscreen.values():
            vao.release()
        for prog in self._programs.values():
            prog.release()
        self._programs.clear()
        self._given.clear()
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
        given = (vertex, fragment, modern, geometry, *(defines or {}).items())
        if given in self._given:
            return self._given[given]
        key = (vertex, fragment, tuple(sorted((defines or {}).items())), modern, geometry)
        prog = self._programs.get(key)
        if prog is None:
            version = COMPUTE_VERSION if modern else VERSION
            prog = self._programs[key] = build_program(self.ctx, vertex, fragment, defines, version, geometry)
        self._given[given] = prog
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

    def depth_snap_px(self) -> float:
        """How far apart, in pixels' worth of the plane's slope, the driver puts the depths of
        two triangles lying on one plane where they overlap."""
        ctx = self.ctx
        prog = ctx.program(vertex_shader=_SNAP_VERTEX, fragment_shader=_SNAP_FRAGMENT)
        # the pool's: a framebuffer released while bound leaves moderngl binding a dead one
        target = self.pool.texture("snap.depth", (64, 64), "r32f")
        fbo = self.pool.framebuffer((target,))
        depths = []
        fbo.use()
        for corners in _SNAP_TRIANGLES:
            vbo = ctx.buffer(np.array(corners, "f4"))
            vao = ctx.vertex_array(prog, [(vbo, "2f", "in_px")])
            fbo.clear(-1.0)
            vao.render()
            depths.append(np.frombuffer(target.read(), "f4"))
            vao.release()
            vbo.release()
        prog.release()
        a, b = depths
        both = (a >= 0.0) & (b >= 0.0)
        if not both.any():
            return 0.0
        slope = 0.5 * sum(_SNAP_PLANE) / 32.0  # window depth a pixel along x plus along y
        return float(np.abs(a[both] - b[both]).max() / slope)

    def compute(self, ref: str, defines=None):
        given = ("compute", ref, *(defines or {}).items())
        if given in self._given:
            return self._given[given]
        key = ("compute", ref, tuple(sorted((defines or {}).items())))
        prog = self._programs.get(key)
        if prog is None:
            prog = self._programs[key] = build_compute(self.ctx, ref, defines)
        self._given[given] = prog
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
        w, h = size
        w, h = int(w), int(h)
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


# GL_NVX_gpu_memory_info's queries: the memory the GPU has in all, and free now
TOTAL_AVAILABLE_NVX, CURRENT_AVAILABLE_NVX = 0x9048, 0x9049


def nvx_memory(ctx, query: int) -> int | None:
    """Bytes of NVIDIA's ``GL_NVX_gpu_memory_info`` ``query`` (``TOTAL_AVAILABLE_NVX``,
    ``CURRENT_AVAILABLE_NVX``) on ``ctx``, or None where the driver does not tell."""
    if "GL_NVX_gpu_memory_info" not in ctx.extensions:
        return None
    import ctypes

    try:
        gl = ctypes.CDLL("libOpenGL.so.0")
        value = ctypes.c_int(0)
        gl.glGetIntegerv(query, ctypes.byref(value))  # in KiB
    except (OSError, AttributeError):
        return None
    return value.value * 1024 if value.value > 0 else None
