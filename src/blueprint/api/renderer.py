"""The renderer of the API: one device, the layer capture of the models uploaded to it, and the
executor that draws blueprint frames through the pipeline."""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import numpy as np

from blueprint.compose.style import Style
from blueprint.gpu.device import Device, current
from blueprint.render.renderer import Capturer, Frame
from blueprint.render.table import CaptureTable, capture_table
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model

if TYPE_CHECKING:
    from blueprint.pipeline.executor import Executor


class _Of:
    """An attribute of one of the renderer's parts (``device``, ``capturer``), read (and set,
    as a test forcing a capability does) through the renderer."""

    def __init__(self, part: str) -> None:
        self.part = part

    def __set_name__(self, owner, name: str) -> None:
        self.name = name

    def __get__(self, renderer, owner=None):
        return self if renderer is None else getattr(getattr(renderer, self.part), self.name)

    def __set__(self, renderer, value) -> None:
        setattr(getattr(renderer, self.part), self.name, value)


def _of_capturer(method):
    """``method`` of ``Capturer`` as the renderer's own, its signature and docstring kept."""

    @functools.wraps(method)
    def delegate(renderer, *args, **kwargs):
        return method(renderer.capturer, *args, **kwargs)

    return delegate


class Renderer:
    """Owns one OpenGL context and composes what draws with it: its ``device`` (context,
    targets, programs, queries and capabilities: ``gpu.Device``, whose attributes are the
    renderer's too), its ``capturer`` (the models uploaded to it and how their layers are
    captured: ``render.renderer.Capturer``, whose ``mesh``, ``forget``, ``peel``,
    ``triangles_at``, ``face_kbuffer``, ``each_face_layer`` and sources' memory are the
    renderer's too) and its
    ``executor`` (the pipeline's, made on first use). Draws blueprints (``render``) and peels
    depth layers (``peel``, ``triangles_at``).

    ``ctx``: a context to draw with (a window's), else a headless one. ``capture``: how layers
    are captured (``capture_table``): None for the table measured for the device, a way
    (``"peel"``, ``"k-buffer"``, ``"A-buffer"``) to capture every frame that way where it can
    be, or a ``render.table.CaptureTable``.

    Use as a context manager or call ``release()``. Models, cameras and styles stay GPU-free;
    the renderer uploads a model once per (model, crease angle).
    """

    ctx = _Of("device")
    pool = _Of("device")
    queries = _Of("device")
    uniforms = _Of("device")
    info = _Of("device")
    max_texture = _Of("device")
    max_draw_buffers = _Of("device")
    software = _Of("device")
    use_compute = _Of("device")
    framebuffer_fetch = _Of("device")
    fragment_interlock = _Of("device")
    subgroup_ballot = _Of("device")
    snapped_depth = _Of("device")
    make_current = _Of("device")
    flush = _Of("device")
    program = _Of("device")
    compute = _Of("device")
    fullscreen = _Of("device")
    depth_snap_px = _Of("device")
    mesh = _of_capturer(Capturer.mesh)
    forget = _of_capturer(Capturer.forget)
    peel = _of_capturer(Capturer.peel)
    triangles_at = _of_capturer(Capturer.triangles_at)
    face_kbuffer = _of_capturer(Capturer.face_kbuffer)
    each_face_layer = _of_capturer(Capturer.each_face_layer)
    abuffer_room = _Of("capturer")
    compute_raster = _Of("capturer")

    def __init__(self, ctx=None, *, capture: str | CaptureTable | None = None) -> None:
        self.device = Device(ctx)
        table = capture if isinstance(capture, CaptureTable) else capture_table(self.device, capture)
        self.capturer = Capturer(self.device, table)

    @functools.cached_property
    def executor(self) -> Executor:
        """The pipeline's executor on this renderer's device and capturer (its caches of
        programs and plans), made on first use: vector drawings and depth layers run none."""
        from blueprint.pipeline.executor import Executor

        return Executor(self.device, self.capturer)

    @property
    def capture_table(self) -> CaptureTable:
        """How layers are captured (``render.table``): the device's measured table, or one set
        here (``render.table.capture_table(renderer.device, way)`` forces a way)."""
        return self.capturer.table

    @capture_table.setter
    def capture_table(self, table: CaptureTable) -> None:
        self.capturer.table = table

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def release(self) -> None:
        """The executor's programs and buffers, the uploaded models, then the context."""
        self.device.make_current()
        if "executor" in self.__dict__:
            self.executor.release()
        self.capturer.release()
        self.device.release()

    @current
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
        on_gpu: bool = False,
    ) -> Frame:
        """Render a blueprint of ``model``: the ``blueprint`` pipeline preset.

        Parameters
        ----------
        model : Model
        camera : Camera, optional
            Defaults to ``Camera.fit`` from ``view`` at the image's aspect.
        size : (int, int)
            Output width and height in pixels.
        style : str or Style
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
        on_gpu : bool
            Leave the picture on the GPU (``Frame.texture``), unread: for a window of this
            renderer's context to show it (``Frame.image`` is None then). Nothing is read
            back then: ``Frame.layers_left`` is not counted (0).
        """
        # the pipeline is for pictures: vector drawings and depth layers start without it
        from blueprint.pipeline.blueprint import render_blueprint

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
            highlight=highlight,
            reveal=reveal,
            shade=shade,
            shade_opacity=shade_opacity,
            profile=profile,
            on_gpu=on_gpu,
        )
