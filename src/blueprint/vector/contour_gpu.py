"""Smooth contours of a dense mesh found on the GPU: one compute pass over the faces of the
mesh as it is drawn (its prepared vertex normals, the smooth faces its preparation found,
``scene.prepare.feature_faces``) gives the contour segments, the faces whose outline they
draw and the occlusion pass's tables of face planes and grazing band, with no adjacency, edge
classification or plane table made on the CPU. On a dense mesh (``contour_ink.DENSE``) those
cost seconds, and its triangles are some two pixels across or less: the bridges from a
contour's end to the mesh's silhouette that the vector drawing draws
(``lines.smooth_contour_segments``) would span no more, and are left out."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.gpu.device import run_over
from blueprint.gpu.tables import TABLE_WIDTH, table_fits, table_of, table_rows, table_texture
from blueprint.render.mesh import FaceSubset, GpuMesh
from blueprint.render.renderer import LayerRenderer
from blueprint.scene.model import Model
from blueprint.scene.prepare import feature_faces
from blueprint.silhouette.edges import _projected
from blueprint.sorting import stable_argsort

from .chain import chain_order
from .lines import _EDGE_ON_SMOOTH, _MIN_CONTOUR_PX, GRAZING_DEGREES, GRAZING_REACH, SILHOUETTE, Polylines
from .occlusion.gpu import FaceTables

__all__ = ["GpuContours", "gpu_contours", "near_faces"]

CONTOURS_COMP = "blueprint.vector:glsl/contours.comp"
CULL_COMP = "blueprint.vector:glsl/contour_cull.comp"
# A vertex seen within this |cos| of edge-on counts as turned away (silhouette/contours.py's).
_VERTEX_EDGE_ON = 1e-7
_GROUP = 64
# The faces near the lines are drawn alone where they are at most this share of the mesh.
_MOST_KEPT = 0.75


@dataclass(frozen=True)
class GpuContours:
    """The smooth contours of one view (``gpu_contours``).

    lines : Polylines, the contours (``SILHOUETTE``, each segment inside one face) in runs of
        at least ``lines._MIN_CONTOUR_PX`` pixels, chained end to end
    contoured : (F,) bool, the faces whose outline they draw: smooth, not seen edge-on, not on
        a shorter run unless it closes on itself
    tables : FaceTables, the faces' planes and grazing band on the GPU, for ``gpu_levels``
    mesh : GpuMesh, the model as drawn
    bounds : Buffer, each face's tiles on screen (contours.comp), for ``near_faces``
    tile : int, pixels a side of those tiles

    The caller releases what it holds on the GPU (``release``).
    """

    lines: Polylines
    contoured: np.ndarray
    tables: FaceTables
    mesh: GpuMesh
    bounds: object
    tile: int

    def release(self) -> None:
        self.tables.release()
        self.bounds.release()


def near_faces(renderer: LayerRenderer, found: GpuContours, pixels: np.ndarray, size) -> tuple | None:
    """(``FaceSubset``, r32i table of the face each of its faces is) of the faces whose box on
    screen meets a tile holding one of ``pixels`` ((N, 2), x right, y down, at ``size``) or a
    pixel within two of it: all that the occlusion pass reads around a contour's samples can
    show (the faces k-buffer, or the peel in its place, costs by its triangles); None where
    that would keep more than ``_MOST_KEPT`` of the faces. The caller releases both."""
    ctx, mesh, faces, tile = renderer.ctx, found.mesh, len(found.contoured), found.tile
    shape = (-(-size[1] // tile), -(-size[0] // tile))
    mask = np.zeros(shape, np.uint8)
    for dx in (-2.0, 2.0):
        for dy in (-2.0, 2.0):
            x = np.clip(np.floor((pixels[:, 0] + dx) / tile).astype(np.int64), 0, shape[1] - 1)
            y = np.clip(np.floor((pixels[:, 1] + dy) / tile).astype(np.int64), 0, shape[0] - 1)
            mask[y, x] = 1
    words = -(-faces // 32)
    texture = ctx.texture(shape[::-1], 1, mask, dtype="u1", alignment=1)
    kept_bits = ctx.buffer(reserve=4 * words)
    try:
        _cull(renderer, 0, ("u_mask", texture), ("u_faces", faces), {11: found.bounds, 12: kept_bits})
        ctx.memory_barrier()
        bits = np.frombuffer(kept_bits.read(), np.uint8)
    finally:
        kept_bits.release()
        texture.release()
    kept = np.flatnonzero(np.unpackbits(bits, count=faces, bitorder="little")).astype(np.int32)
    count = len(kept)
    if count > _MOST_KEPT * faces:
        return None  # lines all over the picture: the whole mesh draws as fast
    # the kept faces as the occlusion pass's table, which the gather reads too
    remap = table_texture(ctx, table_of(kept, np.int32))
    ibo = ctx.buffer(reserve=max(12 * count, 12))
    try:
        _cull(renderer, 1, ("u_kept", remap), ("u_count", count), {6: mesh.ibo, 13: ibo})
        ctx.memory_barrier(ctx.ELEMENT_ARRAY_BARRIER_BIT)
    except BaseException:
        ibo.release()
        remap.release()
        raise
    return FaceSubset(mesh, ibo, count, pieces=renderer.device.software), remap


def _cull(renderer: LayerRenderer, stage: int, table: tuple, count: tuple, buffers: dict) -> None:
    """One dispatch of contour_cull.comp's ``stage``: its ``table`` (uniform, texture) on unit
    0, its ``count`` (uniform, value) of invocations, its storage ``buffers`` by binding."""
    prog = renderer.compute(CULL_COMP, {"STAGE": stage})
    table[1].use(location=0)
    renderer.uniforms.set(prog, table[0], 0)
    renderer.uniforms.set(prog, *count)
    for binding, buffer in buffers.items():
        buffer.bind_to_storage_buffer(binding)
    run_over(prog, count[1], _GROUP)


def gpu_contours(
    renderer: LayerRenderer,
    model: Model,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    crease_angle: float,
    max_layers: int | None,
) -> GpuContours | None:
    """The smooth contours of ``model`` for the camera of ``view`` and ``projection`` ((4, 4),
    OpenGL conventions) at ``size`` (width, height) pixels, found on the GPU; None where they
    cannot be: a renderer without compute passes, a model kept as instances or drawn in chunks
    (beside a frame of ``max_layers`` at ``size``), normals not smoothed at ``crease_angle``, or
    tables larger than a texture; None too where no face is smooth."""
    if model.instances is not None or renderer.ctx.version_code < 430 or crease_angle <= 0:
        return None
    faces = model.triangle_count
    rows = table_rows(faces + 1)
    if faces == 0 or not table_fits(rows, renderer.max_texture):
        return None
    renderer.make_current()
    # a face's plane, reach and box (24 bytes) and room for segments (48 bytes for 16 faces)
    # beside a frame of the view: a mesh that would be drawn in chunks keeps its outline
    if not renderer.capturer.fits_whole(
        model, size[0] * size[1], max_layers, crease_angle, {"contours": 28 * rows}
    ):
        return None
    mesh = renderer.mesh(model, crease_angle)
    feature = feature_faces(model, crease_angle)
    # a model of no smooth face (every vertex of a building's boxes on a crease) has no contour
    if mesh.chunk_faces is not None or not mesh.one_placement or feature is None or feature.all():
        return None
    ctx = renderer.ctx
    camera_to_model = np.linalg.inv(np.asarray(view, np.float64))
    ortho = bool(projection[3, 3] == 1.0)
    toward = camera_to_model[:3, 2] if ortho else camera_to_model[:3, 3]
    prog = renderer.compute(CONTOURS_COMP)
    put = renderer.uniforms.set
    put(prog, "u_faces", faces)
    put(prog, "u_rows", rows)
    put(prog, "u_view", tuple(np.asarray(view, np.float32).T.reshape(-1).tolist()))
    put(prog, "u_toward", tuple(float(x) for x in toward))
    put(prog, "u_ortho", ortho)
    put(prog, "u_edge_on", _EDGE_ON_SMOOTH)
    put(prog, "u_vertex_edge_on", _VERTEX_EDGE_ON)
    put(prog, "u_grazing", float(np.sin(np.radians(GRAZING_DEGREES))))
    put(prog, "u_band_reach", GRAZING_REACH)
    put(prog, "u_projection", tuple(np.asarray(projection, np.float32).T.reshape(-1).tolist()))
    put(prog, "u_size", (float(size[0]), float(size[1])))
    # tiles of the faces' boxes: at most 256 a side
    tile = max(4, -(-max(size) // 256))
    put(prog, "u_tile", float(tile))
    words = -(-faces // 32)
    smooth = np.zeros(words * 4, np.uint8)
    packed = np.packbits(np.logical_not(feature), bitorder="little")
    smooth[: len(packed)] = packed
    planes = ctx.texture((TABLE_WIDTH, rows // TABLE_WIDTH), 4, dtype="f4")
    reach = ctx.texture((TABLE_WIDTH, rows // TABLE_WIDTH), 1, dtype="f4")
    for table in (planes, reach):
        table.filter = (ctx.NEAREST, ctx.NEAREST)
    tables = FaceTables(planes, reach, faces + 1)
    buffers = {7: ctx.buffer(smooth), 8: ctx.buffer(reserve=words * 4), 9: ctx.buffer(reserve=4)}
    bounds = ctx.buffer(reserve=4 * faces)
    # contours of a smooth surface run some square root of its faces; a noisy one's small loops
    # add more: the pass runs again where they outgrow the room
    capacity = max(1 << 12, faces // 16)
    try:
        mesh.vbo.bind_to_storage_buffer(5)
        mesh.ibo.bind_to_storage_buffer(6)
        planes.bind_to_image(0, read=False, write=True)
        reach.bind_to_image(1, read=False, write=True)
        while True:
            buffers[10] = ctx.buffer(reserve=48 * capacity)
            buffers[9].write(np.zeros(1, np.uint32))
            for binding, buffer in buffers.items():
                buffer.bind_to_storage_buffer(binding)
            bounds.bind_to_storage_buffer(11)
            put(prog, "u_capacity", capacity)
            run_over(prog, rows, _GROUP)
            ctx.memory_barrier()
            count = int(np.frombuffer(buffers[9].read(), np.uint32)[0])
            if count <= capacity:
                break
            buffers.pop(10).release()
            capacity = count
        found = np.zeros((0, 3, 4), np.float32)
        if count:
            found = np.frombuffer(buffers[10].read(size=48 * count), np.float32).reshape(count, 3, 4)
        bits = np.frombuffer(buffers[8].read(), np.uint8)
    except BaseException:
        tables.release()
        bounds.release()
        raise
    finally:
        for buffer in buffers.values():
            buffer.release()
    contoured = np.unpackbits(bits, count=faces, bitorder="little").view(bool)
    lines = _runs(model, found, contoured, view, projection, size)
    return GpuContours(lines, contoured, tables, mesh, bounds, tile)


def _runs(model: Model, found: np.ndarray, contoured: np.ndarray, view, projection, size) -> Polylines:
    """The contour segments ``found`` ((N, 3, 4) float32 rows of contours.comp) chained end to
    end through the edges their ends lie on, clipped to the near plane, without runs shorter
    than ``lines._MIN_CONTOUR_PX`` pixels: where such a run meets a feature, the mesh's own
    silhouette stays there (its faces leave ``contoured``), and one closed on itself is a bump
    of the noise, left out."""
    if len(found) == 0:
        none = np.zeros(0, np.int64)
        return Polylines(
            np.zeros((0, 3)), np.zeros(1, np.int64), np.zeros((0, 2), np.int64), none, none, none
        )
    face = np.ascontiguousarray(found[:, 0, 3]).view(np.int32).astype(np.int64)
    # the pass appends them in whatever order its invocations ran: by face, a face holding one,
    # the same picture every time
    order = np.argsort(face)
    face, found = face[order], found[order]
    edges = np.ascontiguousarray(found[:, 2]).view(np.uint32).astype(np.int64)
    points, pixels, kept = _projected(found[:, :2, :3].astype(np.float64), view, projection, size)
    face, edges = face[kept], edges[kept]
    # an end's key is its edge's two vertices; two segments meet where their keys are one
    ends = (edges[:, 0::2] << 32 | edges[:, 1::2]).reshape(-1)
    order = stable_argsort(ends)
    same = np.flatnonzero(ends[order[1:]] == ends[order[:-1]])
    partner = np.full(len(ends), -1, np.int64)
    partner[order[same]] = order[same + 1]
    partner[order[same + 1]] = order[same]
    piece, reverse, lengths = chain_order(partner)
    chain = np.repeat(np.arange(len(lengths)), lengths)
    run = np.bincount(chain, np.linalg.norm(pixels[:, 1] - pixels[:, 0], axis=1)[piece], len(lengths))
    enough = run >= _MIN_CONTOUR_PX
    open_chain = np.bincount(chain, (partner.reshape(-1, 2) < 0).any(axis=1)[piece], len(lengths)) > 0
    dropped = ~enough[chain]
    contoured[face[piece[dropped & open_chain[chain]]]] = False
    keep = ~dropped
    piece, reverse, chain = piece[keep], reverse[keep], chain[keep]
    lengths = lengths[enough]
    # points of a chain: its first segment's start, then every segment's end
    first = np.cumsum(lengths) - lengths
    offsets = np.r_[0, np.cumsum(lengths + 1)]
    slot = np.arange(len(piece)) + np.repeat(np.arange(len(lengths)), lengths)
    out = np.empty((offsets[-1], 3))
    out[slot] = points[piece, reverse.astype(np.int64)]
    last = first + lengths - 1
    out[offsets[1:] - 1] = points[piece[last], 1 - reverse[last].astype(np.int64)]
    faces_out = np.full((offsets[-1], 2), -1, np.int64)
    faces_out[slot, 0] = face[piece]
    kind = np.full(offsets[-1], SILHOUETTE, np.uint8)
    part = model.face_part[face[piece[first]]].astype(np.int32)
    return Polylines(out, offsets.astype(np.int64), faces_out, part, kind, np.full(offsets[-1], -1, np.int64))
