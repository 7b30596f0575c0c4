"""The renderer: owns the GL context, the target pool and uploaded meshes; peels depth layers,
turns each into an edge map and composes the blueprint."""

from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass, field

import numpy as np

from blueprint.compose.style import Style, get_style
from blueprint.errors import InputError
from blueprint.gpu import TargetPool, build_program, create_context, gl_info
from blueprint.ops import DILATE, EDGES
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model
from blueprint.scene.normals import corner_normals

# Layers peeled between two looks at the occlusion queries when no maximum is set: one CPU
# wait per chunk instead of one per layer.
CHUNK = 8
HARD_MAX_LAYERS = 256
# Peeling tolerance in eye depth, as a fraction of the camera's depth range: surfaces closer
# than this count as one (coplanar faces, duplicates, touching parts).
PEEL_EPSILON = 1e-5
GEOMETRY_VERT = "blueprint.render:glsl/geometry.vert"
PEEL_FRAG = "blueprint.render:glsl/peel.frag"
# Window-depth push of back faces (16 steps of a 24-bit depth buffer), see peel.frag.
BACK_BIAS = 16.0 / (1 << 24)


@dataclass
class Frame:
    """One rendered blueprint.

    ``image`` is (H, W, 4) uint8 RGBA, row 0 at the top, straight alpha. ``layer_pixels`` holds
    the covered samples of every layer peeled (at the supersampled size), ``layers`` how many
    of them were drawn.
    """

    image: np.ndarray
    layers: int
    layer_pixels: list[int]
    camera: Camera
    ms: float
    draws: int
    stages: dict[str, float] = field(default_factory=dict)


@dataclass
class Layers:
    """Depth layers read back from the GPU.

    depth : (L, H, W) float32, window depth in [0, 1], 1.0 where there is no surface
    normal : (L, H, W, 3) float32, eye-space normal facing the viewer, 0 where none
    triangle : (L, H, W) int32, face index in the model, -1 where none
    part : (L, H, W) int32, part index, -1 where none
    view, projection : (4, 4) float64
    """

    depth: np.ndarray
    normal: np.ndarray
    triangle: np.ndarray
    part: np.ndarray
    view: np.ndarray
    projection: np.ndarray
    camera: Camera


class _Mesh:
    """A model's triangles on the GPU, one vertex per corner (flat IDs, crease-split normals)."""

    def __init__(self, ctx, program, model: Model, crease_angle: float) -> None:
        keep = np.flatnonzero(~model.degenerate_faces())
        faces = model.faces[keep]
        data = np.empty((len(keep), 3), [("p", "f4", 3), ("n", "f4", 3), ("ids", "i4", 2)])
        data["p"] = model.positions[faces]
        data["n"] = corner_normals(model.positions, faces, crease_angle)
        data["ids"][:, :, 0] = keep[:, None]
        data["ids"][:, :, 1] = model.face_part[keep][:, None]
        self.vertices = len(keep) * 3
        self.vbo = ctx.buffer(data.tobytes())
        self.vao = ctx.vertex_array(program, [(self.vbo, "3f 3f 2i", "in_position", "in_normal", "in_ids")])

    def release(self) -> None:
        self.vao.release()
        self.vbo.release()


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


class Renderer:
    """Owns one OpenGL context, its targets, programs and uploaded meshes.

    Use as a context manager or call ``release()``. Models, cameras and styles stay GPU-free;
    the renderer uploads a model once per (model, crease angle).
    """

    def __init__(self, ctx=None) -> None:
        self.ctx = ctx if ctx is not None else create_context()
        self.pool = TargetPool(self.ctx)
        self._programs: dict[tuple, object] = {}
        self._meshes: dict[tuple[int, float], tuple[Model, _Mesh]] = {}
        self._queries: list = []
        self._fullscreen = {}
        self.info = gl_info(self.ctx)
        self.max_texture = int(self.info["max_texture_size"])

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def release(self) -> None:
        for _, mesh in self._meshes.values():
            mesh.release()
        self._meshes.clear()
        self.pool.release()
        for vao in self._fullscreen.values():
            vao.release()
        for prog in self._programs.values():
            prog.release()
        self._programs.clear()
        self.ctx.release()

    # -- resources ---------------------------------------------------------------------------
    def program(self, fragment: str, vertex: str = "fullscreen.vert", defines=None):
        key = (vertex, fragment, tuple(sorted((defines or {}).items())))
        prog = self._programs.get(key)
        if prog is None:
            prog = self._programs[key] = build_program(self.ctx, vertex, fragment, defines)
        return prog

    def fullscreen(self, fragment: str):
        """(program, vertex array) of a full-screen pass drawing one triangle."""
        prog = self.program(fragment)
        vao = self._fullscreen.get(fragment)
        if vao is None:
            vao = self._fullscreen[fragment] = self.ctx.vertex_array(prog, [])
        return prog, vao

    def mesh(self, model: Model, crease_angle: float) -> _Mesh:
        key = (id(model), float(crease_angle))
        held = self._meshes.get(key)
        if held is None or held[0] is not model:
            prog = self.program("blueprint.render:glsl/peel.frag", "blueprint.render:glsl/geometry.vert")
            held = self._meshes[key] = (model, _Mesh(self.ctx, prog, model, crease_angle))
        return held[1]

    def forget(self, model: Model) -> None:
        """Release the GPU copy of a model."""
        for key in [k for k, (m, _) in self._meshes.items() if m is model]:
            self._meshes.pop(key)[1].release()

    def _query(self, i: int):
        while len(self._queries) <= i:
            self._queries.append(self.ctx.query(samples=True))
        return self._queries[i]

    # -- camera --------------------------------------------------------------------------------
    @staticmethod
    def camera_for(model: Model, size: tuple[int, int], view: str = "iso", **kwargs) -> Camera:
        return Camera.fit(model.positions, view, aspect=size[0] / size[1], up=model.up, **kwargs)

    # -- peeling -------------------------------------------------------------------------------
    def _gbuffer(self, size: tuple[int, int]):
        pool = self.pool
        depth = (pool.texture("gb.depth0", size, "r32f"), pool.texture("gb.depth1", size, "r32f"))
        normal = pool.texture("gb.normal", size, "rgba16f")
        ids = pool.texture("gb.ids", size, "rg32i")
        z = pool.depth("gb.z", size)
        fbos = tuple(pool.framebuffer((d, normal, ids), z) for d in depth)
        return depth, normal, ids, fbos

    def _setup_geometry(self, camera: Camera, size: tuple[int, int], depth_textures) -> object:
        prog = self.program("blueprint.render:glsl/peel.frag", "blueprint.render:glsl/geometry.vert")
        prog["u_view"].write(camera.view_matrix().T.astype("f4").tobytes())
        prog["u_projection"].write(camera.projection_matrix().T.astype("f4").tobytes())
        prog["u_depth_range"].value = (camera.near, camera.far, 1.0 if camera.ortho else 0.0)
        prog["u_peel_eps"].value = PEEL_EPSILON * (camera.far - camera.near)
        prog["u_ortho"].value = camera.ortho
        prog["u_back_bias"].value = BACK_BIAS
        depth_textures[0].use(0)
        depth_textures[1].use(1)
        return prog

    def _peel(self, mesh: _Mesh, prog, fbos, i: int, query) -> None:
        """Draw layer ``i`` into ``fbos[i % 2]``, counting its samples in ``query``."""
        fbo = fbos[i % 2]
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        prog["u_peel"].value = i > 0
        prog["u_prev_depth"].value = (i - 1) % 2
        with query:
            mesh.vao.render()

    @staticmethod
    def _layer_count(counts: list[int], min_fraction: float) -> int:
        layers = 0
        for i, count in enumerate(counts):
            if count == 0 or (i > 0 and count < min_fraction * counts[0]):
                break
            layers = i + 1
        return layers

    # -- blueprint -----------------------------------------------------------------------------
    def render(
        self,
        model: Model,
        camera: Camera | None = None,
        *,
        size: tuple[int, int] = (1024, 1024),
        view: str = "iso",
        style: str | Style = "blueprint",
        max_layers: int | None = 8,
        min_fraction: float = 0.0,
        crease_angle: float = 30.0,
        line_width: float = 1.0,
        supersample: int = 2,
        depth_threshold: float = 4.0,
        part_edges: bool = True,
        profile: bool = False,
    ) -> Frame:
        """Render a blueprint of ``model``.

        Parameters
        ----------
        model : Model
        camera : Camera, optional
            Defaults to ``Camera.fit`` from ``view`` at the image's aspect.
        size : (int, int)
            Output width and height in pixels.
        max_layers : int or None
            Depth layers to peel at most; ``None`` peels until a pass draws nothing.
        min_fraction : float
            Stop once a layer covers fewer than this fraction of layer 0's pixels.
        crease_angle : float
            Degrees: normals are smoothed across smaller angles, larger ones draw creases.
        line_width : float
            Line width in output pixels.
        supersample : int
            G-buffer and edges are computed at this multiple of the size, then filtered down.
        profile : bool
            Synchronise after each stage to fill ``Frame.stages`` (slower).
        """
        style = get_style(style)
        _check_frame_args(max_layers, min_fraction, crease_angle, line_width)
        params = EDGES.uniforms(depth_threshold=depth_threshold, part_edges=part_edges)
        w, h = check_size(size, supersample, self.max_texture)
        camera = camera or self.camera_for(model, (w, h), view)
        ss = (w * supersample, h * supersample)
        ctx = self.ctx
        stages: dict[str, float] = {}
        t0 = clock = time.perf_counter()

        def stage(name: str) -> None:
            nonlocal clock
            if profile:
                ctx.finish()
                now = time.perf_counter()
                stages[name] = (now - clock) * 1e3
                clock = now

        mesh = self.mesh(model, crease_angle)
        stage("upload")

        ctx.enable_only(ctx.DEPTH_TEST)
        ctx.depth_func = "<"
        depth_tex, normal, ids, fbos = self._gbuffer(ss)
        geo = self._setup_geometry(camera, ss, depth_tex)
        edge_prog, edge_vao = self.fullscreen(EDGES.shader)
        edge_prog["u_depth_range"].value = geo["u_depth_range"].value
        half = math.radians(crease_angle)
        edge_prog["u_normal_cos"].value = (math.cos(0.5 * half), math.cos(0.8 * half))
        edge_prog["u_pixel_angle"].value = camera.pixel_angle(ss[1])
        for name, value in params.items():
            edge_prog[name].value = value
        normal.use(2)
        ids.use(3)
        edge_prog["u_normal"].value = 2
        edge_prog["u_ids"].value = 3
        dilate = None
        if line_width > 1.0:
            dilate, dilate_vao = self.fullscreen(DILATE.shader)
            dilate["u_radius"].value = (line_width - 1.0) * supersample / 2
            dilate["u_source"].value = 4
            scratch = self.pool.texture("edges.scratch", ss, "r8")
            scratch_fbo = self.pool.framebuffer((scratch,))

        limit = max_layers if max_layers is not None else HARD_MAX_LAYERS
        edge_fbos: list = []
        peeled = 0
        while peeled < limit:
            end = min(limit, peeled + (max_layers or CHUNK))
            while len(edge_fbos) < (end + 3) // 4:
                tex = self.pool.texture(f"edges.{len(edge_fbos)}", ss, "rgba8")
                fbo = self.pool.framebuffer((tex,))
                fbo.color_mask = (True, True, True, True)
                fbo.use()
                fbo.clear()
                edge_fbos.append(fbo)
            for layer in range(peeled, end):
                # an empty layer skips the rest on the GPU, without the CPU waiting for it
                guard = self._query(layer - 1).crender if layer else contextlib.nullcontext()
                with guard:
                    ctx.enable(ctx.DEPTH_TEST)
                    self._peel(mesh, geo, fbos, layer, self._query(layer))
                    ctx.disable(ctx.DEPTH_TEST)
                    edge_prog["u_depth"].value = layer % 2
                    target = edge_fbos[layer // 4]
                    mask = tuple(c == layer % 4 for c in range(4))
                    if dilate is not None:
                        scratch_fbo.use()
                        edge_vao.render(vertices=3)
                        scratch.use(4)
                    target.color_mask = mask
                    target.use()
                    (edge_vao if dilate is None else dilate_vao).render(vertices=3)
            peeled = end
            if max_layers is not None or self._query(peeled - 1).samples == 0:
                break
        counts = [self._query(k).samples for k in range(peeled)]
        stage("peel_edges")
        layers = self._layer_count(counts, min_fraction)

        out = self.pool.texture("out.color", (w, h), "rgba8")
        out_fbo = self.pool.framebuffer((out,))
        out_fbo.use()
        self._paper(style, out_fbo)
        self._compose(style, edge_fbos, layers, supersample)
        stage("compose")
        raw = np.frombuffer(out_fbo.read(components=4), np.uint8).reshape(h, w, 4)
        image = _straight_alpha(raw[::-1]) if style.paper is None else raw[::-1].copy()
        stage("read")
        ms = (time.perf_counter() - t0) * 1e3
        draws = len(counts) * (2 if dilate is None else 3) + (layers + 7) // 8 + 1
        return Frame(image, layers, counts, camera, ms, draws, stages)

    def _paper(self, style: Style, fbo) -> None:
        ctx = self.ctx
        ctx.disable(ctx.BLEND)
        if style.paper is None:
            fbo.clear(0.0, 0.0, 0.0, 0.0)
            return
        prog, vao = self.fullscreen("blueprint.compose:glsl/paper.frag")
        prog["u_paper"].value = style.paper
        prog["u_grid_color"].value = style.grid_color
        prog["u_grid"].value = float(style.grid)
        vao.render(vertices=3)

    def _compose(self, style: Style, edge_fbos: list, layers: int, supersample: int) -> None:
        if layers == 0:
            return
        ctx = self.ctx
        prog, vao = self.fullscreen("blueprint.compose:glsl/compose.frag")
        prog["u_supersample"].value = supersample
        prog["u_threshold"].value = style.threshold
        prog["u_edges0"].value = 4
        prog["u_edges1"].value = 5
        inks = style.layer_inks(layers)
        ctx.enable(ctx.BLEND)
        ctx.blend_func = ctx.ONE, ctx.ONE_MINUS_SRC_ALPHA
        for first in range(((layers - 1) // 8) * 8, -1, -8):
            count = min(8, layers - first)
            g = first // 4
            edge_fbos[g].color_attachments[0].use(4)
            if count > 4:
                edge_fbos[g + 1].color_attachments[0].use(5)
            ink = np.zeros((8, 4), np.float32)
            ink[:count] = inks[first : first + count]
            prog["u_ink"].write(ink.tobytes())
            prog["u_layers"].value = count
            vao.render(vertices=3)
        ctx.disable(ctx.BLEND)

    # -- layers for other tools ----------------------------------------------------------------
    def peel(
        self,
        model: Model,
        camera: Camera | None = None,
        *,
        size: tuple[int, int] = (512, 512),
        view: str = "iso",
        max_layers: int | None = None,
        min_fraction: float = 0.0,
        crease_angle: float = 30.0,
    ) -> Layers:
        """Peel depth layers and read each one back (see ``Layers``).

        Peels until a pass draws nothing, ``max_layers`` are done, or a layer covers fewer than
        ``min_fraction`` of layer 0's pixels.
        """
        _check_frame_args(max_layers, min_fraction, crease_angle, 1.0)
        w, h = check_size(size, 1, self.max_texture)
        camera = camera or self.camera_for(model, (w, h), view)
        ctx = self.ctx
        mesh = self.mesh(model, crease_angle)
        ctx.enable_only(ctx.DEPTH_TEST)
        ctx.depth_func = "<"
        depth_tex, normal, ids, fbos = self._gbuffer((w, h))
        geo = self._setup_geometry(camera, (w, h), depth_tex)
        limit = max_layers if max_layers is not None else HARD_MAX_LAYERS
        depth, normals, tri, part, counts = [], [], [], [], []
        for i in range(limit):
            query = self._query(i)
            self._peel(mesh, geo, fbos, i, query)
            counts.append(query.samples)
            if self._layer_count(counts, min_fraction) <= i:
                break
            z = np.frombuffer(depth_tex[i % 2].read(), np.float32).reshape(h, w)
            n = np.frombuffer(normal.read(), np.float16).reshape(h, w, 4)
            ij = np.frombuffer(ids.read(), np.int32).reshape(h, w, 2)
            depth.append(np.where(z > 0, z, 1.0)[::-1])
            normals.append(n[::-1, :, :3].astype(np.float32))
            tri.append(ij[::-1, :, 0] - 1)
            part.append(ij[::-1, :, 1] - 1)
        if not depth:
            empty = np.zeros((0, h, w), np.float32)
            return Layers(
                empty,
                np.zeros((0, h, w, 3), np.float32),
                empty.astype(np.int32),
                empty.astype(np.int32),
                camera.view_matrix(),
                camera.projection_matrix(),
                camera,
            )
        return Layers(
            np.stack(depth),
            np.stack(normals),
            np.stack(tri),
            np.stack(part),
            camera.view_matrix(),
            camera.projection_matrix(),
            camera,
        )


def _check_frame_args(max_layers, min_fraction, crease_angle, line_width) -> None:
    if max_layers is not None and not 1 <= int(max_layers) <= HARD_MAX_LAYERS:
        raise InputError(f"max-layers must be between 1 and {HARD_MAX_LAYERS}, got {max_layers}")
    if not 0.0 <= min_fraction <= 1.0:
        raise InputError(f"min-fraction must be in [0, 1], got {min_fraction}")
    if not 0.0 <= crease_angle <= 180.0:
        raise InputError(f"crease-angle must be in [0, 180] degrees, got {crease_angle}")
    if not 1.0 <= line_width <= 16.0:
        raise InputError(f"line-width must be in [1, 16] pixels, got {line_width}")


def _straight_alpha(premultiplied: np.ndarray) -> np.ndarray:
    rgba = premultiplied.astype(np.float32)
    alpha = rgba[..., 3:4]
    rgb = np.where(alpha > 0, rgba[..., :3] * 255.0 / np.maximum(alpha, 1), 0)
    return np.concatenate([np.clip(rgb + 0.5, 0, 255), alpha], axis=-1).astype(np.uint8)
