"""The renderer: owns the GL context, the target pool and uploaded meshes; peels depth layers,
turns each into an edge map and composes the blueprint."""

from __future__ import annotations

import contextlib
import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np

from blueprint.compose.style import Style, get_style
from blueprint.errors import InputError
from blueprint.gpu import TargetPool, build_compute, build_program, create_context, gl_info
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
# Touching solids have coincident faces of opposite winding (the top of one, the bottom of the
# other). Drawing back faces in a second draw pushed back by this polygon offset (in steps of
# the depth buffer) makes the front face win every pixel of the tie, instead of whichever
# rounds nearer (speckle); it is far below the peeling tolerance, so both still peel as one.
BACK_OFFSET = 16.0
# Edge maps are kept in texture arrays of this many slices (compute path).
SLICES = 8
MASK_UNIT = 7
MASK_FLAGS_UNIT = 8
SHADE_UNIT = 9
SHADE_MAPS_UNIT = 10  # shade.index, then shade.color at the next unit
CORNERS_UNIT = 12
KBUFFER_UNIT = 13
KBUFFER_FRAG = "blueprint.render:glsl/kbuffer.frag"
UNPACK_FRAG = "blueprint.render:glsl/unpack.frag"
# Layers one k-buffer pass finds at most: the targets a fragment shader may write.
KBUFFER_MAX = 8
# The k-buffer saves geometry passes but adds a full-screen pass a layer: on llvmpipe it paid
# from about this many triangles per G-buffer pixel (8 layers at 1024x1024 supersampled:
# featuretype, 0.003, 16 % slower; rocker arm, 0.02, 8 % slower; bunny, 0.066, 21 % faster;
# 2CylinderEngine, 0.12, 27 % faster; 5 layers of the rocker arm at 800x600, 0.04, 16 % faster).
KBUFFER_MIN_DENSITY = 0.03
# The k-buffer's targets hold 16 bytes a pixel a layer (8 for triangle IDs alone); above this
# many bytes the layers are peeled a pass each instead (8 layers at 2048x2048 supersampled
# would take 2 GiB).
KBUFFER_MAX_BYTES = 1 << 29


@dataclass
class Frame:
    """One rendered blueprint.

    ``image`` is (H, W, 4) uint8 RGBA, row 0 at the top, straight alpha. ``layer_pixels`` holds
    for every layer peeled (at the supersampled size) the samples its occlusion query counted:
    its covered pixels where a k-buffer peels, those plus the fragments drawn over again where a
    geometry pass peels it. ``layers`` is how many of them were drawn.
    """

    image: np.ndarray
    layers: int
    layer_pixels: list[int]
    camera: Camera
    ms: float
    draws: int
    stages: dict[str, float] = field(default_factory=dict)
    revealed: float | None = None


@dataclass
class Layers:
    """Depth layers read back from the GPU.

    depth : (L, H, W) float32, window depth in [0, 1], 1.0 where there is no surface
    normal : (L, H, W, 3) float32, eye-space normal facing the viewer, 0 where none; None
        where not asked for
    triangle : (L, H, W) int32, face index in the model, -1 where none
    part : (L, H, W) int32, part index, -1 where none
    view, projection : (4, 4) float64
    """

    depth: np.ndarray
    normal: np.ndarray | None
    triangle: np.ndarray
    part: np.ndarray
    view: np.ndarray
    projection: np.ndarray
    camera: Camera


class _Mesh:
    """A model's triangles on the GPU: shared vertices (split only where crease-split normals
    differ), every face in the index buffer in model order so ``gl_PrimitiveID`` is the face
    index (degenerate faces rasterise to nothing), and a table of each face's part. Without a
    crease angle the normals are left zero, for passes that draw no normals (ID buffers): the
    smoothing is most of the time of an upload."""

    def __init__(self, ctx, model: Model, crease_angle: float | None) -> None:
        self.ctx = ctx
        faces = model.faces
        corner_vertex = faces.reshape(-1).astype(np.int64)
        corner_part = np.repeat(model.face_part, 3).astype(np.int64)
        # a vertex is split where its normal or its part differs, so both can be attributes
        if crease_angle is None:
            normals = None
            key = corner_vertex * max(len(model.part_names), 1) + corner_part
            _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
            vertex, part = corner_vertex[first], corner_part[first]
        else:
            normals = corner_normals(model.positions, faces, crease_angle).reshape(-1, 3)
            quantized = np.round(normals * 32767).astype(np.int64)
            keys = np.column_stack([corner_vertex, corner_part, quantized])
            unique, inverse = np.unique(keys, axis=0, return_inverse=True)
            first = np.zeros(len(unique), np.int64)
            first[inverse.reshape(-1)] = np.arange(len(keys))
            vertex, part = unique[:, 0], unique[:, 1]
        data = np.zeros(len(first), [("p", "f4", 3), ("n", "f4", 3), ("part", "i4")])
        data["p"] = model.positions[vertex]
        if normals is not None:
            data["n"] = normals[first]
        data["part"] = part
        self.vbo = ctx.buffer(data.tobytes())
        self.ibo = ctx.buffer(inverse.reshape(-1).astype(np.uint32).tobytes())
        self._vaos: dict[int, object] = {}
        self._corners = None
        self._model = model
        self.part_count = len(model.part_names)
        self.triangles = len(faces)

    def vao(self, program):
        """The vertex array of these buffers for ``program`` (a vertex array binds one program)."""
        vao = self._vaos.get(program.glo)
        if vao is None:
            # attributes a program does not read (pipeline attribute passes need no part, ID
            # passes no normal) are skipped over
            fields = [("3f", "in_position"), ("3f", "in_normal"), ("1i", "in_part")]
            used = [(f, name) if name in program else (f"{4 * int(f[0])}x", None) for f, name in fields]
            layout = [(self.vbo, " ".join(f for f, _ in used), *(name for _, name in used if name))]
            vao = self._vaos[program.glo] = self.ctx.vertex_array(program, layout, index_buffer=self.ibo)
        return vao

    def bind_corners(self, prog, unit: int) -> None:
        """Give an edge program the corner positions of every face (3 texels per face, rows of
        4096) and the tolerance under which two corners are one vertex, for ID silhouettes."""
        if self._corners is None:
            corners = self._model.positions[self._model.faces].reshape(-1, 3).astype(np.float32)
            rows = max(1, -(-len(corners) // 4096))
            data = np.zeros((rows * 4096, 3), np.float32)
            data[: len(corners)] = corners
            self._corners = self.ctx.texture((4096, rows), 3, data.tobytes(), dtype="f4")
            self._corners.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
            diag = float(np.linalg.norm(np.ptp(self._model.bounds, axis=0))) or 1.0
            self._tolerance = diag * 1e-6
        self._corners.use(unit)
        prog["u_corners"].value = unit
        prog["u_tolerance2"].value = self._tolerance**2

    def release(self) -> None:
        for obj in (*self._vaos.values(), self.vbo, self.ibo, self._corners):
            if obj is not None:
                obj.release()


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


def _current(method):
    """Make the renderer's context current for the call, and leave it so: a process may hold
    several contexts (a window, the API's default renderer, test fixtures), and GL calls go to
    whichever is current."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        self.make_current()
        return method(self, *args, **kwargs)

    return wrapper


class Renderer:
    """Owns one OpenGL context, its targets, programs and uploaded meshes.

    Use as a context manager or call ``release()``. Models, cameras and styles stay GPU-free;
    the renderer uploads a model once per (model, crease angle).
    """

    def __init__(self, ctx=None) -> None:
        self.ctx = ctx if ctx is not None else create_context()
        self.pool = TargetPool(self.ctx)
        self._programs: dict[tuple, object] = {}
        self._meshes: dict[tuple, tuple[Model, _Mesh]] = {}
        self._queries: list = []
        self._fullscreen = {}
        self.info = gl_info(self.ctx)
        self.max_texture = int(self.info["max_texture_size"])
        # Image-space passes run as compute shaders where OpenGL 4.3 allows: on GPUs built for
        # compute (H100) only a few cores rasterise, while compute runs on all of them.
        software = any(name in self.info["renderer"].lower() for name in ("llvmpipe", "softpipe"))
        self.use_compute = self.ctx.version_code >= 430 and not software
        # The back-face tie-break as one draw writing depth, or two culled draws with a polygon
        # offset: one draw measured faster on llvmpipe and on the H100 in 3 of 4 cases
        # (benchmarks/variants.py), and never more than 10 % slower.
        self.back_bias_in_shader = True
        # Peeling several layers a geometry pass (_KBufferPeel) needs the fragments of a pixel
        # to read what the ones before wrote: framebuffer fetch, which Mesa's drivers have
        # (llvmpipe among them), used from KBUFFER_MIN_DENSITY triangles per pixel
        # (benchmarks/variants.py compares both ways).
        ext = self.ctx.extensions
        self.kbuffer = (
            "GL_EXT_shader_framebuffer_fetch" in ext
            and (self.ctx.version_code >= 420 or "GL_ARB_shading_language_packing" in ext)
            and self.ctx.info["GL_MAX_DRAW_BUFFERS"] >= KBUFFER_MAX
        )
        self.kbuffer_density = KBUFFER_MIN_DENSITY

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def make_current(self) -> None:
        """Direct this thread's GL calls to this renderer's context."""
        self.ctx.__enter__()

    def release(self) -> None:
        self.make_current()
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

    def mesh(self, model: Model, crease_angle: float | None) -> _Mesh:
        """``model`` on the GPU, uploaded once per crease angle (None: no normals)."""
        key = (id(model), None if crease_angle is None else float(crease_angle))
        held = self._meshes.get(key)
        if held is None or held[0] is not model:
            held = self._meshes[key] = (model, _Mesh(self.ctx, model, crease_angle))
        return held[1]

    @_current
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
        """Two depth textures (this layer and the previous one) plus normal and ID targets."""
        pool = self.pool
        depth = (pool.depth("gb.depth0", size), pool.depth("gb.depth1", size))
        normal = pool.texture("gb.normal", size, "rgba16f")
        ids = pool.texture("gb.ids", size, "rg32i")
        fbos = tuple(pool.framebuffer((normal, ids), d) for d in depth)
        clears = tuple(pool.framebuffer((), d) for d in depth)
        return depth, normal, ids, fbos, clears

    def _geometry_program(
        self, selected_only: bool = False, face_ids: bool = True, normals: bool = True, tie_break=None
    ):
        # ID passes (no normals) break no ties unless asked: silhouettes compare triangles, not
        # parts, but layers handed out must be the ones the G-buffer gets
        tie_break = normals if tie_break is None else tie_break
        defines = {
            "BACK_BIAS_IN_SHADER": self.back_bias_in_shader and tie_break,
            "SELECTED_ONLY": selected_only,
            "FACE_IDS": face_ids,
            "NORMALS": normals,
        }
        return self.program(PEEL_FRAG, GEOMETRY_VERT, defines)

    def _setup_geometry(
        self,
        camera: Camera,
        mesh: _Mesh,
        depth_textures,
        selected_only: bool = False,
        face_ids: bool = True,
        normals: bool = True,
        batch: int = 1,
        tie_break: bool | None = None,
    ) -> object:
        """The geometry program, set up for ``camera``, for ``_draw``. Without ``face_ids``
        the ID target's face channel is left 0: the blueprint needs only parts, and a software
        rasteriser pays for tracking primitive IDs. With ``batch`` > 1, where the driver
        allows, one geometry pass finds that many layers (``_KBufferPeel``)."""
        batch = -(-batch // -(-batch // KBUFFER_MAX))  # as many to a pass as evenly fit
        w, h = depth_textures[0].size
        kbuffer = (
            self.kbuffer
            and batch > 1
            and mesh.triangles >= self.kbuffer_density * w * h
            and 16 * batch * w * h <= KBUFFER_MAX_BYTES
            and normals
            and not selected_only
            and self.back_bias_in_shader
            and mesh.part_count < 0xFFFF
        )
        if kbuffer:
            prog = self.program(KBUFFER_FRAG, GEOMETRY_VERT, {"K": batch, "FACE_IDS": face_ids})
        else:
            prog = self._geometry_program(selected_only, face_ids, normals, tie_break)
        _peel_uniforms(prog, camera)
        if normals:  # only the normal's orientation needs it
            prog["u_ortho"].value = camera.ortho
        if self.back_bias_in_shader and (normals if tie_break is None else tie_break):
            prog["u_back_bias"].value = BACK_OFFSET / (1 << 24)
        depth_textures[0].use(0)
        depth_textures[1].use(1)
        return _KBufferPeel(self, prog, batch) if kbuffer else prog

    def _id_buffer(self, size: tuple[int, int]):
        """Like ``_gbuffer`` with face IDs alone (r32i, face + 1): what triangle-ID passes need,
        a quarter of the bytes per fragment (use ``_setup_geometry(..., normals=False)``)."""
        pool = self.pool
        depth = (pool.depth("idb.depth0", size), pool.depth("idb.depth1", size))
        ids = pool.texture("idb.ids", size, "r32i")
        fbos = tuple(pool.framebuffer((ids,), d) for d in depth)
        clears = tuple(pool.framebuffer((), d) for d in depth)
        return depth, ids, fbos, clears

    def _clear(self, clears, layer: int) -> None:
        clears[layer % 2].use()
        clears[layer % 2].clear(depth=1.0)

    def _draw(self, mesh: _Mesh, prog, fbos, layer: int, query, tie_break: bool = True) -> None:
        """Draw layer ``layer`` into ``fbos[layer % 2]``, counting its samples in ``query``:
        front faces first, then back faces pushed back by ``BACK_OFFSET`` (one draw where the
        shader does it, or where no tie-break is wanted)."""
        if isinstance(prog, _KBufferPeel):
            prog.draw(mesh, fbos, layer, query)
            return
        ctx = self.ctx
        fbos[layer % 2].use()
        prog["u_peel"].value = layer > 0
        prog["u_prev_depth"].value = (layer - 1) % 2
        if self.back_bias_in_shader or not tie_break:
            ctx.enable(ctx.DEPTH_TEST)
            with query:
                mesh.vao(prog).render()
            ctx.disable(ctx.DEPTH_TEST)
            return
        ctx.enable(ctx.DEPTH_TEST | ctx.CULL_FACE)
        with query:
            ctx.cull_face = "back"
            mesh.vao(prog).render()
            ctx.cull_face = "front"
            ctx.polygon_offset = 0.0, BACK_OFFSET
            mesh.vao(prog).render()
        ctx.polygon_offset = 0.0, 0.0
        ctx.disable(ctx.DEPTH_TEST | ctx.CULL_FACE)

    @staticmethod
    def _layer_count(counts: list[int], min_fraction: float) -> int:
        layers = 0
        for i, count in enumerate(counts):
            if count == 0 or (i > 0 and count < min_fraction * counts[0]):
                break
            layers = i + 1
        return layers

    # -- blueprint -----------------------------------------------------------------------------
    @_current
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
        id_silhouettes: bool = False,
        highlight: np.ndarray | None = None,
        reveal: float | None = None,
        shade: np.ndarray | None = None,
        shade_opacity: float = 1.0,
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
        id_silhouettes : bool
            Also draw triangle-ID silhouettes (neighbouring pixels whose triangles share no
            vertex, paper 002) in every layer's edge map.
        highlight : (P,) bool, optional
            Designated parts (see ``blueprint.scene.parts.select_parts``): their whole outline
            is drawn over everything in the style's highlight ink and width.
        reveal : float, optional
            Depth masking: stop peeling as soon as this fraction of the highlighted parts'
            pixels is uncovered, so the clutter behind them is not drawn. Needs ``highlight``.
        shade : (P,) bool, optional
            Parts drawn shaded (Lambert, headlight) inside the blueprint, in depth order: edges
            in front of them stay on top, the ones behind are hidden (``shade_opacity`` 1) or
            seen through them.
        shade_opacity : float
            Opacity of the shading, in (0, 1].
        profile : bool
            Synchronise after each stage to fill ``Frame.stages`` (slower).
        """
        if highlight is None and reveal is None and shade is None:
            # the plain blueprint is the `blueprint` pipeline preset; designated and shaded
            # parts are not expressed as pipeline passes yet and take the path below
            from blueprint.pipeline.executor import render_blueprint

            return render_blueprint(
                self,
                model,
                camera,
                size=size,
                view=view,
                style=style,
                max_layers=max_layers,
                min_fraction=min_fraction,
                crease_angle=crease_angle,
                line_width=line_width,
                supersample=supersample,
                depth_threshold=depth_threshold,
                part_edges=part_edges,
                id_silhouettes=id_silhouettes,
                profile=profile,
            )
        style = get_style(style)
        _check_frame_args(max_layers, min_fraction, crease_angle, line_width)
        params = EDGES.uniforms(
            depth_threshold=depth_threshold, part_edges=part_edges, id_silhouettes=id_silhouettes
        )
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
        if reveal is not None and highlight is None:
            raise InputError("reveal needs parts to reveal: give highlight as well")
        if reveal is not None and not 0.0 < reveal <= 1.0:
            raise InputError(f"reveal must be in (0, 1], got {reveal}")
        ctx.enable_only(ctx.NOTHING)
        ctx.depth_func = "<"
        depth_tex, normal, ids, fbos, clears = self._gbuffer(ss)
        edges = self._edge_stage(camera, ss, crease_angle, params, line_width, supersample, style)
        if id_silhouettes:
            mesh.bind_corners(edges.prog, CORNERS_UNIT)
        normal.use(3)
        ids.use(4)
        draws = 0
        mask = None
        if highlight is not None:
            mask, wanted, passes = self._highlight(mesh, camera, ss, highlight, edges)
            draws += passes
        if shade is not None:
            if not 0.0 < shade_opacity <= 1.0:
                raise InputError(f"shade-opacity must be in (0, 1], got {shade_opacity}")
            self._shading(mesh, camera, ss, shade, (*style.shade[:3], shade_opacity))
            draws += 3
        geo = self._setup_geometry(
            camera, mesh, depth_tex, face_ids=id_silhouettes, batch=max_layers or KBUFFER_MAX
        )

        limit = max_layers if max_layers is not None else HARD_MAX_LAYERS
        peeled = 0
        revealed = None
        while peeled < limit:
            step = 1 if reveal is not None else (max_layers or CHUNK)
            end = min(limit, peeled + step)
            edges.reserve(end)
            for layer in range(peeled, end):
                self._clear(clears, layer)
                # an empty layer skips its draws on the GPU, without the CPU waiting for it;
                # its cleared depth then gives an empty edge map
                guard = self._query(layer - 1).crender if layer else contextlib.nullcontext()
                with guard:
                    self._draw(mesh, geo, fbos, layer, self._query(layer))
                draws += 3 + edges.run(layer)
                if shade is not None:
                    self._mark_shaded(layer, camera, ss)
                    draws += 1
            peeled = end
            if reveal is not None:
                # the one rule that needs the CPU to look after every layer
                shown = self._count_revealed(mask, layer % 2, camera, ss)
                draws += 1
                revealed = shown / wanted if wanted else 1.0
                if revealed >= reveal or self._query(layer).samples == 0:
                    break
            elif max_layers is not None or self._query(peeled - 1).samples == 0:
                break
        counts = [self._query(k).samples for k in range(peeled)]
        stage("peel_edges")
        layers = self._layer_count(counts, min_fraction)

        draws += edges.finish(layers)
        out = self.pool.texture("out.color", (w, h), "rgba8")
        draws += self._compose(style, edges, layers, supersample, out, shade is not None)
        stage("compose")
        ctx.memory_barrier(ctx.TEXTURE_UPDATE_BARRIER_BIT | ctx.FRAMEBUFFER_BARRIER_BIT)
        raw = np.frombuffer(out.read(), np.uint8).reshape(h, w, 4)
        image = _straight_alpha(raw[::-1]) if style.paper is None else raw[::-1].copy()
        stage("read")
        ms = (time.perf_counter() - t0) * 1e3
        return Frame(image, layers, counts, camera, ms, draws, stages, revealed)

    def _selected_surface(self, mesh: _Mesh, camera: Camera, ss, parts: np.ndarray, name: str, what: str):
        """Draw only the flagged parts into the depth texture ``name`` (their front surface),
        leaving its normals and IDs in the G-buffer's normal and ID targets."""
        parts = np.asarray(parts, bool)
        if parts.shape != (mesh.part_count,):
            raise InputError(f"{what} needs one flag per part ({mesh.part_count}), got {parts.shape}")
        flags = self.ctx.texture((len(parts), 1), 1, parts.astype(np.int32).tobytes(), dtype="i4")
        flags.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        depth = self.pool.depth(name, ss)
        normal = self.pool.texture("gb.normal", ss, "rgba16f")
        ids = self.pool.texture("gb.ids", ss, "rg32i")
        fbo = self.pool.framebuffer((normal, ids), depth)
        fbo.use()
        fbo.clear(depth=1.0)
        prog = self._setup_geometry(camera, mesh, (depth, depth), selected_only=True)
        flags.use(MASK_FLAGS_UNIT)
        prog["u_selected"].value = MASK_FLAGS_UNIT
        self._draw(mesh, prog, (fbo, fbo), 0, self._query(HARD_MAX_LAYERS))
        flags.release()
        return depth

    def _highlight(self, mesh: _Mesh, camera: Camera, ss, highlight: np.ndarray, edges):
        """Draw only the designated parts into a depth mask and turn it into the highlight edge
        map. Returns the mask texture, the number of its covered pixels and the passes run."""
        mask = self._selected_surface(mesh, camera, ss, highlight, "gb.mask", "highlight")
        mask.use(MASK_UNIT)
        passes = 2 + edges.run_highlight(MASK_UNIT)
        wanted = self._count_revealed(mask, None, camera, ss)
        return mask, wanted, passes + 1

    def _shading(self, mesh: _Mesh, camera: Camera, ss, shade: np.ndarray, color) -> None:
        """Shade the flagged parts' front surface into ``shade.color`` and clear the map of the
        layer that surface belongs to, ``shade.index``, which ``_mark_shaded`` fills."""
        surface = self._selected_surface(mesh, camera, ss, shade, "gb.shade", "shade")
        surface.use(SHADE_UNIT)
        prog, vao = self.fullscreen("blueprint.compose:glsl/shade.frag")
        prog["u_depth"].value = SHADE_UNIT
        prog["u_normal"].value = 3
        prog["u_color"].value = tuple(color)
        target = self.pool.framebuffer((self.pool.texture("shade.color", ss, "rgba8"),))
        target.use()
        vao.render(vertices=3)
        index = self.pool.framebuffer((self.pool.texture("shade.index", ss, "r8"),))
        index.use()
        index.clear()

    def _mark_shaded(self, layer: int, camera: Camera, ss) -> None:
        prog, vao = self.fullscreen("blueprint.render:glsl/shade_index.frag")
        prog["u_depth_range"].value = (camera.near, camera.far, 1.0 if camera.ortho else 0.0)
        prog["u_peel_eps"].value = PEEL_EPSILON * (camera.far - camera.near)
        prog["u_shade_depth"].value = SHADE_UNIT
        prog["u_layer_depth"].value = layer % 2
        prog["u_layer"].value = layer
        self.pool.framebuffer((self.pool.texture("shade.index", ss, "r8"),)).use()
        vao.render(vertices=3)

    def _count_revealed(self, mask, layer_unit: int | None, camera: Camera, ss) -> int:
        """Pixels of the mask whose surface is in layers peeled so far (all mask pixels when
        ``layer_unit`` is None), counted by an occlusion query and read back."""
        prog, vao = self.fullscreen("blueprint.render:glsl/reveal.frag")
        prog["u_depth_range"].value = (camera.near, camera.far, 1.0 if camera.ortho else 0.0)
        prog["u_peel_eps"].value = PEEL_EPSILON * (camera.far - camera.near)
        prog["u_mask_depth"].value = MASK_UNIT
        prog["u_layer_depth"].value = layer_unit if layer_unit is not None else MASK_UNIT
        prog["u_count_all"].value = layer_unit is None
        scratch = self.pool.texture("reveal.scratch", ss, "r8")
        fbo = self.pool.framebuffer((scratch,))
        fbo.use()
        query = self._query(HARD_MAX_LAYERS + 1)
        with query:
            vao.render(vertices=3)
        return query.samples

    def _edge_stage(self, camera, ss, crease_angle, params, line_width, supersample, style):
        defines = EDGES.defines(params)
        vao = None
        if self.use_compute:
            prog = self.compute(EDGES.compute, defines)
        else:
            prog, vao = self.fullscreen(EDGES.shader, defines)
        prog["u_depth_range"].value = (camera.near, camera.far, 1.0 if camera.ortho else 0.0)
        half = math.radians(crease_angle)
        prog["u_normal_cos"].value = (math.cos(0.5 * half), math.cos(0.8 * half))
        prog["u_pixel_angle"].value = camera.pixel_angle(ss[1])
        switched = {f"u_{name}" for name in EDGES.switches}  # defines, not uniforms
        for name, value in params.items():
            if name not in switched:
                prog[name].value = value
        prog["u_normal"].value = 3
        prog["u_ids"].value = 4
        radius = (line_width - 1.0) * supersample / 2
        highlight_radius = (line_width * style.highlight_width - 1.0) * supersample / 2
        if self.use_compute:
            return _ComputeEdges(self, prog, ss, radius, highlight_radius)
        return _FragmentEdges(self, prog, vao, ss, radius, highlight_radius)

    def _compose(self, style: Style, edges, layers: int, supersample: int, out, shaded: bool) -> int:
        """Paper, then the edge layers back to front onto ``out``; returns the passes run."""
        inks = style.layer_inks(max(layers, 1))
        groups = list(range(((max(layers, 1) - 1) // 8) * 8, -1, -8))

        def shading(prog, first: int) -> None:
            prog["u_shaded"].value = shaded
            if shaded:
                prog["u_first_layer"].value = first
                prog["u_shade_index"].value = SHADE_MAPS_UNIT
                prog["u_shade_color"].value = SHADE_MAPS_UNIT + 1
                self.pool.texture("shade.index", edges.ss, "r8").use(SHADE_MAPS_UNIT)
                self.pool.texture("shade.color", edges.ss, "rgba8").use(SHADE_MAPS_UNIT + 1)

        if self.use_compute:
            prog = self.compute("blueprint.compose:glsl/compose.comp")
            _set_paper(prog, style)
            prog["u_supersample"].value = supersample
            prog["u_threshold"].value = style.threshold
            prog["u_has_paper"].value = style.paper is not None
            prog["u_edges"].value = 5
            out.bind_to_image(0, read=True, write=True)
            for first in groups:
                count = min(8, layers - first) if layers else 0
                edges.array(first).use(5)
                prog["u_first"].value = first == groups[0]
                prog["u_layers"].value = count
                shading(prog, first)
                prog["u_ink"].write(_inks(inks, first, count))
                prog.run(*_groups(out.size))
                self.ctx.memory_barrier(self.ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)
            if edges.highlight is not None:
                edges.highlight.use(5)
                prog["u_shaded"].value = False
                prog["u_first"].value = False
                prog["u_layers"].value = 1
                prog["u_ink"].write(_inks(np.array([style.highlight]), 0, 1))
                prog.run(*_groups(out.size))
                self.ctx.memory_barrier(self.ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)
            return len(groups) + (edges.highlight is not None)
        ctx = self.ctx
        fbo = self.pool.framebuffer((out,))
        fbo.use()
        ctx.disable(ctx.BLEND)
        if style.paper is None:
            fbo.clear(0.0, 0.0, 0.0, 0.0)
        else:
            prog, vao = self.fullscreen("blueprint.compose:glsl/paper.frag")
            _set_paper(prog, style)
            vao.render(vertices=3)
        prog, vao = self.fullscreen("blueprint.compose:glsl/compose.frag", {"SUPERSAMPLE": supersample})
        prog["u_threshold"].value = style.threshold
        prog["u_edges0"].value = 5
        prog["u_edges1"].value = 6
        ctx.enable(ctx.BLEND)
        ctx.blend_func = ctx.ONE, ctx.ONE_MINUS_SRC_ALPHA
        sprites = [(edges.texture(f), edges.texture(f + 4), min(8, layers - f), inks[f:], f) for f in groups]
        if layers == 0:
            sprites = []
        if edges.highlight is not None:
            sprites.append((edges.highlight, edges.highlight, 1, np.array([style.highlight]), None))
        for first, second, count, ink, first_layer in sprites:
            first.use(5)
            if count > 4:
                second.use(6)
            if first_layer is None:
                prog["u_shaded"].value = False
            else:
                shading(prog, first_layer)
            prog["u_ink"].write(_inks(ink, 0, count))
            prog["u_layers"].value = count
            vao.render(vertices=3)
        ctx.disable(ctx.BLEND)
        return 1 + len(sprites)

    # -- layers for other tools ----------------------------------------------------------------
    @_current
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
        normals: bool = True,
    ) -> Layers:
        """Peel depth layers and read each one back (see ``Layers``).

        Peels until a pass draws nothing, ``max_layers`` are done, or a layer covers fewer than
        ``min_fraction`` of layer 0's pixels. Without ``normals`` the layers are the same but
        ``Layers.normal`` is None: no normals are smoothed, drawn or read (vector drawings need
        only depths and triangles).
        """
        w, h = check_size(size, 1, self.max_texture)
        camera = camera or self.camera_for(model, (w, h), view)
        depth, normal_maps, tri = [], [], []
        for depth_tex, normal, ids in self._peeled(
            model, camera, (w, h), max_layers, min_fraction, crease_angle, normals
        ):
            z = np.frombuffer(depth_tex.read(), np.float32).reshape(h, w)[::-1]
            covered = z < 1.0
            depth.append(np.where(covered, z, 1.0).astype(np.float32))
            if normals:
                n = np.frombuffer(normal.read(), np.float16).reshape(h, w, 4)[::-1, :, :3]
                normal_maps.append(np.where(covered[..., None], n.astype(np.float32), 0.0))
                face = np.frombuffer(ids.read(), np.int32).reshape(h, w, 2)[::-1, :, 0]
            else:
                face = np.frombuffer(ids.read(), np.int32).reshape(h, w)[::-1]
            tri.append(np.where(covered, face - 1, -1).astype(np.int32))
        if depth:
            depths, triangles = np.stack(depth), np.stack(tri)
        else:
            depths, triangles = np.zeros((0, h, w), np.float32), np.zeros((0, h, w), np.int32)
        parts = np.where(triangles >= 0, model.face_part[np.maximum(triangles, 0)], -1).astype(np.int32)
        if normals:
            normal_stack = np.stack(normal_maps) if normal_maps else np.zeros((0, h, w, 3), np.float32)
        else:
            normal_stack = None
        return Layers(
            depths, normal_stack, triangles, parts, camera.view_matrix(), camera.projection_matrix(), camera
        )

    @_current
    def triangles_at(
        self,
        model: Model,
        camera: Camera,
        pixels: np.ndarray,
        *,
        size: tuple[int, int],
        max_layers: int | None = None,
        min_fraction: float = 0.0,
    ) -> np.ndarray:
        """(L, N) int32: the face of every peeled layer at ``pixels`` (N flat indices
        ``y * width + x``, row 0 at the top), -1 where none. The layers are ``peel``'s without
        normals; only the pixels asked for leave the GPU's copy, so a vector drawing does not
        pay for whole images."""
        w, h = check_size(size, 1, self.max_texture)
        pixels = np.asarray(pixels, np.int64)
        if len(pixels) and (pixels.min() < 0 or pixels.max() >= w * h):
            raise InputError(f"pixels must be flat indices into {w}x{h}")
        # the same pixels in OpenGL's rows, bottom up
        gl = (h - 1 - pixels // w) * w + pixels % w
        if (
            self.kbuffer
            and max_layers is not None
            and 1 < max_layers <= KBUFFER_MAX
            and 8 * max_layers * w * h <= KBUFFER_MAX_BYTES
        ):
            return self._kbuffer_faces(model, camera, (w, h), max_layers, min_fraction, gl)
        out = []
        for depth_tex, _, ids in self._peeled(model, camera, (w, h), max_layers, min_fraction, 30.0, False):
            z = np.frombuffer(depth_tex.read(), np.float32)[gl]
            face = np.frombuffer(ids.read(), np.int32)[gl]
            out.append(np.where(z < 1.0, face - 1, -1).astype(np.int32))
        return np.stack(out) if out else np.zeros((0, len(pixels)), np.int32)

    def _kbuffer_faces(self, model, camera, size, k, min_fraction, gl) -> np.ndarray:
        """``triangles_at`` in one k-buffer pass of depths and faces alone: no layer is
        unpacked, the k targets are read as they are (a pixel's surfaces run up to the first
        empty one, kbuffer.frag) and gathered at the OpenGL pixel indices ``gl``."""
        _check_frame_args(k, min_fraction, 0.0, 1.0)
        ctx, pool = self.ctx, self.pool
        mesh = self.mesh(model, None)
        prog = self.program(KBUFFER_FRAG, GEOMETRY_VERT, {"K": k, "FACE_IDS": True, "IDS_ONLY": True})
        _peel_uniforms(prog, camera)
        prog["u_back_bias"].value = BACK_OFFSET / (1 << 24)
        prog["u_peel"].value = False
        name = f"kbuffer.faces.{size[0]}x{size[1]}"
        surfaces = [pool.texture(f"{name}.{i}", size, "rg32ui") for i in range(k)]
        pool.framebuffer((surfaces[0],)).clear()
        pool.framebuffer(tuple(surfaces)).use()
        ctx.enable_only(ctx.NOTHING)
        mesh.vao(prog).render()
        valid = np.ones(size[0] * size[1], bool)
        out, counts = [], []
        for tex in surfaces:
            face = np.frombuffer(tex.read(), np.uint32)[1::2]
            valid &= face != 0
            counts.append(int(np.count_nonzero(valid)))
            if self._layer_count(counts, min_fraction) < len(counts):
                break
            out.append(np.where(valid[gl], face[gl].astype(np.int64) - 1, -1).astype(np.int32))
        return np.stack(out) if out else np.zeros((0, len(gl)), np.int32)

    def _peeled(self, model, camera, size, max_layers, min_fraction, crease_angle, normals):
        """Peel layer after layer; after each one that counts, yield its depth texture, normal
        texture (None without ``normals``) and ID texture (face + 1; with normals, part + 1 too)."""
        _check_frame_args(max_layers, min_fraction, crease_angle, 1.0)
        ctx = self.ctx
        ctx.enable_only(ctx.NOTHING)
        ctx.depth_func = "<"
        if normals:
            mesh = self.mesh(model, crease_angle)
            depth_tex, normal, ids, fbos, clears = self._gbuffer(size)
            geo = self._setup_geometry(camera, mesh, depth_tex, batch=max_layers or KBUFFER_MAX)
        else:
            mesh = self.mesh(model, None)
            normal = None
            depth_tex, ids, fbos, clears = self._id_buffer(size)
            geo = self._setup_geometry(camera, mesh, depth_tex, normals=False, tie_break=True)
        limit = max_layers if max_layers is not None else HARD_MAX_LAYERS
        counts = []
        for i in range(limit):
            query = self._query(i)
            self._clear(clears, i)
            self._draw(mesh, geo, fbos, i, query)
            counts.append(query.samples)
            if self._layer_count(counts, min_fraction) <= i:
                break
            yield depth_tex[i % 2], normal, ids


class _KBufferPeel:
    """Depth peeling ``k`` layers a geometry pass. At every k-th layer one geometry pass
    (kbuffer.frag) sorts the k nearest surfaces behind the previous layer into k integer
    targets; each layer is then unpacked into the G-buffer by a full-screen pass, so whatever
    reads layers sees what the one-pass-a-layer peel draws. The layer's occlusion query counts
    its covered pixels."""

    def __init__(self, renderer: Renderer, prog, k: int) -> None:
        self.r, self.prog, self.k = renderer, prog, k
        self.unpack, self.unpack_vao = renderer.fullscreen(UNPACK_FRAG)
        self.unpack["u_surfaces"].value = KBUFFER_UNIT
        self.unpack["u_back_bias"].value = BACK_OFFSET / (1 << 24)
        self._targets: dict[tuple[int, int], tuple] = {}

    def _surfaces(self, size: tuple[int, int]) -> tuple:
        """(targets, their framebuffer, the first one's) at ``size``: pipelines peel G-buffers
        of several sizes in turn, so the targets are named by size too."""
        held = self._targets.get(size)
        if held is None:
            pool, name = self.r.pool, f"kbuffer.{size[0]}x{size[1]}"
            surfaces = tuple(pool.texture(f"{name}.{i}", size, "rgba32ui") for i in range(self.k))
            held = self._targets[size] = (
                surfaces,
                pool.framebuffer(surfaces),
                pool.framebuffer(surfaces[:1]),
            )
        return held

    def draw(self, mesh: _Mesh, fbos, layer: int, query) -> None:
        ctx = self.r.ctx
        surfaces, target, first_target = self._surfaces(tuple(fbos[0].size))
        first = layer % self.k == 0
        if first:
            # the first target alone is cleared: kbuffer.frag keeps the rest valid
            first_target.clear()
            target.use()
            self.prog["u_peel"].value = layer > 0
            self.prog["u_prev_depth"].value = (layer - 1) % 2
            mesh.vao(self.prog).render()
        fbos[layer % 2].use()
        surfaces[layer % self.k].use(KBUFFER_UNIT)
        self.unpack["u_first"].value = first
        self.unpack["u_prev_depth"].value = (layer - 1) % 2
        ctx.enable(ctx.DEPTH_TEST)
        with query:
            self.unpack_vao.render(vertices=3)
        ctx.disable(ctx.DEPTH_TEST)


class _ComputeEdges:
    """Edge maps as slices of r8 texture arrays, written by compute shaders (GL 4.3)."""

    def __init__(self, renderer: Renderer, prog, ss, radius: float, highlight_radius: float) -> None:
        self.r, self.prog, self.ss = renderer, prog, ss
        self.radius, self.highlight_radius = radius, highlight_radius
        self.arrays: list = []
        self.dilated: list = []
        self.highlight = None

    def reserve(self, layers: int) -> None:
        while len(self.arrays) * SLICES < layers:
            k = len(self.arrays)
            self.arrays.append(self.r.pool.texture(f"edges.{k}", self.ss, "r8", SLICES))

    def _edge(self, depth_unit: int, array, index: int) -> int:
        array.bind_to_image(1, read=False, write=True)
        self.prog["u_depth"].value = depth_unit
        self.prog["u_layer"].value = index
        self.prog.run(*_groups(self.ss))
        return 1

    def run(self, layer: int) -> int:
        return self._edge(layer % 2, self.arrays[layer // SLICES], layer % SLICES)

    def run_highlight(self, depth_unit: int) -> int:
        self.highlight = self.r.pool.texture("edges.highlight", self.ss, "r8", 1)
        return self._edge(depth_unit, self.highlight, 0)

    def _dilate(self, source, name: str, radius: float, slices: int):
        prog = self.r.compute(DILATE.compute)
        prog["u_radius"].value = radius
        prog["u_source"].value = 5
        target = self.r.pool.texture(name, self.ss, "r8", slices)
        source.use(5)
        target.bind_to_image(1, read=False, write=True)
        prog.run(*_groups(self.ss), slices)
        return target

    def finish(self, layers: int) -> int:
        ctx = self.r.ctx
        ctx.memory_barrier(ctx.TEXTURE_FETCH_BARRIER_BIT | ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)
        passes = 0
        if self.radius > 0 and layers:
            used = self.arrays[: (layers + SLICES - 1) // SLICES]
            self.dilated = [
                self._dilate(a, f"edges.dilated.{k}", self.radius, SLICES) for k, a in enumerate(used)
            ]
            passes += len(used)
        if self.highlight is not None and self.highlight_radius > 0:
            self.highlight = self._dilate(self.highlight, "edges.highlight.wide", self.highlight_radius, 1)
            passes += 1
        ctx.memory_barrier(ctx.TEXTURE_FETCH_BARRIER_BIT)
        return passes

    def array(self, first_layer: int):
        source = self.dilated or self.arrays
        return source[first_layer // SLICES]


class _FragmentEdges:
    """Edge maps packed four layers to an RGBA8 texture, one channel per layer (GL 3.3)."""

    def __init__(self, renderer: Renderer, prog, vao, ss, radius: float, highlight_radius: float) -> None:
        self.r, self.prog, self.vao, self.ss = renderer, prog, vao, ss
        self.radius, self.highlight_radius = radius, highlight_radius
        self.fbos: list = []
        self.highlight = None
        if max(radius, highlight_radius) > 0:
            self.dilate, self.dilate_vao = renderer.fullscreen(DILATE.shader)
            self.dilate["u_source"].value = 6
            self.scratch = renderer.pool.texture("edges.scratch", ss, "r8")
            self.scratch_fbo = renderer.pool.framebuffer((self.scratch,))

    def _target(self, name: str):
        tex = self.r.pool.texture(name, self.ss, "rgba8")
        fbo = self.r.pool.framebuffer((tex,))
        fbo.color_mask = (True, True, True, True)
        fbo.use()
        fbo.clear()
        return fbo

    def reserve(self, layers: int) -> None:
        while len(self.fbos) * 4 < layers:
            self.fbos.append(self._target(f"edges.rgba.{len(self.fbos)}"))

    def _edge(self, depth_unit: int, target, channel: int, radius: float) -> int:
        self.prog["u_depth"].value = depth_unit
        if radius > 0:
            self.scratch_fbo.use()
            self.vao.render(vertices=3)
            self.scratch.use(6)
            self.dilate["u_radius"].value = radius
        target.color_mask = tuple(c == channel for c in range(4))
        target.use()
        (self.vao if radius <= 0 else self.dilate_vao).render(vertices=3)
        return 1 if radius <= 0 else 2

    def run(self, layer: int) -> int:
        return self._edge(layer % 2, self.fbos[layer // 4], layer % 4, self.radius)

    def run_highlight(self, depth_unit: int) -> int:
        fbo = self._target("edges.rgba.highlight")
        self.highlight = fbo.color_attachments[0]
        return self._edge(depth_unit, fbo, 0, self.highlight_radius)

    def finish(self, layers: int) -> int:
        return 0

    def texture(self, first_layer: int):
        return self.fbos[min(first_layer // 4, len(self.fbos) - 1)].color_attachments[0]


def _peel_uniforms(prog, camera: Camera) -> None:
    """What every geometry pass of the peel takes from the camera."""
    prog["u_view"].write(camera.view_matrix().T.astype("f4").tobytes())
    prog["u_projection"].write(camera.projection_matrix().T.astype("f4").tobytes())
    prog["u_depth_range"].value = (camera.near, camera.far, 1.0 if camera.ortho else 0.0)
    prog["u_peel_eps"].value = PEEL_EPSILON * (camera.far - camera.near)


def _groups(size) -> tuple[int, int]:
    return (size[0] + 7) // 8, (size[1] + 7) // 8


def _inks(inks: np.ndarray, first: int, count: int) -> bytes:
    block = np.zeros((8, 4), np.float32)
    block[:count] = inks[first : first + count]
    return block.tobytes()


def _set_paper(prog, style: Style) -> None:
    prog["u_paper"].value = style.paper or (0.0, 0.0, 0.0, 0.0)
    prog["u_grid_color"].value = style.grid_color
    prog["u_grid"].value = float(style.grid)


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
