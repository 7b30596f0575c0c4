"""Contour lines in a frame's edge maps: the pieces of a ``ContourInk`` (smooth contours with
their occlusion levels, ``vector.contour_ink``) drawn anti-aliased into the map of the layer
of their level, blended by the maximum, before the maps are composed. The edges pass leaves
the outline of the faces they stand for to them (edges.glsl, ``SMOOTH_CONTOURS``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

CONTOUR_VERT = "blueprint.pipeline:glsl/contour_lines.vert"
CONTOUR_FRAG = "blueprint.pipeline:glsl/contour_lines.frag"
CONTOUR_MERGE = "blueprint.pipeline:glsl/contour_merge.comp"

__all__ = ["LineWidths", "draw_contours", "segment_quads"]


@dataclass(frozen=True)
class LineWidths:
    """Half widths (target pixels) and inks of the lines the edge maps hold: a visible layer's
    (0) and a hidden one's, as the edges and the lines passes make them."""

    visible_half: float
    hidden_half: float
    hidden_ink: float

    def of(self, layer: int) -> tuple[float, float]:
        """(half width, ink) of the lines of ``layer``."""
        return (self.visible_half, 1.0) if layer == 0 else (self.hidden_half, self.hidden_ink)


def segment_quads(points: np.ndarray, offsets: np.ndarray, keep: np.ndarray, reach: float) -> np.ndarray:
    """(6 S, 6) float32 vertices: two triangles a segment (corner x, y, then the segment's ends)
    around each segment of the polylines ``keep`` (P,) bool selects, grown by ``reach``
    pixels every way; ``points`` (N, 2), polyline ``i`` ``points[offsets[i]:offsets[i + 1]]``."""
    lengths = np.diff(offsets)
    inner = np.ones(max(len(points) - 1, 0), bool)
    inner[offsets[1:-1] - 1] = False  # from the last point of one polyline to the next's first
    owner = np.repeat(np.arange(len(lengths)), np.maximum(lengths - 1, 0))
    starts = np.flatnonzero(inner)
    starts = starts[keep[owner]]
    a, b = points[starts], points[starts + 1]
    along = b - a
    length = np.linalg.norm(along, axis=1)
    unit = along / np.where(length > 0, length, 1.0)[:, None]
    unit[length == 0] = (1.0, 0.0)
    side = np.stack([-unit[:, 1], unit[:, 0]], axis=1) * reach
    unit *= reach
    corners = np.stack([a - unit - side, b + unit - side, b + unit + side, a - unit + side], axis=1)
    quads = corners[:, [0, 1, 2, 0, 2, 3]]
    out = np.empty((len(starts), 6, 6), np.float32)
    out[:, :, :2] = quads
    out[:, :, 2:4] = a[:, None]
    out[:, :, 4:] = b[:, None]
    return out.reshape(-1, 6)


def draw_contours(device, ink, targets: list, layers: int, widths: LineWidths, slices: int = 0) -> int:
    """Draw ``ink``'s pieces of level below ``layers`` into ``targets`` (the edge maps, layer
    ``k`` in ``targets[k]``, all of one size: ``ink.size`` times a whole factor; or with
    ``slices``, the compute form's arrays of that many maps each, layer ``k`` in slice
    ``k % slices`` of ``targets[k // slices]``: each level drawn into a map of its own, then
    merged into its slice, CONTOUR_MERGE); the draw calls and dispatches issued."""
    ctx = device.ctx
    width, height = targets[0].size[:2]
    scale = width / ink.size[0]
    # target pixels: x right, y up
    points = np.column_stack([ink.points[:, 0] * scale, height - ink.points[:, 1] * scale])
    prog = device.program(CONTOUR_FRAG, CONTOUR_VERT)
    device.uniforms.set(prog, "u_target", (float(width), float(height)))
    # every level's quads in one buffer, each level drawn from its own range of it
    levels = np.unique(ink.level[ink.level < layers]).tolist()
    if not levels:
        return 0
    quads = [
        segment_quads(points, ink.offsets, ink.level == level, widths.of(level)[0] + 1.0) for level in levels
    ]
    ends = np.cumsum([len(q) for q in quads]).tolist()
    buffer = ctx.buffer(np.concatenate(quads).tobytes())
    vao = ctx.vertex_array(prog, [(buffer, "2f 4f", "in_corner", "in_segment")])
    ctx.enable_only(ctx.BLEND)
    ctx.blend_func = ctx.ONE, ctx.ONE
    ctx.blend_equation = ctx.MAX
    draws = 0
    merge = lines = None
    if slices:
        merge = device.compute(CONTOUR_MERGE)
        lines = device.pool.texture("pipeline.contours.lines", (width, height), "r8")
    try:
        for level, end, held in zip(levels, ends, quads, strict=True):
            half, share = widths.of(level)
            device.uniforms.update(prog, {"u_half": half, "u_ink": share})
            target = device.pool.framebuffer((targets[level] if merge is None else lines,))
            target.use()
            if merge is not None:
                target.clear()
            vao.render(vertices=len(held), first=end - len(held))
            draws += 1
            if merge is not None:
                lines.use(0)
                device.uniforms.update(merge, {"u_lines": 0, "u_slice": level % slices})
                targets[level // slices].bind_to_image(0, read=True, write=True)
                merge.run(-(-width // 8), -(-height // 8))
                ctx.memory_barrier(ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT | ctx.TEXTURE_FETCH_BARRIER_BIT)
                draws += 1
    finally:
        ctx.blend_equation = ctx.FUNC_ADD
        ctx.disable(ctx.BLEND)
        vao.release()
        buffer.release()
    return draws
