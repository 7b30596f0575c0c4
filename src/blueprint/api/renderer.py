"""The renderer of the API: one device, the layer capture of the models uploaded to it, and the
executor that draws blueprint frames through the pipeline."""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

from blueprint.api.options import DrawOptions, takes_options
from blueprint.gpu.device import Device, current
from blueprint.render.renderer import Capturer, Frame
from blueprint.render.table import CaptureTable, capture_table
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model

if TYPE_CHECKING:
    from blueprint.pipeline.executor import Executor

# The options of a blueprint frame (``Renderer.render``): the preset's, and how it is profiled.
FRAME_KEYWORDS = (
    "size", "view", "style", "max_layers", "min_fraction", "crease_angle", "line_width", "supersample",
    "depth_threshold", "part_edges", "id_silhouettes", "smooth_contours", "highlight", "reveal", "shade",
    "shade_opacity", "profile",
)  # fmt: skip


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


def _of_capturer(method, name: str | None = None):
    """``method`` of ``Capturer`` as the renderer's own (called ``name`` where the renderer
    names it otherwise), its signature and docstring kept."""

    # looked up on the capturer at each call: what replaced it there (``stages.watch``) runs
    name_there = method.__name__

    @functools.wraps(method)
    def delegate(renderer, *args, **kwargs):
        return getattr(renderer.capturer, name_there)(*args, **kwargs)

    if name is not None:
        delegate.__name__ = name
    return delegate


class Renderer:
    """Owns one OpenGL context and composes what draws with it: its ``device`` (context,
    targets, programs, queries and capabilities: ``gpu.Device``, whose attributes are the
    renderer's too), its ``capturer`` (the models uploaded to it and how their layers are
    captured: ``render.renderer.Capturer``, whose ``mesh``, ``forget``, ``read_layers`` (the
    renderer's ``peel``), ``triangles_at``, ``face_kbuffer``, ``each_face_layer``, sources'
    memory and ``chunk_faces``, the most faces a mesh uploads at a time, are the renderer's
    too) and its
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
    peel = _of_capturer(Capturer.read_layers, "peel")
    triangles_at = _of_capturer(Capturer.triangles_at)
    face_kbuffer = _of_capturer(Capturer.face_kbuffer)
    each_face_layer = _of_capturer(Capturer.each_face_layer)
    abuffer_room = _Of("capturer")
    chunk_faces = _Of("capturer")
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
    @takes_options(*FRAME_KEYWORDS)
    def render(
        self,
        model: Model,
        camera: Camera | None = None,
        options: DrawOptions | None = None,
        *,
        on_gpu: bool = False,
    ) -> Frame:
        """Render a blueprint of ``model``: the ``blueprint`` pipeline preset.

        Parameters
        ----------
        model : Model
        camera : Camera, optional
            Defaults to ``Camera.fit`` from ``view`` at the image's aspect.
        options : DrawOptions, optional
            The frame's options, each of these fields a keyword too, over ``options`` where both
            are given (see ``blueprint.api.options.DrawOptions``): ``size``, ``view``, ``style``,
            ``max_layers``, ``min_fraction``, ``crease_angle``, ``line_width``, ``supersample``,
            ``depth_threshold``, ``part_edges``, ``id_silhouettes`` (triangle-ID silhouettes,
            paper 002), ``smooth_contours`` (smooth surfaces outlined by their contour lines),
            ``highlight`` (their whole outline drawn over everything in the style's
            highlight ink and width), ``reveal`` (depth masking: stop peeling as soon as this
            fraction of the highlighted parts' pixels is uncovered), ``shade`` (parts shaded
            inside the blueprint, in depth order), ``shade_opacity`` and ``profile``
            (synchronise after each stage to fill ``Frame.stages``).
        on_gpu : bool
            Leave the picture on the GPU (``Frame.texture``), unread: for a window of this
            renderer's context to show it (``Frame.image`` is None then). Nothing is read
            back then: ``Frame.layers_left`` is not counted (0).
        """
        # the frame's own module, which loads the pipeline: vector drawings and depth layers
        # start without it
        from blueprint.api.picture import blueprint_frame

        return blueprint_frame(self, model, camera, options, on_gpu=on_gpu)
