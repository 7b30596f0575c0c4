"""A device's layer capture (``Capturer``): the models uploaded to it, the capture table, and
depth layers peeled and read back for other tools; what code below the API takes as a renderer
(``LayerRenderer``); and the values frames and layers come back in."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from blueprint.errors import InputError
from blueprint.gpu.device import Device, check_size, current
from blueprint.render.budget import check_frame_memory, frame_bytes, uploaded
from blueprint.render.capture import Capture, layer_loop
from blueprint.render.gbuffer import gbuffer
from blueprint.render.mesh import ChunkedMesh, GpuMesh
from blueprint.render.raster import ComputeRaster
from blueprint.render.stop import standard_rules
from blueprint.render.table import CaptureTable, capture_table
from blueprint.scene.camera import Camera, fit_camera
from blueprint.scene.model import Model

if TYPE_CHECKING:
    from blueprint.scene.sheet import Marks


# Frames and layers hold arrays, which make a generated equality raise: they compare by
# identity, and their modules load without building one.
@dataclass(eq=False)
class Frame:
    """One rendered blueprint.

    ``image`` is (H, W, 4) uint8 RGBA, row 0 at the top, straight alpha. ``layer_pixels`` holds
    for every layer peeled (at the supersampled size) the samples its occlusion query counted:
    its covered pixels where a k-buffer peels, those plus the fragments drawn over again where a
    geometry pass peels it. ``layers`` is how many of them were drawn; ``draws`` the GL draw
    calls and compute dispatches the frame issued (those skipped on the GPU by conditional
    rendering included);
    ``revealed`` the fraction of the highlighted parts uncovered where depth masking peeled;
    ``layers_left``, where the peel stopped at its ``max_layers`` with surfaces left behind the
    last layer, how many more layers a peel without the cap would have drawn (at most: surfaces
    closer than the peel's tolerance count apart), else 0; always 0 on frames drawn ``on_gpu``,
    which read nothing back.
    ``marks``: the sheet marks drawn over the image (a plan sheet's border, title block and
    labels, dimensions; ``blueprint.scene.sheet.Marks``, in the image's pixels), if any.
    ``texture``, where the frame was drawn ``on_gpu``: the picture left on the GPU (a
    ``moderngl.Texture``, premultiplied RGBA, OpenGL rows from the bottom, valid until the
    renderer draws again), ``image`` None.
    """

    image: np.ndarray | None
    layers: int
    layer_pixels: list[int]
    camera: Camera
    ms: float
    draws: int
    stages: dict[str, float] = field(default_factory=dict)
    revealed: float | None = None
    layers_left: int = 0
    marks: Marks | None = None
    texture: object | None = field(default=None, repr=False)

    @property
    def layers_shown(self) -> str:
        """``"8 layers"``, or ``"8 of 40 layers"`` where the cap left layers undrawn."""
        if self.layers_left:
            return f"{self.layers} of {self.layers + self.layers_left} layers"
        return f"{self.layers} layers"


@dataclass(eq=False)
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


class Capturer:
    """The layer capture of one ``device``: the models uploaded to it, the capture table that
    chooses each frame's layer source (``render.table``: ``table``, the device's measured one
    unless given), what the sources keep from frame to frame (the fragments, and triangle-tile
    pairs, the last frame of each G-buffer size drew: the room the next one starts with), and
    the layers peeled in the one peel loop for other tools, read back (``peel``,
    ``triangles_at``) or left on the GPU (``face_kbuffer``, ``each_face_layer``).

    Release it (its models) before its device. Models and cameras stay GPU-free; a model is
    uploaded once per (model, crease angle), whole, or where the frame checked for it
    (``check_memory``, which its own routes ask before they upload) would not fit on the GPU
    with it, or ``chunk_faces`` is set, a chunk of faces at a time at every draw
    (``render.mesh.ChunkedMesh``).
    """

    def __init__(self, device: Device, table: CaptureTable | None = None) -> None:
        self.device = device
        self.table = capture_table(device) if table is None else table
        self._meshes: dict[tuple, tuple[Model, GpuMesh]] = {}
        self._checked: tuple | None = None
        self.chunk_faces = None
        # (model, faces a chunk) the last frame checked planned for its model
        self._planned: tuple[Model, int | None] | None = None
        self.abuffer_room: dict[tuple[int, int], int] = {}
        # the bytes the last frame checked leaves its A-buffer's lists (``check_memory``), and
        # what the pool held as it checked, by name: the free memory it saw was without them
        self.list_room: int | None = None
        self.pool_held: dict[str, int] = {}
        self.compute_raster = ComputeRaster(device)

    @property
    def table(self) -> CaptureTable:
        """How layers are captured (``render.table``)."""
        return self._table

    @table.setter
    def table(self, table: CaptureTable) -> None:
        if not isinstance(table, CaptureTable):
            raise TypeError(f"a capture table must be a CaptureTable, got {type(table).__name__}")
        self._table = table

    @property
    def chunk_faces(self) -> int | None:
        """The most faces a mesh uploaded from now on uploads at a time, drawn in chunks where
        it has more (None: as its frame's GPU memory allows, ``check_memory``)."""
        return self._chunk_faces

    @chunk_faces.setter
    def chunk_faces(self, faces: int | None) -> None:
        if faces is not None and (isinstance(faces, bool) or not isinstance(faces, int) or faces < 1):
            raise InputError(f"chunk_faces must be a positive whole number of faces or None, got {faces!r}")
        self._chunk_faces = faces

    def make_current(self) -> None:
        self.device.make_current()

    def release(self) -> None:
        self.make_current()
        for _, mesh in self._meshes.values():
            mesh.release()
        self._meshes.clear()

    # -- models --------------------------------------------------------------------------------
    def mesh(self, model: Model, crease_angle: float | None) -> GpuMesh:
        """``model`` on the GPU, uploaded once per crease angle (None: no normals, for passes
        that read none: a copy uploaded with normals serves them as well)."""
        found = self._held_key(model, crease_angle)
        held = self._meshes.get(found)
        faces = self._chunk_of(model)
        if held is not None and held[0] is model and faces is not None:
            uploaded_faces = held[1].chunk_faces
            # uploaded whole, or in chunks bigger than its frame now leaves room for
            if uploaded_faces is None or uploaded_faces > faces:
                self._meshes.pop(found)[1].release()
                held = None
        if held is None or held[0] is not model:
            software = self.device.software
            if faces is None:
                mesh = GpuMesh(self.device.ctx, model, crease_angle, pieces=software)
            else:
                mesh = ChunkedMesh(self.device.ctx, model, crease_angle, faces, pieces=software)
            # kept under its own crease angle, whichever copy it stands in for
            key = (id(model), None if crease_angle is None else float(crease_angle))
            held = self._meshes[key] = (model, mesh)
        return held[1]

    def _held_key(self, model: Model, crease_angle: float | None) -> tuple:
        """The key of ``model``'s upload at ``crease_angle``; for None (no normals read), that
        of a copy already uploaded with normals where there is one: its faces and corners are
        the model's, in the model's order, so its depths and face IDs are the same."""
        if crease_angle is not None:
            return id(model), float(crease_angle)
        with_normals = (k for k, (m, _) in self._meshes.items() if k[0] == id(model) and m is model)
        return next(with_normals, (id(model), None))

    def chunks(self, model: Model) -> int:
        """The chunks ``model``'s mesh is drawn in (the most of its uploads), 0 where it was
        uploaded whole or not at all."""
        return max(
            (len(mesh.chunks) for held, mesh in self._meshes.values() if held is model and mesh.chunk_faces),
            default=0,
        )

    def _chunk_of(self, model: Model) -> int | None:
        """The faces a chunk of ``model``'s mesh holds at most: ``chunk_faces``, or fewer where
        its frame's memory needs them (``check_memory``); None: uploaded whole."""
        planned = self._planned[1] if self._planned is not None and self._planned[0] is model else None
        chosen = [faces for faces in (self.chunk_faces, planned) if faces is not None]
        return min(chosen) if chosen else None

    def model_of(self, mesh: GpuMesh) -> Model | None:
        """The model uploaded as ``mesh``, or None where it is not this capturer's."""
        return next((model for model, held in self._meshes.values() if held is mesh), None)

    def check_memory(
        self,
        model: Model,
        pixels: int,
        max_layers: int | None,
        crease_angle: float | None,
        extra: dict[str, int] | None = None,
    ) -> None:
        """Size a frame of ``model`` at ``pixels`` supersampled pixels and ``max_layers``
        against the GPU memory the device has free (``render.budget``), before it allocates
        any: its mesh at ``crease_angle`` (as ``mesh`` uploads it) where not uploaded whole
        yet, and ``extra``, what the frame's own passes allocate beside the capture, by kind.
        Where the mesh does not fit beside the frame's other buffers it is drawn in chunks that
        do (``mesh``); where those buffers and a small chunk would not fit either, raise
        ``InputError``. The A-buffer's lists take no more than the rest leaves (``list_room``):
        a model deeper than they hold is peeled. Every route that uploads a model asks first (a
        picture, the layers read back or left on the GPU for the vector drawings, the GPU
        silhouettes, a pipeline's run). A frame like the last one checked, asking no more beside
        the capture, allocates nothing new, so it is not asked again: asking the driver every
        frame costs a streamed frame time it need not spend, and a caller that sized the frame
        with its own passes' buffers keeps the chunks planned for them when the capture's route
        asks again."""
        extra = dict(extra or {})
        crease = None if crease_angle is None else float(crease_angle)
        asked = (model, pixels, max_layers, crease, extra)
        last = self._checked
        if (
            last is not None
            and last[0] is model
            and last[1:4] == asked[1:4]
            and all(size <= last[4].get(kind, -1) for kind, size in extra.items())
        ):
            return
        faces, self.list_room = self._sized(model, pixels, max_layers, crease, extra)
        self.pool_held = self.device.pool.held_bytes()
        self._planned = (model, faces)
        self._checked = asked

    def fits_whole(
        self,
        model: Model,
        pixels: int,
        max_layers: int | None,
        crease_angle: float | None,
        extra: dict[str, int] | None = None,
    ) -> bool:
        """Whether a frame sized as ``check_memory`` sizes it holds ``model``'s mesh uploaded
        whole beside it, planning nothing: for a pass that runs before the frame and wants the
        mesh whole (the smooth contours found on the GPU), leaving the frame's own plan to
        the frame."""
        crease = None if crease_angle is None else float(crease_angle)
        try:
            faces, _ = self._sized(model, pixels, max_layers, crease, dict(extra or {}))
        except InputError:
            return False  # (the frame says why, in its own words)
        return faces is None

    def _sized(self, model: Model, pixels: int, max_layers: int | None, crease, extra: dict) -> tuple:
        """(the faces a chunk holds, None: the mesh whole; the lists' room) of ``check_memory``."""
        held = self._meshes.get(self._held_key(model, crease))
        whole = held is not None and held[0] is model and held[1].chunk_faces is None
        triangles, instances = (0, 0) if whole else uploaded(model)
        abuffer = self.table.row("A-buffer")
        need = frame_bytes(
            triangles,
            pixels,
            max_layers,
            abuffer.max_bytes if abuffer else None,
            instances=instances,
            extra=extra,
            slim=bool(abuffer and abuffer.slim),
        )
        return check_frame_memory(self.device, model.source or "the model", need, instances)

    @current
    def forget(self, model: Model) -> None:
        """Release the GPU copy of a model."""
        for key in [k for k, (m, _) in self._meshes.items() if m is model]:
            self._meshes.pop(key)[1].release()

    # -- layers for other tools ----------------------------------------------------------------
    @current
    def read_layers(
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
        w, h = check_size(size, 1, self.device.max_texture)
        camera = camera or fit_camera(model, (w, h), view)
        depth, normal_maps, tri = [], [], []

        def read(gb, layer: int) -> None:
            z = np.frombuffer(gb.layer_depth(layer).read(), np.float32).reshape(h, w)[::-1]
            covered = z < 1.0
            depth.append(np.where(covered, z, 1.0).astype(np.float32))
            if normals:
                n = np.frombuffer(gb.normal.read(), np.float16).reshape(h, w, 4)[::-1, :, :3]
                normal_maps.append(np.where(covered[..., None], n.astype(np.float32), 0.0))
                face = np.frombuffer(gb.ids.read(), np.int32).reshape(h, w, 2)[::-1, :, 0]
            else:
                face = np.frombuffer(gb.ids.read(), np.int32).reshape(h, w)[::-1]
            tri.append(np.where(covered, face - 1, -1).astype(np.int32))

        self._peeled(model, camera, (w, h), max_layers, min_fraction, crease_angle, normals, read)
        if depth:
            depths, triangles = np.stack(depth), np.stack(tri)
        else:
            depths, triangles = np.zeros((0, h, w), np.float32), np.zeros((0, h, w), np.int32)
        parts = np.where(triangles >= 0, model.parts_of(np.maximum(triangles, 0)), -1).astype(np.int32)
        if normals:
            normal_stack = np.stack(normal_maps) if normal_maps else np.zeros((0, h, w, 3), np.float32)
        else:
            normal_stack = None
        return Layers(
            depths, normal_stack, triangles, parts, camera.view_matrix(), camera.projection_matrix(), camera
        )

    @current
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
        pay for whole images. Where an A-buffer captures the frame, the faces are read from its
        lists at those pixels alone, every layer in one pass, none unpacked."""
        w, h = check_size(size, 1, self.device.max_texture)
        pixels = np.asarray(pixels, np.int64)
        if len(pixels) and (pixels.min() < 0 or pixels.max() >= w * h):
            raise InputError(f"pixels must be flat indices into {w}x{h}")
        # the same pixels in OpenGL's rows, bottom up
        gl = (h - 1 - pixels // w) * w + pixels % w
        check_frame_args(max_layers, min_fraction, 30.0, 1.0)
        capture, gb = self._faces(model, camera, (w, h), max_layers, in_place=True)
        out = []

        def read(layer: int) -> None:
            if capture.reads == "lists":  # read once the layers that count are known
                return
            if capture.reads == "surfaces":  # one k-buffer pass, its surfaces read as they are
                face = capture.source.faces(layer)[gl].astype(np.int64)
                out.append(np.where(face != 0, face - 1, -1).astype(np.int32))
                return
            z = np.frombuffer(gb.layer_depth(layer).read(), np.float32)[gl]
            face = np.frombuffer(gb.ids.read(), np.int32)[gl]
            out.append(np.where(z < 1.0, face - 1, -1).astype(np.int32))

        rules = standard_rules(max_layers, min_fraction)
        _, counted = layer_loop(
            capture.draw, self.device.queries("peel"), rules, read, samples=capture.samples
        )
        if capture.reads == "lists":
            faces = capture.source.faces_at(gl, counted)
        else:
            faces = np.stack(out) if out else np.zeros((0, len(pixels)), np.int32)
        capture.release()
        return faces

    @current
    def face_kbuffer(
        self,
        model: Model,
        camera: Camera,
        *,
        size: tuple[int, int],
        max_layers: int | None,
        mesh: GpuMesh | None = None,
    ):
        """The ``max_layers`` nearest surfaces of every pixel left on the GPU, for passes that
        read them there (vector occlusion): a list of ``rg32ui`` textures, surface ``k`` in the
        ``k``-th, (window depth bits, face + 1), a pixel's surfaces running up to the first
        with face 0, OpenGL rows (bottom up), from one k-buffer pass where the capture table's
        k-buffer takes such a frame; else None (``each_face_layer`` peels them a pass a layer,
        ``triangles_at`` serves either way). ``mesh``: draw these faces of the model alone (a
        ``FaceSubset``: its face IDs are the subset's)."""
        w, h = check_size(size, 1, self.device.max_texture)
        capture, _ = self._faces(model, camera, (w, h), max_layers, mesh=mesh)
        if capture.reads != "surfaces":
            capture.release()
            return None
        capture.draw(0, None)
        return list(capture.source.surfaces)

    @current
    def each_face_layer(
        self,
        model: Model,
        camera: Camera,
        visit,
        *,
        size: tuple[int, int],
        max_layers: int | None = None,
        min_fraction: float = 0.0,
        mesh: GpuMesh | None = None,
    ) -> None:
        """Peel a pass a layer, as ``triangles_at`` does there, and hand every layer that counts
        to ``visit(ids, depth, layer)`` while it is on the GPU: ``ids`` the ``r32i`` target of
        face + 1, ``depth`` the layer's window depth (1.0 where it has no surface), OpenGL rows.
        Nothing is read back. ``mesh``: peel these faces of the model alone (a ``FaceSubset``:
        its face IDs are the subset's)."""
        w, h = check_size(size, 1, self.device.max_texture)
        self._peeled(
            model,
            camera,
            (w, h),
            max_layers,
            min_fraction,
            30.0,
            False,
            lambda gb, layer: visit(gb.ids, gb.layer_depth(layer), layer),
            mesh,
        )

    def _faces(self, model, camera, size, max_layers, in_place: bool = False, mesh=None) -> tuple:
        """(capture, G-buffer) of depths and faces alone, for readers of a k-buffer's surfaces
        where the capture table's k-buffer finds every layer in one pass (``reads``
        "surfaces"), with ``in_place`` of an A-buffer's lists where the table's A-buffer takes
        the frame (``reads`` "lists"), else peeled a pass a layer into the G-buffer."""
        self.check_memory(model, size[0] * size[1], max_layers, None)
        ctx = self.device.ctx
        ctx.enable_only(ctx.NOTHING)
        ctx.depth_func = "<"
        gb = gbuffer(self.device.pool, size, "idb", normals=False)
        mesh = self.mesh(model, None) if mesh is None else mesh
        asked = {"layers": max_layers, "tie_break": True, "surfaces": True, "unpack": not in_place}
        return Capture(self, mesh, camera, gb, **asked), gb

    def _peeled(
        self, model, camera, size, max_layers, min_fraction, crease_angle, normals, read, faces=None
    ) -> None:
        """Peel layer after layer; after each one that counts, ``read(gbuffer, layer)`` (depth
        of layer ``i`` in ``depth[i % 2]``; ID target face + 1, with normals part + 1 too)."""
        check_frame_args(max_layers, min_fraction, crease_angle, 1.0)
        self.check_memory(model, size[0] * size[1], max_layers, crease_angle if normals else None)
        device = self.device
        device.ctx.enable_only(device.ctx.NOTHING)
        device.ctx.depth_func = "<"
        if normals:
            mesh = self.mesh(model, crease_angle)
            gb = gbuffer(device.pool, size)
            capture = Capture(self, mesh, camera, gb, layers=max_layers)
        else:
            mesh = self.mesh(model, None) if faces is None else faces
            gb = gbuffer(device.pool, size, "idb", normals=False)
            capture = Capture(self, mesh, camera, gb, tie_break=True)
        rules = standard_rules(max_layers, min_fraction)
        queries = device.queries("peel")
        layer_loop(capture.draw, queries, rules, lambda layer: read(gb, layer), samples=capture.samples)


class LayerRenderer(Protocol):
    """What code below the API takes as a renderer (``blueprint.Renderer`` is one): a
    ``device`` whose attributes it shows as its own (``ctx``, ``pool``, ``uniforms``,
    ``queries``, ``program``, ``compute``, ``fullscreen``, the capabilities: ``gpu.Device``)
    and the ``capturer`` of the models uploaded to it, whose methods it shows as its own too
    (``mesh``, ``read_layers`` as ``peel``, ``triangles_at``, ``face_kbuffer``,
    ``each_face_layer``)."""

    device: Device
    capturer: Capturer

    def mesh(self, model: Model, crease_angle: float | None) -> GpuMesh: ...

    def peel(self, model: Model, camera: Camera | None = None, **options) -> Layers: ...


def check_frame_args(max_layers, min_fraction, crease_angle, line_width) -> None:
    """A frame's arguments, checked before any GPU work (the stop rules check their own)."""
    standard_rules(max_layers, min_fraction)
    if not 0.0 <= crease_angle <= 180.0:
        raise InputError(f"crease-angle must be in [0, 180] degrees, got {crease_angle}")
    if not 1.0 <= line_width <= 16.0:
        raise InputError(f"line-width must be in [1, 16] pixels, got {line_width}")


def straight_alpha(premultiplied: np.ndarray) -> np.ndarray:
    rgba = premultiplied.astype(np.float32)
    alpha = rgba[..., 3:4]
    rgb = np.where(alpha > 0, rgba[..., :3] * 255.0 / np.maximum(alpha, 1), 0)
    return np.concatenate([np.clip(rgb + 0.5, 0, 255), alpha], axis=-1).astype(np.uint8)
