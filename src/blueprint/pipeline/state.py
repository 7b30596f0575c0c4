"""What a pipeline run is asked for, holds and gives back: the request (``RunRequest``), the
G-buffer of each attribute scale, the run's state (made anew each run), what its frame drew and
read (``Drawn``), and its result."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from blueprint.compose.style import Style
from blueprint.errors import InputError
from blueprint.gpu.device import Device
from blueprint.pipeline.arrays import ArrayPlan
from blueprint.pipeline.graph import Plan
from blueprint.pipeline.inputs import PendingRead
from blueprint.pipeline.schema import Bound
from blueprint.render.capture import Capture, gbuffer
from blueprint.render.renderer import straight_alpha
from blueprint.scene.camera import Camera

# attributes the attribute pass draws (the rest are the renderer's G-buffer)
EXTRA = ("linear_depth", "position", "uv", "base_color", "triangle", "part", "layer")
#: ``RunRequest.max_layers`` where the pipeline file's setting holds.
FROM_FILE = object()


# Made every frame and never changed, yet not frozen: a frozen dataclass sets each field through
# object.__setattr__, several times the cost of a plain one's, and the executor's Python is per
# frame. Compared by identity, never by value: no generated equality to build at import.
@dataclass(slots=True, eq=False)
class RunRequest:
    """What one run of a pipeline is asked for besides the pipeline, model and camera: the
    keywords of ``Executor.run``.

    Attributes
    ----------
    size : (int, int), optional
        Output size; default the file's ``size``, else the first image input's, else 1024².
    view : str
        The named view ``camera`` defaults to (``fit_camera``).
    variables : dict, optional
        Values overriding the pipeline's declared variables.
    images : dict, optional
        Image inputs by name: (H, W, 3 or 4) uint8 arrays (row 0 at the top) or file paths,
        overriding the files the pipeline names.
    style : str or Style, optional
        Paper and inks of every composite pass (default: the pass's ``style`` parameter).
    max_layers, min_fraction, crease_angle
        Override the file's peeling settings (``max_layers=None``: every layer; ``FROM_FILE``:
        the file's).
    parts : dict, optional
        Sets of parts by name, (P,) bool each, for the attributes of chosen parts
        (``{ of = "depth", parts = "NAME" }``) that the pipeline reads.
    dumps : tuple of str
        Names whose targets are read back into ``Result.dumps``.
    profile : bool
        Wait for the GPU after each stage, timing it (``Result.stages``).
    frame : int, optional
        The frame of a video (``u_frame``); default: the executor's count of runs.
    read_later : callable, optional
        Gives a pixel buffer for the output's texture: a one-texture output is copied into it
        instead of read back (``Executor.stream``), and the result comes with ``pending`` set
        and ``output`` None.
    keep : bool
        Leave a one-texture output on the GPU, unread: ``Result.texture`` (a window shows it
        from there). Such a frame reads nothing back, so it does not count the layers a cap
        left (``Result.layers_left`` is 0): that count is a geometry pass and a read-back.
    slot : int
        Which set of buffers read late: 0 and 1 for a stream's frames (they alternate), 2 for
        a frame read at once (never those of a stream still to be read).
    contours : ContourInk, optional
        Smooth contour lines (``vector.contour_ink``) drawn into the maps the composite reads,
        in place of the outline of the faces they stand for (``pipeline.contours``).
    """

    size: tuple[int, int] | None = None
    view: str = "iso"
    variables: dict | None = None
    images: dict | None = None
    style: str | Style | None = None
    max_layers: object = FROM_FILE
    min_fraction: float | None = None
    crease_angle: float | None = None
    parts: dict[str, np.ndarray] | None = None
    dumps: tuple[str, ...] = ()
    profile: bool = False
    frame: int | None = None
    read_later: Callable | None = None
    keep: bool = False
    slot: int = 2
    contours: object | None = None


# compared by identity, never by value: no generated equality to build when the module loads
@dataclass(eq=False)
class Result:
    """What a pipeline run produced.

    output : ndarray
        (H, W, C) for a once-result, (L, H, W, C) for a per-layer one (every layer); uint8 for
        8-bit formats, float32 or int32 otherwise; row 0 at the top.
    premultiplied : bool
        The output is premultiplied colour (composite); ``image`` gives straight alpha.
    dumps : dict
        Name -> array like ``output`` for every ``dumps`` name asked for.
    revealed : float or None
        Where a ``reveal`` stop rule peeled: the fraction of its parts uncovered.
    layers_left : int
        Where the peel stopped at ``max_layers`` with surfaces left behind its last layer: how
        many more layers a peel without the cap would draw (at most); 0 otherwise.
    pending : PendingRead or None
        Where a stream issued the next frame before reading this one's output back: the output
        is None until ``collected()``.
    counting : callable or None
        Where a stream's frame was issued whole before its layers were counted: gives
        (layer_pixels, layers, layers_left), which ``collected()`` fills in (``layers`` is the
        layers drawn until then). May raise ``abuffer.Overflow``: the frame must be drawn again.
    texture : moderngl.Texture or None
        Where the run was asked to ``keep`` its output on the GPU: the output's target (OpenGL
        rows, bottom up; valid until the next run), and ``output`` is None.
    """

    output: np.ndarray
    format: str
    premultiplied: bool
    layers: int
    layer_pixels: list[int]
    camera: Camera | None
    ms: float
    draws: int
    stages: dict[str, float] = field(default_factory=dict)
    dumps: dict[str, np.ndarray] = field(default_factory=dict)
    revealed: float | None = None
    layers_left: int = 0
    pending: PendingRead | None = field(default=None, repr=False)
    counting: Callable | None = field(default=None, repr=False)
    texture: object | None = field(default=None, repr=False)

    def collected(self, **changes) -> Result:
        """This result with its output brought back, its layers counted and ``changes`` made
        (itself where there is nothing to do)."""
        if self.counting is not None:
            counts, layers, left = self.counting()
            changes.update(layer_pixels=counts, layers=layers, layers_left=left, counting=None)
        if self.pending is not None:
            changes.update(output=self.pending.collect(), pending=None)
        # (``dataclasses.replace`` looks each field up by name: a dozen calls every streamed frame)
        return Result(**{**self.__dict__, **changes}) if changes else self

    @property
    def image(self) -> np.ndarray:
        """The output as an 8-bit picture: straight alpha, row 0 at the top."""
        out = self.output
        if out.dtype != np.uint8:
            raise InputError(f"the output is {self.format}, not an 8-bit image: write it as .npz")
        if self.premultiplied and out.shape[-1] == 4:
            return straight_alpha(out)
        return out


class Sizes:
    """The target size of each scale of a plan at the output size ``size``, each checked against
    the most pixels a side the GPU allows (``most``) when first asked for."""

    def __init__(self, size: tuple[int, int], most: int) -> None:
        self.size, self.most = size, most
        self.held: dict[float, tuple[int, int]] = {}

    def __call__(self, scale: float) -> tuple[int, int]:
        held = self.held.get(scale)
        if held is None:
            w, h = self.size
            held = (max(1, round(w * scale)), max(1, round(h * scale)))
            if max(held) > self.most:
                raise InputError(
                    f"size {w}x{h} at scale {scale:g} is {held[0]}x{held[1]}: "
                    f"this GPU allows {self.most} pixels per side"
                )
            self.held[scale] = held
        return held


# compared by identity, never by value: no generated equality to build when the module loads
@dataclass(slots=True, eq=False)
class Drawn:
    """What one attempt at a run's frame drew and read: the samples of every layer drawn
    (None until counted), how many layers count, what depth masking uncovered, the layers a cap
    left, the outputs and dumps read back (by resolved name), and where the output is read late
    (``pending``), left on the GPU (``texture``) or counted late (``counting``, a stream's)."""

    layer_pixels: list[int] | None = field(default_factory=list)
    layers: int = 0
    revealed: float | None = None
    layers_left: int = 0
    outputs: dict[str, np.ndarray] = field(default_factory=dict)
    pending: PendingRead | None = None
    texture: object | None = None
    counting: Callable | None = None
    rules: tuple = ()  # the stop rules the layers were drawn under


class Group:
    """The G-buffer of one attribute scale, its geometry passes and queries, plus the attribute
    pass's targets."""

    def __init__(
        self, r: Device, scale: float, size, names: list[str], primary: bool, bound: Bound, clear_gb
    ):
        self.scale, self.size, self.names = scale, size, names
        self.queries = r.queries("peel" if primary else f"peel.pipeline.gb{scale:g}")
        self.primary = primary
        self.capture: Capture | None = None
        self.extra = [n for n in EXTRA if n in names]
        formats = tuple(bound.attributes[n].format for n in self.extra) if self.extra else ()

        def targets() -> tuple:
            gb = gbuffer(r.pool, size, "gb" if primary else f"pipeline.gb{scale:g}")
            textures = {
                name: r.pool.texture(f"pipeline.attr{scale:g}.{name}", size, fmt)
                for name, fmt in zip(self.extra, formats, strict=True)
            }
            return (
                gb,
                r.pool.framebuffer((gb.normal, gb.ids)) if clear_gb else None,
                textures,
                r.pool.framebuffer(tuple(textures[n] for n in self.extra)) if self.extra else None,
            )

        key = ("pipeline.group", scale, tuple(size), primary, clear_gb, tuple(self.extra), formats)
        self.gb, self.attr_clear, self.textures, self.extra_fbo = r.pool.held(key, targets)

    def texture(self, name: str, layer: int):
        if name == "depth":
            return self.gb.layer_depth(layer)
        if name == "normal":
            return self.gb.normal
        if name == "ids":
            return self.gb.ids
        return self.textures[name]


# compared by identity, never by value: no generated equality to build when the module loads
@dataclass(eq=False)
class RunState:
    """What one run of a pipeline holds, from its plan to the passes it ran."""

    pl: Plan
    camera: Camera | None
    crease: float
    style: Style | None  # overrides every composite's own
    shade_ink: tuple
    size_of: Callable[[float], tuple[int, int]]
    frame: int
    arrays: ArrayPlan | None  # the compute form, where it runs
    slot: int = 2  # which buffers read late (Executor.run)
    max_layers: int | None = 1  # the layers the frame draws at most (None: every layer)
    min_fraction: float = 0.0
    mesh: object = None
    stacks: dict[str, list] = field(default_factory=dict)
    stacked_layers: int = 0  # layers ``stacks`` hold room for
    stacked_arrays: int = 0  # arrays of ``SLICES`` layers each of ``stacks``' arrays holds
    attr_dumps: dict[str, list] = field(default_factory=dict)
    groups: list[Group] = field(default_factory=list)
    by_attr: dict[str, Group] = field(default_factory=dict)
    parts: dict[str, object] = field(default_factory=dict)  # attribute of chosen parts -> texture
    reach: dict[str, int | None] = field(default_factory=dict)  # Executor.reach, per pass
    # per-layer passes that read each layer from the A-buffer's lists as it is drawn
    # (Executor.run_pass), once layer 0 has captured them
    layer_lists: tuple[str, ...] = ()
    # the passes that read every layer from the surfaces of a k-buffer that holds them all
    from_surfaces: tuple[str, ...] = ()
    # the layers between the starts of two passes of those (their batch): each draws that many
    edge_step: int = 1
    # (edges pass, composite pass) where the first composes its layers into the second's target
    # (Executor.composed)
    composed: tuple[str, str] | None = None
    contours: object | None = None  # RunRequest.contours
    contoured: object | None = None  # its faces' table on the GPU (edges.glsl's u_contoured)
    draws: int = 0
