"""Triangle-ID silhouettes on the GPU (paper 002): silhouettes straight from a triangle-ID buffer.

Each depth layer is drawn by the renderer's G-buffer pass, whose ID target holds the face index
of every pixel. A second pass looks at each pixel and its four neighbours: where a neighbour
shows a triangle that shares no vertex with the pixel's triangle, or coverage changes, the pixel
is on a silhouette. Adjacency is decided in one of two ways:

``"vertex"`` (vertex storage, the paper's choice)
    The three corner positions of every face, 3 RGB32F entries per face in rows of 4096, are
    compared with a small tolerance. No preprocessing: soups, inconsistent winding, non-manifold
    edges and deforming meshes that change topology all work, and a deforming mesh uploads its
    new positions and nothing else (:class:`SoupMesh`). On the compute path the pass reads the
    very buffer the ID pass draws from (a storage buffer); on the fragment path that buffer is
    copied into a texture on the GPU.
``"idlist"`` (ID-list storage, for static meshes)
    Vertex-to-triangle lists precomputed on the CPU (welding included), packed into a list
    texture and a pointer table (:mod:`blueprint.silhouette.idlist`); the pass binary-searches
    the lists of the pixel's three vertices. Same result as ``"vertex"``, at the price of the
    preprocessing whenever the topology changes.

Edge images are float32 (L, H, W) in {0, 1}, one per layer, row 0 at the top; lines are two
pixels wide, centred on the boundary (both pixels of a pair mark). Layer 0 holds the visible
silhouettes; deeper layers the hidden ones (where a surface in front ends, its outline shows in
the layers behind as well, under the visible line). :func:`composite` turns them into a picture.
"""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from blueprint.errors import InputError
from blueprint.gpu import units
from blueprint.gpu.device import check_size
from blueprint.ops import Op, Param
from blueprint.render.capture import Capture, gbuffer, peel
from blueprint.render.renderer import LayerRenderer
from blueprint.render.stop import MaxLayers
from blueprint.scene.camera import Camera, fit_camera
from blueprint.scene.model import Model

from . import BORDER, SILHOUETTE, build_adjacency, classify_edges, draw_segments
from .deform import Animation
from .idlist import IdLists, build_id_lists, id_lists_from_topology

__all__ = [
    "IDSIL_LIST",
    "IDSIL_VERTEX",
    "METHODS",
    "GpuSilhouettes",
    "SoupMesh",
    "animate_silhouettes",
    "composite",
    "render_silhouettes",
]

IDSIL_VERTEX = Op(
    name="idsil_vertex",
    shader="blueprint.ops:glsl/idsil_vertex.frag",
    inputs={"depth": "depth", "ids": "rg32i", "corners": "rgb32f"},
    output="r8",
    params=(
        Param(
            "tolerance2", 0.0, 0.0, None, "squared model-space distance under which corners are one vertex"
        ),
    ),
    doc="triangle-ID silhouettes, adjacency from per-face corner positions (no preprocessing)",
    compute="blueprint.ops:glsl/idsil_vertex.comp",
)
IDSIL_LIST = Op(
    name="idsil_list",
    shader="blueprint.ops:glsl/idsil_list.frag",
    inputs={
        "depth": "depth",
        "ids": "rg32i",
        "face_vertices": "rgb32i",
        "pointers": "rg32i",
        "lists": "r32i",
    },
    output="r8",
    doc="triangle-ID silhouettes, adjacency from precomputed vertex-to-triangle lists",
    compute="blueprint.ops:glsl/idsil_list.comp",
)
METHODS = {"vertex": IDSIL_VERTEX, "idlist": IDSIL_LIST}
# Entries per row of the per-face and per-vertex tables (moderngl has no buffer textures).
TABLE_WIDTH = 4096
MAX_LAYERS = 64
# The renderer's crease angle, so the ID pass shares the renderer's upload of a model.
_CREASE = 30.0
# Texture units of the pass (the G-buffer pass holds 0-2; the renderer's edges use 3-4).
_IDS_UNIT, _TABLE_UNIT = units.SILHOUETTE_IDS, units.SILHOUETTE_IDS + 1


def _on_gl(method):
    """Run the method with the renderer's context current (see :meth:`GpuSilhouettes.current`)."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        with self.current():
            return method(self, *args, **kwargs)

    return wrapper


def _rows(entries: int) -> int:
    return max(1, -(-entries // TABLE_WIDTH))


def _check_rows(ctx, entries: int, what: str) -> None:
    limit = int(ctx.info["GL_MAX_TEXTURE_SIZE"])
    if _rows(entries) > limit:
        raise InputError(
            f"{what}: {entries} entries need {_rows(entries)} rows of {TABLE_WIDTH}, this GPU allows {limit}"
        )


def _table(ctx, values: np.ndarray, dtype: str):
    """(N, C) values as a (4096, rows) texture of C components, entry i at (i % 4096, i / 4096)."""
    values = values.reshape(len(values), -1)
    _check_rows(ctx, len(values), "too many triangles for the adjacency tables")
    padded = np.zeros((_rows(len(values)) * TABLE_WIDTH, values.shape[1]), values.dtype)
    padded[: len(values)] = values
    tex = ctx.texture((TABLE_WIDTH, _rows(len(values))), values.shape[1], padded.tobytes(), dtype=dtype)
    tex.filter = (ctx.NEAREST, ctx.NEAREST)
    return tex


class _Corners:
    """Corner positions of F faces in one GPU buffer: corner k of face f at entry 3f + k, three
    float32 each, padded to whole rows of 4096 entries so the buffer is also a texture image."""

    def __init__(self, ctx, faces: int) -> None:
        _check_rows(ctx, 3 * faces, "too many triangles for the vertex table")
        self.ctx, self.faces = ctx, faces
        self.rows = _rows(3 * faces)
        self.buffer = ctx.buffer(reserve=self.rows * TABLE_WIDTH * 12)
        self.texture = None
        self._stale = True

    def write(self, corners: np.ndarray) -> None:
        data = np.ascontiguousarray(corners, dtype=np.float32)
        if data.size != 9 * self.faces:
            raise InputError(f"expected corners of {self.faces} triangles, (F, 3, 3), got shape {data.shape}")
        self.buffer.write(data)
        self._stale = True

    def as_texture(self):
        """The buffer as an RGB32F texture (fragment path), copied on the GPU when it changed."""
        if self.texture is None:
            self.texture = self.ctx.texture((TABLE_WIDTH, self.rows), 3, dtype="f4")
            self.texture.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        if self._stale:
            self.texture.write(self.buffer)
            self._stale = False
        return self.texture

    def release(self) -> None:
        self.buffer.release()
        if self.texture is not None:
            self.texture.release()


class _ListTextures:
    """The ID lists of a topology as three integer textures."""

    def __init__(self, ctx, lists: IdLists) -> None:
        self.lists = lists
        self.textures = (
            _table(ctx, lists.face_vertices, "i4"),
            _table(ctx, lists.pointers, "i4"),
            _table(ctx, lists.lists if len(lists.lists) else np.zeros(1, np.int32), "i4"),
        )

    def release(self) -> None:
        for tex in self.textures:
            tex.release()


def _diagonal(points: np.ndarray) -> float:
    if len(points) == 0:
        return 1.0
    return float(np.linalg.norm(np.ptp(points.reshape(-1, 3).astype(np.float64), axis=0))) or 1.0


class SoupMesh:
    """A deforming triangle mesh on the GPU, drawn as a soup: F triangles whose corner
    positions are replaced every frame.

    Create it with :meth:`GpuSilhouettes.soup`. :meth:`update` uploads new positions, one
    buffer write and nothing else: the same buffer is the vertex buffer of the ID pass and the
    vertex storage of the silhouette pass. The number of triangles is fixed; the topology may
    change freely (the ``"vertex"`` method never looks at it). For the ``"idlist"`` method pass
    the connectivity as `topology` whenever it changes; without one, the lists are built once by
    welding the first positions.

    Attributes
    ----------
    bounds : np.ndarray
        (2, 3) float64 box of the positions given at creation (used to fit a camera).
    tolerance : float
        Model-space distance under which two corners are one vertex, fixed at creation.
    """

    def current(self):
        return self.owner.current()

    def __init__(self, owner: GpuSilhouettes, corners, face_part=None, topology=None) -> None:
        self.owner = owner
        with self.current():
            self._create(owner, corners, face_part, topology)

    def _create(self, owner: GpuSilhouettes, corners, face_part, topology) -> None:
        corners = np.asarray(corners, dtype=np.float32)
        if corners.ndim != 3 or corners.shape[1:] != (3, 3) or len(corners) == 0:
            raise InputError(f"corners must have shape (F, 3, 3) with F > 0, got {corners.shape}")
        if not np.isfinite(corners).all():
            raise InputError("corner positions must be finite")
        ctx = owner.renderer.ctx
        self.faces = len(corners)
        self.corners = _Corners(ctx, self.faces)
        self.corners.write(corners)
        points = corners.reshape(-1, 3).astype(np.float64)
        self.bounds = np.array([points.min(axis=0), points.max(axis=0)])
        self.tolerance = owner.tolerance * _diagonal(points)
        # what the renderer's geometry pass needs of a mesh: vertex arrays, the part per vertex
        self._vaos: dict[int, object] = {}
        parts = np.zeros(self.faces, np.int32) if face_part is None else np.asarray(face_part, np.int32)
        self._corner_parts = ctx.buffer(np.repeat(parts, 3).astype(np.int32))
        self._first = corners
        self._topology = None if topology is None else tuple(topology)
        self._lists: _ListTextures | None = None

    @property
    def triangle_count(self) -> int:
        return self.faces

    def vao(self, program):
        """The soup drawn with `program` (the renderer's geometry pass): corner 3f + k is vertex
        3f + k, so ``gl_PrimitiveID`` is the face index. No normals: the pass's normal target
        is not read by the silhouette pass."""
        vao = self._vaos.get(program.glo)
        if vao is None:
            layout = [(self.corners.buffer, "3f", "in_position")]
            if "in_part" in program:
                layout.append((self._corner_parts, "1i", "in_part"))
            vao = self._vaos[program.glo] = self.owner.renderer.ctx.vertex_array(program, layout)
            vao.vertices = 3 * self.faces
        return vao

    @_on_gl
    def update(self, corners, topology=None) -> None:
        """Replace the corner positions, (F, 3, 3) float; `topology`, ``(faces, vertices)``
        of the new connectivity, only where it changed and only for the ``"idlist"`` method."""
        self.corners.write(corners)
        if topology is not None:
            self._topology = tuple(topology)
            if self._lists is not None:
                self._lists.release()
                self._lists = None

    @_on_gl
    def id_lists(self) -> _ListTextures:
        if self._lists is None:
            if self._topology is not None:
                faces, vertices = self._topology
                lists = id_lists_from_topology(faces, vertices)
            else:
                flat = self._first.reshape(-1, 3)
                lists = build_id_lists(flat, np.arange(len(flat)).reshape(-1, 3), self.tolerance)
            if len(lists.face_vertices) != self.faces:
                raise InputError(f"topology has {len(lists.face_vertices)} faces, the mesh {self.faces}")
            self._lists = _ListTextures(self.owner.renderer.ctx, lists)
        return self._lists

    @_on_gl
    def release(self) -> None:
        for obj in (*self._vaos.values(), self._corner_parts):
            obj.release()
        self._vaos.clear()
        self.corners.release()
        if self._lists is not None:
            self._lists.release()


@dataclass
class _Static:
    """What a static model holds on the GPU besides the renderer's upload."""

    model: Model
    corners: _Corners
    tolerance: float
    lists: _ListTextures | None = None

    def release(self) -> None:
        self.corners.release()
        if self.lists is not None:
            self.lists.release()


class GpuSilhouettes:
    """Triangle-ID silhouettes drawn with a renderer's context, G-buffer pass and targets.

    Parameters
    ----------
    renderer : LayerRenderer
        Lends its context, target pool, programs and model uploads. Release this object
        before the renderer.
    compute : bool, optional
        Run the silhouette pass as a compute shader (storage buffer of corners) rather than a
        full-screen fragment pass; defaults to ``renderer.use_compute``.
    tolerance : float
        Distance, as a fraction of the model's bounding-box diagonal, under which two corners
        are one vertex (the vertex method compares positions; the ID-list method welds with it).
    """

    def __init__(
        self, renderer: LayerRenderer, *, compute: bool | None = None, tolerance: float = 1e-6
    ) -> None:
        if not 0.0 <= tolerance < 0.01:
            raise InputError(f"tolerance must be in [0, 0.01) of the model's size, got {tolerance}")
        self.renderer = renderer
        self.compute = renderer.use_compute if compute is None else bool(compute)
        self.tolerance = float(tolerance)
        self._static: dict[int, _Static] = {}
        self._entered = 0

    @contextlib.contextmanager
    def current(self):
        """Make the renderer's context current for a block (a process may hold several).

        Entering a moderngl context makes it current and leaving it makes *none* current, so
        only the outermost block of nested calls enters it.
        """
        if self._entered:
            yield
            return
        self._entered += 1
        try:
            with self.renderer.ctx:
                yield
        finally:
            self._entered -= 1

    def __enter__(self) -> GpuSilhouettes:
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    @_on_gl
    def release(self) -> None:
        for model in [held.model for held in self._static.values()]:
            self.forget(model)

    @_on_gl
    def forget(self, model: Model) -> None:
        """Release what was uploaded for `model` (its corners and ID lists)."""
        held = self._static.pop(id(model), None)
        if held is not None:
            held.release()

    def soup(self, corners, face_part=None, topology=None) -> SoupMesh:
        """A deforming mesh on the GPU from (F, 3, 3) corner positions (see :class:`SoupMesh`)."""
        return SoupMesh(self, corners, face_part, topology)

    def _entry(self, model: Model) -> _Static:
        held = self._static.get(id(model))
        if held is None or held.model is not model:
            corners = model.positions[model.faces]
            store = _Corners(self.renderer.ctx, len(model.faces))
            store.write(corners)
            tolerance = self.tolerance * _diagonal(corners)
            held = self._static[id(model)] = _Static(model, store, tolerance)
        return held

    @_on_gl
    def id_lists(self, model: Model) -> IdLists:
        """The ID lists of a static model (built, welded, on first use, then kept)."""
        return self._model_lists(model).lists

    def _model_lists(self, model: Model) -> _ListTextures:
        held = self._entry(model)
        if held.lists is None:
            lists = build_id_lists(model.positions, model.faces, held.tolerance)
            held.lists = _ListTextures(self.renderer.ctx, lists)
        return held.lists

    # -- drawing -------------------------------------------------------------------------------
    @_on_gl
    def render(
        self,
        model: Model | SoupMesh,
        camera: Camera | None = None,
        size: tuple[int, int] = (1024, 1024),
        layers: int = 1,
        method: str = "vertex",
        view: str = "iso",
        read: bool = True,
    ) -> np.ndarray | None:
        """Silhouette images of the first `layers` depth layers.

        Parameters
        ----------
        model : Model or SoupMesh
            A static model (uploaded once, shared with the renderer's blueprints) or a
            deforming mesh from :meth:`soup`.
        camera : Camera, optional
            Defaults to ``fit_camera`` from `view` at the image's size.
        size : (int, int)
            Width and height in pixels.
        layers : int
            Depth layers, 1 to 64; layer 0 is what is visible. Layers past the last surface
            come back empty.
        method : {"vertex", "idlist"}
        read : bool
            Read the images back (waits for the GPU). Without, nothing waits and the images
            stay in the renderer's target pool for GPU-side use: ``idsil.edges``, an r8 array
            with one slice per layer (compute path), or ``idsil.edge.<k>``, one r8 texture per
            layer (fragment path); row 0 at the bottom, as GL stores them.

        Returns
        -------
        np.ndarray or None
            (layers, H, W) float32, 1.0 on silhouette pixels, 0.0 elsewhere, row 0 at the top;
            None when `read` is false.
        """
        if method not in METHODS:
            raise InputError(f"unknown silhouette method {method!r} (choose {', '.join(METHODS)})")
        if int(layers) != layers or not 1 <= layers <= MAX_LAYERS:
            raise InputError(f"layers must be an integer from 1 to {MAX_LAYERS}, got {layers}")
        r, ctx = self.renderer, self.renderer.ctx
        w, h = check_size(size, 1, r.max_texture)
        if isinstance(model, SoupMesh):
            mesh, corners, tolerance = model, model.corners, model.tolerance
            lists = model.id_lists() if method == "idlist" else None
            if camera is None:
                camera = fit_camera(_box_corners(model.bounds), (w, h), view)
        elif isinstance(model, Model):
            mesh = r.mesh(model, _CREASE)
            held = self._entry(model)
            corners, tolerance = held.corners, held.tolerance
            lists = self._model_lists(model) if method == "idlist" else None
            camera = camera or fit_camera(model, (w, h), view)
        else:
            raise InputError(f"expected a Model or a SoupMesh, got {type(model).__name__}")

        ctx.enable_only(ctx.NOTHING)
        ctx.depth_func = "<"
        gb = gbuffer(r.pool, (w, h), "idb", normals=False)
        capture = Capture(r, mesh, camera, gb, tie_break=False)
        gb.ids.use(_IDS_UNIT)
        sil = self._pass(METHODS[method], (w, h), layers, corners, lists, tolerance)

        def draw(layer: int, query, guard) -> None:
            # an empty layer skips the next one's draws on the GPU, without the CPU waiting
            capture.draw(layer, query, guard)
            sil.run(layer)

        peel(draw, r.queries("peel"), [MaxLayers(layers)], look=read)
        return sil.read() if read else None

    def _pass(self, op: Op, size, layers, corners: _Corners, lists, tolerance):
        r = self.renderer
        if self.compute:
            prog = r.compute(op.compute)
            target = r.pool.texture("idsil.edges", size, "r8", layers)
            out = _ComputePass(r, prog, target, size)
        else:
            prog, vao = r.fullscreen(op.shader)
            out = _FragmentPass(r, prog, vao, size, layers)
        prog["u_ids"].value = _IDS_UNIT
        if op is IDSIL_VERTEX:
            prog["u_tolerance2"].value = tolerance * tolerance
            if self.compute:
                corners.buffer.bind_to_storage_buffer(0)
            else:
                corners.as_texture().use(_TABLE_UNIT)
                prog["u_corners"].value = _TABLE_UNIT
        else:
            for k, (name, tex) in enumerate(
                zip(("u_face_vertices", "u_pointers", "u_lists"), lists.textures, strict=True)
            ):
                tex.use(_TABLE_UNIT + k)
                prog[name].value = _TABLE_UNIT + k
        return out


class _ComputePass:
    def __init__(self, r: LayerRenderer, prog, target, size) -> None:
        self.r, self.prog, self.target, self.size = r, prog, target, size

    def run(self, layer: int) -> None:
        self.target.bind_to_image(1, read=False, write=True)
        self.prog["u_depth"].value = layer % 2
        self.prog["u_layer"].value = layer
        self.prog.run((self.size[0] + 7) // 8, (self.size[1] + 7) // 8)

    def read(self) -> np.ndarray:
        ctx = self.r.ctx
        ctx.memory_barrier(ctx.TEXTURE_UPDATE_BARRIER_BIT)
        w, h = self.size
        data = np.frombuffer(self.target.read(), np.uint8).reshape(-1, h, w)
        return (data[:, ::-1] > 127).astype(np.float32)


class _FragmentPass:
    def __init__(self, r: LayerRenderer, prog, vao, size, layers: int) -> None:
        self.prog, self.vao = prog, vao
        self.targets = [r.pool.texture(f"idsil.edge.{k}", size, "r8") for k in range(layers)]
        self.fbos = [r.pool.framebuffer((t,)) for t in self.targets]
        self.size = size

    def run(self, layer: int) -> None:
        self.prog["u_depth"].value = layer % 2
        self.fbos[layer].use()
        self.vao.render(vertices=3)

    def read(self) -> np.ndarray:
        w, h = self.size
        data = np.stack([np.frombuffer(t.read(), np.uint8).reshape(h, w) for t in self.targets])
        return (data[:, ::-1] > 127).astype(np.float32)


def _box_corners(bounds: np.ndarray) -> np.ndarray:
    lo, hi = bounds
    return np.array(
        [[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )


# -- pictures ------------------------------------------------------------------------------------
PAPER = (250, 250, 245)
INK = (20, 40, 90)


def composite(edges: np.ndarray, hidden: float = 0.35) -> np.ndarray:
    """Edge layers, (L, H, W) in [0, 1], as an RGB picture: layer 0 in full ink on paper,
    deeper layers at `hidden` strength, fading by a quarter per layer.

    Returns
    -------
    np.ndarray
        (H, W, 3) uint8.
    """
    edges = np.asarray(edges, dtype=np.float32)
    strength = np.array([1.0] + [hidden * 0.75**k for k in range(len(edges) - 1)], np.float32)
    alpha = (edges * strength[:, None, None]).max(axis=0)[..., None]
    paper, ink = np.array(PAPER, np.float32), np.array(INK, np.float32)
    return np.clip(paper + alpha * (ink - paper) + 0.5, 0, 255).astype(np.uint8)


STILL_METHODS = ("gpu-vertex", "gpu-idlist", "cpu")


def _cpu_image(positions, faces, camera: Camera, size) -> np.ndarray:
    w, h = size
    edge_set = classify_edges(
        build_adjacency(positions, faces), camera.view_matrix(), camera.projection_matrix(), w, h
    )
    chosen = np.isin(edge_set.kind, (SILHOUETTE, BORDER))
    return draw_segments(edge_set.segments2d[chosen], w, h)[None]


def render_silhouettes(
    model: Model,
    *,
    method: str = "gpu-vertex",
    layers: int = 1,
    size: tuple[int, int] = (800, 600),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    camera: Camera | None = None,
    renderer: LayerRenderer,
) -> np.ndarray:
    """A picture of a model's silhouettes (see :func:`composite`), (H, W, 3) uint8.

    ``method`` is ``gpu-vertex``, ``gpu-idlist`` or ``cpu`` (the object-space method: weld,
    connect, orient, classify, draw; it has no visibility, so it draws hidden silhouettes in
    full ink and ignores `layers`). The camera is `camera`, or one fitted from `view`,
    `azimuth`, `elevation` (degrees), `fov` and `ortho` as ``fit_camera`` does. `renderer`
    draws them (``blueprint.api.files.render_silhouettes_file`` defaults to the shared one).
    """
    if method not in STILL_METHODS:
        raise InputError(f"unknown method {method!r} (choose {', '.join(STILL_METHODS)})")
    w, h = check_size(size, 1, renderer.max_texture)
    camera = camera or fit_camera(
        model, (w, h), view, azimuth=azimuth, elevation=elevation, fov=fov, ortho=ortho
    )
    if method == "cpu":
        return composite(_cpu_image(model.positions, model.faces, camera, (w, h)))
    with GpuSilhouettes(renderer) as sil:
        edges = sil.render(model, camera, (w, h), layers, method.removeprefix("gpu-"))
    return composite(edges)


def animate_silhouettes(
    model: Model,
    *,
    animate: str = "twist",
    frames: int = 60,
    split_at: float = 0.5,
    method: str = "gpu-vertex",
    layers: int = 1,
    size: tuple[int, int] = (800, 600),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    camera: Camera | None = None,
    renderer: LayerRenderer,
) -> Iterator[tuple[np.ndarray, float]]:
    """Pictures of a deforming model's silhouettes, frame by frame: ``(image, ms)`` pairs, the
    image (H, W, 3) uint8 and `ms` the time to get its silhouettes from the frame's positions.

    ``gpu-vertex`` uploads the new positions and does nothing else per frame; ``gpu-idlist``
    rebuilds its lists when the topology changes (once, at the split); ``cpu`` redoes the whole
    object-space preprocessing every frame, as the paper's comparison does. `renderer` draws
    them, as for :func:`render_silhouettes`.
    """
    if method not in STILL_METHODS:
        raise InputError(f"unknown method {method!r} (choose {', '.join(STILL_METHODS)})")
    anim = Animation(model, animate, frames, split_at)
    w, h = check_size(size, 1, renderer.max_texture)
    if camera is None:
        camera = fit_camera(
            _box_corners(anim.bounds()),
            (w, h),
            view,
            azimuth=azimuth,
            elevation=elevation,
            fov=fov,
            ortho=ortho,
            up=model.up,
        )
    if method == "cpu":
        for i in range(anim.frames):
            pose = anim.pose(i)
            t0 = time.perf_counter()
            image = _cpu_image(pose.positions, pose.faces, camera, (w, h))
            yield composite(image), (time.perf_counter() - t0) * 1e3
        return
    with GpuSilhouettes(renderer) as sil:
        pose = anim.pose(0)
        soup = sil.soup(pose.corners(), model.face_part, (pose.faces, len(pose.positions)))
        topology = pose.topology
        try:
            for i in range(anim.frames):
                pose = anim.pose(i)
                corners = pose.corners()
                t0 = time.perf_counter()
                changed = pose.topology != topology and method == "gpu-idlist"
                soup.update(corners, (pose.faces, len(pose.positions)) if changed else None)
                topology = pose.topology
                edges = sil.render(soup, camera, (w, h), layers, method.removeprefix("gpu-"))
                yield composite(edges), (time.perf_counter() - t0) * 1e3
        finally:
            soup.release()
