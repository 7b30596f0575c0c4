"""GPU silhouettes of a model or a deforming mesh, drawn with a renderer: each depth layer is
peeled into the renderer's ID buffer, then either the line pass draws the object-space
silhouette edges that lie on that layer, or the triangle-ID pass marks where adjacent pixels
show triangles that share no vertex."""

from __future__ import annotations

import contextlib

import numpy as np

from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.render.capture import Capture, gbuffer, layer_loop
from blueprint.render.renderer import LayerRenderer
from blueprint.render.stop import MaxLayers
from blueprint.scene.camera import Camera, fit_camera
from blueprint.scene.model import Model
from blueprint.silhouette.idlist import IdLists

from .cache import ModelTables
from .context import CurrentContext, on_gl
from .lines import LinePass
from .ops import METHODS
from .passes import IDS_UNIT, silhouette_pass
from .soup import SoupMesh, box_corners

MAX_LAYERS = 64
# What render() draws with: object-space edges as lines, or one of the triangle-ID passes.
LINES = "edges"
DRAW_METHODS = (LINES, *METHODS)
# The ID pass draws no normals, so its upload skips their smoothing, most of an upload's time.
_CREASE = None


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
        self._tables = ModelTables(renderer.ctx, self.tolerance)
        self._current = CurrentContext(renderer)

    def current(self) -> contextlib.AbstractContextManager[None]:
        """Make the renderer's context current for a block (see :class:`CurrentContext`)."""
        return self._current()

    def __enter__(self) -> GpuSilhouettes:
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    @on_gl
    def release(self) -> None:
        self._tables.release()

    @on_gl
    def forget(self, model: Model) -> None:
        """Release what was uploaded for `model` (its corners and ID lists)."""
        self._tables.forget(model)

    def soup(self, corners, face_part=None, topology=None) -> SoupMesh:
        """A deforming mesh on the GPU from (F, 3, 3) corner positions (see :class:`SoupMesh`)."""
        return SoupMesh(self.renderer, self._current, self.tolerance, corners, face_part, topology)

    @on_gl
    def id_lists(self, model: Model) -> IdLists:
        """The ID lists of a static model (built, welded, on first use, then kept)."""
        return self._tables.lists(model).lists

    @on_gl
    def edge_records(self, model: Model) -> np.ndarray:
        """The edge records of a static model, (N, 4) int32 (built, welded, on first use, then
        kept; see :mod:`blueprint.silhouette.edgerecords`)."""
        return self._tables.edges(model).records

    @on_gl
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
            A static model (uploaded once, without normals, and kept by the renderer) or a
            deforming mesh from :meth:`soup`.
        camera : Camera, optional
            Defaults to ``fit_camera`` from `view` at the image's size.
        size : (int, int)
            Width and height in pixels.
        layers : int
            Depth layers, 1 to 64; layer 0 is what is visible. Layers past the last surface
            come back empty, except with ``"edges"``, whose last layer (when there are at least
            two) holds every silhouette behind the layer before it: 2 layers draw all of them,
            visible and hidden, as the CPU method does.
        method : {"edges", "vertex", "idlist"}
            ``"edges"``: the CPU method's silhouette and border edges (front against back
            faces), classified and drawn as anti-aliased lines, one pixel wide, on the GPU;
            each layer's image holds the edges on that layer's surfaces. ``"vertex"`` and
            ``"idlist"``: the triangle-ID test, per pixel (see the package's docstring). The
            pictures (``render_silhouettes``, the command) default to ``"edges"``.
        read : bool
            Read the images back (waits for the GPU). Without, nothing waits and the images
            stay in the renderer's target pool for GPU-side use: ``idsil.line.<k>``, one r8
            texture per layer (``"edges"``), ``idsil.edges``, an r8 array with one slice per
            layer (compute path), or ``idsil.edge.<k>``, one r8 texture per layer (fragment
            path); row 0 at the bottom, as GL stores them.

        Returns
        -------
        np.ndarray or None
            (layers, H, W) float32 in [0, 1], row 0 at the top: line coverage (``"edges"``),
            or 1.0 on silhouette pixels and 0.0 elsewhere; None when `read` is false.
        """
        if method not in DRAW_METHODS:
            raise InputError(f"unknown silhouette method {method!r} (choose {', '.join(DRAW_METHODS)})")
        if int(layers) != layers or not 1 <= layers <= MAX_LAYERS:
            raise InputError(f"layers must be an integer from 1 to {MAX_LAYERS}, got {layers}")
        r, ctx = self.renderer, self.renderer.ctx
        w, h = check_size(size, 1, r.max_texture)
        if isinstance(model, SoupMesh):
            mesh, corners, tolerance, diagonal = model, model.corners, model.tolerance, model.diagonal
            lists = model.id_lists() if method == "idlist" else None
            edges = model.edges() if method == LINES else None
            if camera is None:
                camera = fit_camera(box_corners(model.bounds), (w, h), view)
        elif isinstance(model, Model):
            # sized before anything is uploaded: the ID capture (a layer a pass) in chunks
            # where only the mesh does not fit, refused where the tables and targets do not
            tables = self._tables.to_upload(model, lists=method == "idlist", edges=method == LINES)
            r.capturer.check_memory(model, w * h, 1, _CREASE, {"targets": w * h * layers, **tables})
            mesh = r.mesh(model, _CREASE)
            held = self._tables.entry(model)
            corners, tolerance, diagonal = held.corners, held.tolerance, held.diagonal
            lists = self._tables.lists(model) if method == "idlist" else None
            edges = self._tables.edges(model) if method == LINES else None
            camera = camera or fit_camera(model, (w, h), view)
        else:
            raise InputError(f"expected a Model or a SoupMesh, got {type(model).__name__}")

        ctx.enable_only(ctx.NOTHING)
        ctx.depth_func = "<"
        gb = gbuffer(r.pool, (w, h), "idb", normals=False)
        capture = Capture(r.capturer, mesh, camera, gb, tie_break=False)
        if method == LINES:
            sil = LinePass(r, edges, corners, camera, (w, h), layers, diagonal)

            def draw(layer: int, query, guard) -> None:
                capture.draw(layer, query, guard)
                sil.run(layer, guard)
        else:
            gb.ids.use(IDS_UNIT)
            sil = silhouette_pass(
                r, METHODS[method], (w, h), layers, corners, lists, tolerance, compute=self.compute
            )

            def draw(layer: int, query, guard) -> None:
                # an empty layer skips the next one's draws on the GPU, without the CPU waiting
                capture.draw(layer, query, guard)
                sil.run(layer)

        peeled = sil.peeled if method == LINES else layers
        layer_loop(draw, r.queries("peel"), [MaxLayers(peeled)], look=read)
        return sil.read() if read else None
