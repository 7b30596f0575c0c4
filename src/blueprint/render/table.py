"""How a frame's layers are captured: the capture table, and the one function that chooses.

A row names one way of capturing layers and the thresholds from which it pays, as measured on
each kind of device (the figures are in docs/performance.md). ``capture_table`` builds a
device's table from its capabilities, best way first; ``choose`` answers a frame (a
``Request``) with the rows that take it, in the table's order: the first that holds the frame
captures it, and where one cannot (an A-buffer whose lists would pass its memory) the next takes
over. The peel, last in every table, takes any frame.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from blueprint.errors import InputError
from blueprint.render.abuffer import ABufferSource, gpu_memory_bytes
from blueprint.render.kbuffer import KBUFFER_MAX, KBUFFER_MAX_BYTES, KBufferSource, kbuffer_layers
from blueprint.render.source import PeelSource
from blueprint.settings import memory_budget

# A-buffer lists of a frame at most on a GPU whose driver does not tell its memory.
DEFAULT_ABUFFER_BYTES = 1 << 30


# made and read once a capture, never kept, compared or hashed: the cheapest dataclass
@dataclass(eq=False)
class Request:
    """What a frame asks of its capture.

    ``size`` the G-buffer's (width, height); ``triangles`` the mesh's; ``layers``
    the most layers the frame draws (None: every layer); ``normals`` false for a G-buffer of
    depth and face IDs alone; ``selected`` for the front surface of chosen parts alone;
    ``surfaces`` where the frame's readers read a k-buffer's surfaces in place when one pass
    holds every layer of the frame.
    """

    size: tuple[int, int]
    triangles: int
    layers: int | None = 1
    normals: bool = True
    selected: bool = False
    surfaces: bool = False
    # how the chosen source draws: face IDs kept (a software rasteriser pays for tracking
    # them), back faces pushed behind coincident front faces (``gbuffer.BACK_OFFSET``), and
    # an A-buffer's tiles, counts read late, layers unpacked and buffer slot (``ABufferSource``)
    face_ids: bool = True
    tie_break: bool = True
    tiles: bool = False
    defer: bool = False
    unpack: bool = True
    slot: int = 0

    @property
    def pixels(self) -> int:
        return self.size[0] * self.size[1]

    @property
    def whole(self) -> bool:
        """A whole G-buffer (normals and parts) of every part: what the sorting ways capture."""
        return self.normals and not self.selected


# A device's rows and table stay frozen, being shared by every frame it draws; one object a
# way, they compare by identity, which spares the generated comparisons' cost at import.
@dataclass(frozen=True, eq=False)
class PeelRow:
    """A geometry pass a layer: takes every frame.

    ``culled_from``: (triangles, G-buffer pixels) from which the back-face tie-break is two
    culled draws with a polygon offset instead of one draw writing depth (None: never): one
    draw measured faster in most cases, but a draw writing depth loses the early depth tests
    that big frames of dense models on a GPU need.
    """

    culled_from: tuple[int, int] | None = None
    way = "peel"
    source = PeelSource

    def accepts(self, request: Request) -> bool:
        return True

    def culled(self, request: Request, exact_depth: bool) -> bool:
        """Whether ``request``'s tie-break is two culled draws (depth written by the shader,
        ``exact_depth``, forgoes the early depth tests they keep and loses their offset)."""
        held = self.culled_from
        return (
            not exact_depth
            and held is not None
            and request.triangles >= held[0]
            and request.pixels >= held[1]
        )


@dataclass(frozen=True, eq=False)
class KBufferRow:
    """Several layers a geometry pass: each pixel's nearest surfaces sorted into ``KBUFFER_MAX``
    targets at most, through framebuffer fetch (a target a layer) or, with ``interlock``,
    fragment shader interlock on images.

    ``min_density``: triangles per G-buffer pixel from which it pays (it saves geometry passes
    but adds a full-screen pass a layer); ``max_bytes`` its targets may take; ``whole_frames``:
    only frames whose every layer one pass finds, for readers of its surfaces in place (a row
    placed before the A-buffer where that draws faster). Frames of depths and faces alone (a
    vector drawing's) it takes whatever the density where one pass finds all their layers for
    readers of its surfaces (measured only under framebuffer fetch).
    """

    min_density: float
    interlock: bool = False
    max_bytes: int = KBUFFER_MAX_BYTES
    whole_frames: bool = False
    way = "k-buffer"
    source = KBufferSource

    def accepts(self, request: Request) -> bool:
        if not request.normals:
            return request.surfaces and not request.selected and self.faces_fit(request)
        k = kbuffer_layers(request.layers)
        w, h = request.size
        return (
            k > 1
            and request.triangles >= self.min_density * w * h
            and 16 * k * w * h <= self.max_bytes
            and request.whole
            and (not self.whole_frames or self.holds_frame(request))
        )

    def holds_frame(self, request: Request) -> bool:
        """Whether one pass finds every layer of ``request`` and leaves them in its surfaces
        for its readers, with a target left for the count (framebuffer fetch alone)."""
        layers = request.layers
        return request.surfaces and not self.interlock and layers is not None and layers < KBUFFER_MAX

    def faces_fit(self, request: Request) -> bool:
        """Whether every layer of ``request``, depths and faces alone (8 bytes a pixel a
        layer), comes from one pass."""
        layers, (w, h) = request.layers, request.size
        return (
            not self.interlock
            and layers is not None
            and 1 < layers <= KBUFFER_MAX
            and 8 * layers * w * h <= self.max_bytes
        )


@dataclass(frozen=True, eq=False)
class ABufferRow:
    """Every layer from one geometry pass: per-pixel fragment lists sorted in compute.

    ``max_bytes`` its lists may take a frame (more: the next row takes the frame);
    ``min_layers``: only frames of at least this many layers (those of every layer always);
    ``slim``: fragments of depth and face alone, the rest made by the sort for the fragments
    kept as layers; ``compute_from``: G-buffers of at least this many pixels have their
    fragments listed by the rasteriser in compute (None: never). Frames of depths and faces
    alone it takes only for readers of its lists in place (``ABufferSource.faces_at``): it
    would unpack every layer into a G-buffer of normals and parts.
    """

    max_bytes: int = DEFAULT_ABUFFER_BYTES
    min_layers: int = 1
    slim: bool = False
    compute_from: int | None = None
    way = "A-buffer"
    source = ABufferSource

    def accepts(self, request: Request) -> bool:
        layers = request.layers
        in_place = request.surfaces and not request.unpack and not request.selected
        return (layers is None or layers >= self.min_layers) and (request.whole or in_place)


Row = PeelRow | KBufferRow | ABufferRow


@dataclass(frozen=True, eq=False)
class CaptureTable:
    """The ways a device captures layers, best first, the peel last; ``exact_depth``: every
    geometry pass takes its depths from the true planes (the driver's come from snapped
    corners, which would peel coincident faces of one part as two layers)."""

    rows: tuple[Row, ...] = (PeelRow(),)
    exact_depth: bool = False

    def __post_init__(self) -> None:
        if not self.rows or not isinstance(self.rows[-1], PeelRow):
            raise InputError("a capture table ends with the peel, which takes every frame")

    def row(self, way: str) -> Row | None:
        """The first row of ``way`` (``peel``, ``k-buffer``, ``A-buffer``), or None."""
        return next((row for row in self.rows if row.way == way), None)

    def describe(self) -> dict[str, str]:
        """The k-buffer and A-buffer as ``blueprint info`` prints them."""
        kbuffer, abuffer = self.row("k-buffer"), self.row("A-buffer")
        out = {}
        if kbuffer is None:
            out["kbuffer"] = "none (a geometry pass a layer)"
        else:
            way = "fragment shader interlock" if kbuffer.interlock else "framebuffer fetch"
            out["kbuffer"] = f"{way}, from {kbuffer.min_density:g} triangles per pixel"
        if abuffer is None:
            out["abuffer"] = "none (needs OpenGL 4.3)"
        else:
            least = abuffer.min_layers
            frames = "every frame" if least <= 1 else f"from {least} layers a frame"
            before = self.rows[: self.rows.index(abuffer)]
            if any(row.way == "k-buffer" and row.whole_frames for row in before):
                frames += " that one k-buffer pass does not hold"
            out["abuffer"] = (
                f"every layer in one geometry pass, {frames}, lists up to {abuffer.max_bytes / 2**30:.1f} GiB"
            )
        return out


def choose(table: CaptureTable, request: Request) -> tuple[Row, ...]:
    """The rows of ``table`` that take ``request``, in the table's order: the first that holds
    the frame captures it, the next where it cannot; the peel last."""
    return tuple(row for row in table.rows if row.accepts(request))


# the ways a table may be forced to (``capture_table``)
WAYS = ("peel", "k-buffer", "A-buffer")


def capture_table(device, way: str | None = None, max_bytes: int | None = None) -> CaptureTable:
    """``device``'s capture table (``gpu.Device``: its capabilities), from the thresholds
    measured on its kind; with ``way``, every frame captured that way where it can be, whatever
    the thresholds, the peel taking the rest. ``max_bytes``: the A-buffer's lists at most (its
    default: ``device_max_bytes``)."""
    software = device.software
    # the k-buffer through framebuffer fetch (Mesa's drivers, llvmpipe among them) with a
    # target a layer, else fragment shader interlock on images (NVIDIA's), each from the
    # density where it was measured to pay
    fetch = device.framebuffer_fetch and device.max_draw_buffers >= KBUFFER_MAX
    kbuffer = None
    if fetch:
        kbuffer = KBufferRow(min_density=0.03)
    elif device.fragment_interlock:
        kbuffer = KBufferRow(min_density=0.3, interlock=True)
    abuffer = None
    if device.ctx.version_code >= 430:
        abuffer = ABufferRow(
            max_bytes=max_bytes or device_max_bytes(device),
            # llvmpipe lists and sorts every fragment however few layers are drawn: it pays
            # only from a few layers a frame; a GPU's narrow graphics pipeline draws even one
            # layer's passes slower than the A-buffer in compute
            min_layers=4 if software else 1,
            # a GPU's geometry pass is bound by the bytes its fragments write; llvmpipe's
            # compute is its fragment stage
            slim=device.use_compute,
            # the compute rasteriser measured faster from this G-buffer size on a GPU, slower
            # below it and on llvmpipe
            compute_from=2048 * 2048 if device.use_compute else None,
        )
    # two culled draws pay only for big frames of dense models on a GPU
    peel = PeelRow(culled_from=None if software else (100_000, 1 << 22))
    exact = device.snapped_depth
    if way is not None:
        if way not in WAYS:
            raise InputError(f"unknown capture {way!r} (choose {', '.join(WAYS)})")
        forced = {"peel": None, "k-buffer": kbuffer, "A-buffer": abuffer}[way]
        if way != "peel" and forced is None:
            raise InputError(f"this driver has no {way}")
        if way == "k-buffer":
            forced = replace(forced, min_density=0.0)
        elif way == "A-buffer":
            forced = replace(forced, min_layers=1)
        return CaptureTable((forced, peel) if forced else (peel,), exact)
    rows: list[Row] = []
    if software and kbuffer is not None and abuffer is not None:
        # llvmpipe draws a capped frame faster from one k-buffer pass holding every layer,
        # read where they lie, than from the A-buffer
        rows.append(replace(kbuffer, whole_frames=True))
    rows += [row for row in (abuffer, kbuffer) if row is not None]
    return CaptureTable((*rows, peel), exact)


def device_max_bytes(device) -> int:
    """A quarter of the GPU's memory where the driver tells it; on a software rasteriser, whose
    memory is the host's, the run's memory budget (``settings.memory_budget``: a quarter of the
    memory available); else ``DEFAULT_ABUFFER_BYTES``."""
    total = gpu_memory_bytes(device)
    if total:
        return total // 4
    return memory_budget() if device.software else DEFAULT_ABUFFER_BYTES
