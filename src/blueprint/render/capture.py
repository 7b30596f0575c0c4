"""A frame's layer capture: the sources the capture table chose for it (``Capture``), the front
surface of chosen parts, and the one loop every caller draws layers with, under its stop rules
(``layer_loop``, ``blueprint.render.stop``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from blueprint.errors import InputError
from blueprint.gpu import units
from blueprint.render.gbuffer import GBuffer, depth_range, gbuffer
from blueprint.render.stop import HARD_MAX_LAYERS, StopRule
from blueprint.render.table import Request, choose
from blueprint.scene.camera import Camera

# Layers peeled between two looks at the occlusion queries when no maximum is set: one CPU
# wait per chunk instead of one per layer.
CHUNK = 8
REVEAL_FRAG = "blueprint.render:glsl/reveal.frag"


class Capture:
    """The geometry passes of one frame into one G-buffer: the first source of the rows
    ``capturer``'s capture table chose for the frame (``table.choose``) that holds it, behind the
    ``LayerSource`` protocol (``render.source``); one that finds at layer 0 that it cannot hold
    the frame after all (an A-buffer's lists past its memory) hands it to the peel, the last
    row, which takes any frame and unpacks every layer as its readers then expect.

    ``selected`` (P,) bool draws only those parts. ``asked``: what else the frame asks of its
    capture, as the fields of ``table.Request`` that name it: ``layers`` the frame draws at
    most (default 1; None: all of them), which lets a k-buffer find several a pass or an
    A-buffer every layer; ``face_ids`` false leaves the face channel 0 (a software rasteriser
    pays for tracking primitive IDs, and the blueprint needs only parts); ``tie_break`` pushes
    back faces behind coincident front faces (``gbuffer.BACK_OFFSET``; default: where the
    G-buffer has normals, ID-only passes break no ties unless asked); ``tiles``, ``defer``,
    ``unpack`` and ``slot``: an A-buffer's (its tiles' layers, counts read late, layers left in
    the lists for their readers, counts' buffer: ``ABufferSource``); ``surfaces``: the readers
    read a k-buffer's surfaces in place where one pass finds every layer of the frame
    (``KBufferSource``).
    """

    def __init__(
        self, capturer, mesh, camera: Camera, gb: GBuffer, *, selected: np.ndarray | None = None, **asked
    ) -> None:
        normals = gb.normals
        asked.setdefault("tie_break", normals)
        request = Request(
            tuple(gb.size),
            mesh.triangles,
            normals=normals,
            selected=selected is not None,
            **asked,
        )
        rows = choose(capturer.table, request)

        def open_row(row):
            return row.source.open(capturer, row, mesh, camera, gb, request, selected)

        self._peel = lambda: open_row(rows[-1])
        self.source = next(source for source in map(open_row, rows) if source is not None)

    @property
    def way(self) -> str:
        """How this capture found its layers, for reports (``blueprint bench``): ``peel`` (a
        geometry pass a layer), ``k-buffer`` (up to 8 layers a pass), ``A-buffer`` (every
        layer from one pass) or ``A-buffer, compute rasteriser`` (its fragments listed in
        compute: render.raster)."""
        return self.source.way

    @property
    def reads(self) -> str | None:
        """Where readers find the layers in place (``LayerSource.reads``), or None."""
        return self.source.reads

    @property
    def defines(self) -> dict:
        """The defines of a reader of the layers in place (``LayerSource.defines``)."""
        return self.source.defines

    @property
    def counts_kept(self) -> bool:
        """Whether the counts stay readable after the next frame is issued."""
        return self.source.counts_kept

    def bind(self, prog, layer: int, step: int) -> None:
        """The layers from ``layer`` on bound for ``prog``, a reader of them in place."""
        self.source.bind(prog, layer, step)

    def samples(self, layer: int, query) -> int:
        """Layer ``layer``'s covered samples: what its occlusion ``query`` counted, or what the
        source counted where it holds the layer's count."""
        return self.source.samples(layer, query)

    def counts(self, layers: int, queries) -> list[int]:
        """``samples`` of layers 0 to ``layers`` - 1, each counted by its query of ``queries``."""
        samples = self.source.samples
        return [samples(k, queries[k]) for k in range(layers)]

    @property
    def tile_layers(self) -> np.ndarray | None:
        """The layers of each tile (``abuffer.TILE`` pixels a side, row 0 at the bottom) where
        the source knows them once layer 0 is drawn; else None."""
        return self.source.tile_layers

    def deepest(self) -> int | None:
        """The most layers any pixel has where the source knows it once layer 0 is drawn; None
        otherwise: the layers a capped peel left, without a counting pass."""
        return self.source.deepest()

    def settle(self) -> None:
        """Read what the source reads late (``abuffer.Overflow`` where it had too little room):
        every capture of a frame is known to be whole before the frame is used."""
        self.source.settle()

    def release(self) -> None:
        self.source.release()

    def draw(self, layer: int, query, guard=None) -> int:
        """Clear and draw layer ``layer`` into the G-buffer, its samples counted by ``query``;
        with a ``guard`` query (the layer before's), an empty layer skips its draws on the GPU
        without the CPU waiting (conditional rendering). Returns the draw calls issued."""
        drawn = self.source.draw(layer, query, guard)
        if drawn is None:
            # the frame proved too big for the source: the peel draws it
            self.source.release()
            self.source = self._peel()
            drawn = self.source.draw(layer, query, guard)
        return drawn


def capture_parts(
    capturer, mesh, camera: Camera, size: tuple[int, int], parts: np.ndarray, name: str, what: str
):
    """The front surface of the flagged parts alone, in the G-buffer ``name`` (layer 0, in
    ``depth[0]``), with face IDs: depth masking, highlighted and shaded parts."""
    parts = np.asarray(parts, bool)
    if parts.shape != (mesh.part_count,):
        raise InputError(f"{what} needs one flag per part ({mesh.part_count}), got {parts.shape}")
    r = capturer.device
    gb = gbuffer(r.pool, size, name)
    capture = Capture(capturer, mesh, camera, gb, selected=parts)
    r.ctx.enable_only(r.ctx.NOTHING)
    r.ctx.depth_func = "<"
    capture.draw(0, r.queries("capture")[0])
    capture.release()
    return gb


def layer_loop(
    draw: Callable[[int, object, object], None],
    queries: Sequence,
    rules: Sequence[StopRule],
    on_counted: Callable[[int], None] | None = None,
    look: bool = True,
    samples: Callable[[int, object], int] | None = None,
    eager: bool = False,
) -> tuple[list[int], int]:
    """The one loop that draws a frame's layers, whatever source captures them (a geometry
    pass a layer, a k-buffer, an A-buffer). ``draw(layer, query, guard)`` issues layer
    ``layer``'s geometry pass (counting its samples in ``query``, skipped on the GPU when
    ``guard``, the layer before's query, counted none) and whatever runs per layer. Returns the
    samples of every layer peeled and how many of them count under ``rules``.

    The CPU looks at the counts after every layer where a rule needs it or where the caller
    reads each counted layer back (``on_counted``, called once the layer is known to count);
    else once per ``CHUNK`` layers, or once at the end when a rule caps the layers. Without
    ``look`` (a capped peel whose caller reads nothing back) it never waits: every layer up to
    the cap is issued, and the counts are left unread (returned empty). ``eager`` looks after
    every layer all the same: on a software rasteriser the CPU waiting costs nothing, while a
    capped frame of a shallow model would otherwise draw its empty layers to the cap.
    ``samples(layer, query)`` reads a layer's count where not every layer is counted by its
    query (``Capture.samples``).
    """
    samples = samples or (lambda layer, query: query.samples)
    limits = [limit for limit in (r.limit() for r in rules) if limit is not None]
    limit = min(limits) if limits else HARD_MAX_LAYERS
    every_layer = on_counted is not None or any(r.every_layer for r in rules)
    step = 1 if every_layer or eager else (limit if limits else CHUNK)
    if not look:
        if every_layer or not limits:
            raise ValueError("a peel that does not look needs a cap and no rule that looks every layer")
        for layer in range(limit):
            draw(layer, queries[layer], queries[layer - 1] if layer else None)
        return [], limit
    peeled = counted = 0
    counts: list[int] = []
    while peeled < limit:
        end = min(limit, peeled + step)
        for layer in range(peeled, end):
            draw(layer, queries[layer], queries[layer - 1] if layer else None)
        counts += [samples(k, queries[k]) for k in range(peeled, end)]
        peeled = end
        counted = min((r.count(counts) for r in rules), default=len(counts))
        if on_counted is not None and counted == peeled:
            on_counted(peeled - 1)
        # every rule looks (depth masking counts what the last layer uncovered), then any stops
        finished = [r.done(counts) for r in rules]
        if counted < peeled or any(finished):
            break
    # a chunk looked at at once may hold several layers past the last that counts: the counts
    # end at the first of them, as looking after each layer would have
    return counts[: counted + 1], counted


def revealed_pixels(r, camera: Camera, tolerance: float, mask, layer_depth=None) -> int:
    """Pixels of the chosen parts' front surface ``mask`` (a depth texture) that lie in or in
    front of ``layer_depth`` (within the depth ``tolerance``: ``gbuffer.depth_tolerance``),
    i.e. are uncovered once that layer is peeled (all of the mask's pixels without a layer),
    counted by an occlusion query and read back: depth masking."""
    prog, vao = r.fullscreen(REVEAL_FRAG)
    prog["u_depth_range"].value = depth_range(camera)
    prog["u_peel_eps"].value = tolerance
    mask.use(units.INPUTS)
    prog["u_mask_depth"].value = units.INPUTS
    (layer_depth or mask).use(units.INPUTS + 1)
    prog["u_layer_depth"].value = units.INPUTS + 1
    prog["u_count_all"].value = layer_depth is None
    r.pool.framebuffer((r.pool.texture("reveal.scratch", tuple(mask.size), "r8"),)).use()
    query = r.queries("reveal")[0]
    with query:
        vao.render(vertices=3)
    return query.samples
