"""Occlusion levels on the GPU: one compute pass over a drawing's samples reads the faces
k-buffer where it was drawn, and only each sample's level (and the faces to either side of a
mesh edge, for the crease check) comes back. The rules are those of ``levels``, the reference
that the CPU path runs where a renderer has no faces k-buffer (``occlusion.comp``)."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from blueprint import parallel
from blueprint.gpu.device import run_over
from blueprint.gpu.tables import table_fits, table_of, table_texture
from blueprint.render.renderer import LayerRenderer
from blueprint.render.stop import standard_rules
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model

from ..lines import BORDER, CREASE, GRAZING_REACH, SILHOUETTE, SMOOTH
from .levels import DepthTest, contour_rows
from .pixels import PixelLayers
from .samples import Samples

__all__ = ["FaceTables", "FacesDrawn", "GpuLevels", "draw_faces", "gpu_levels", "stack_levels"]

OCCLUSION_COMP = "blueprint.vector:glsl/occlusion.comp"
LAYER_COUNTS_COMP = "blueprint.vector:glsl/layer_counts.comp"
DEEPEST_COMP = "blueprint.vector:glsl/deepest.comp"
COPY_FACES_COMP = "blueprint.vector:glsl/copy_faces.comp"
# The layers one pass reads at most (texture units of a compute shader: 16 at least).
MAX_LAYERS = 8
# Units the copy pass binds inside a peel, clear of the ones the peel's own passes use.
_COPY_UNITS = (14, 15)
_GROUP = 64
# occlusion.comp's Sample in 32-bit words, and the samples packed and uploaded (or their results
# read) at a time: 48 MiB of them
_SAMPLE_WORDS = 12
_STEP_ROWS = 1 << 20
# Rows of pixels one invocation of deepest.comp looks at.
_DEEPEST_ROWS = 64
# Kinds of line by their ``lines`` code: mesh edges (whose sides the crease check looks at), and
# contours (where a pixel showing no surface takes part in the minimum).
_EDGE_KINDS = np.isin(np.arange(256), (SILHOUETTE, BORDER, CREASE, SMOOTH))
_CONTOUR_KINDS = np.isin(np.arange(256), (SILHOUETTE, BORDER))


@dataclass(frozen=True)
class GpuLevels:
    """What the compute pass gives back.

    level : (S,) int32, layers in front of each sample (-1 outside the view)
    sides : (S, 2) int32, the face seen at the line's depth a pixel to either side of a mesh
        edge's sample (-1 where none, or not asked: ``checked`` False)
    checked : (S,) bool, samples of mesh edges with a direction on screen
    layers : int, layers the peel's stop rules let count
    peel_seconds : float, of the whole: drawing the k-buffer and counting its layers (of a
        k-buffer from ``draw_faces``, setting it drawing and waiting for it, not the drawing
        while the caller did other work)
    """

    level: np.ndarray
    sides: np.ndarray
    checked: np.ndarray
    layers: int
    peel_seconds: float


@dataclass(frozen=True)
class FaceTables:
    """The faces' planes and grazing band as occlusion.comp reads them, made on the GPU
    (``contour_gpu.gpu_contours``) in place of ``levels.face_planes`` and
    ``lines.grazing_band`` uploaded: ``planes`` an rgba32f table (gpu/tables.py) of eye-space
    planes n, c, ``reach`` an r32f one of the band's reach (its size times ``GRAZING_REACH``,
    0 off the band), each of ``rows`` rows and zero past the last face (no face). Samples of
    smooth contours take the band's rule with them (``DepthTest.band``'s). ``remap``: where
    the faces k-buffer drew some faces alone (a ``FaceSubset``), an r32i table of the face
    each of its IDs stands for."""

    planes: object
    reach: object
    rows: int
    remap: object | None = None

    def __len__(self) -> int:
        return self.rows

    def release(self) -> None:
        self.planes.release()
        self.reach.release()


@dataclass(frozen=True)
class FacesDrawn:
    """The faces k-buffer set drawing ahead of ``gpu_levels`` (``draw_faces``).

    surfaces : the renderer's ``face_kbuffer`` targets, or None where it draws none
    seconds : float, spent setting it drawing
    mesh : the faces drawn where some alone (``render.mesh.FaceSubset``), which the peel that
        stands in for a k-buffer draws as well; None: every face of the model
    """

    surfaces: list | None
    seconds: float
    mesh: object = None


def draw_faces(
    renderer: LayerRenderer, model: Model, camera: Camera, size, max_layers: int | None, mesh=None
) -> FacesDrawn:
    """Set the faces k-buffer of ``gpu_levels`` drawing now and go on: flushed to the driver,
    a software rasteriser's threads draw it while the CPU finds the lines, where otherwise
    the layer count would wait for all of it. Pass it to ``gpu_levels`` as ``drawn``, with the
    same model, camera, size and ``max_layers``, before anything else draws into the
    renderer's targets. ``mesh``: some of the model's faces alone (``render.mesh.FaceSubset``,
    with ``FaceTables.remap`` naming them)."""
    clock = time.perf_counter()
    renderer.make_current()
    surfaces = renderer.face_kbuffer(model, camera, size=size, max_layers=max_layers, mesh=mesh)
    if surfaces is not None:
        renderer.flush()
    return FacesDrawn(surfaces, time.perf_counter() - clock, mesh)


def _bind_surfaces(renderer: LayerRenderer, prog, surfaces) -> None:
    for unit, texture in enumerate(surfaces):
        texture.use(location=unit)
        renderer.uniforms.set(prog, f"u_s{unit}", unit)


def _layer_count(renderer: LayerRenderer, surfaces, size, min_fraction: float) -> int:
    """Layers that count under the peel's stop rules, from per-layer pixel counts made on the
    GPU, or (without ``min_fraction``, where only the first empty layer counts) from the
    deepest pixel's surfaces."""
    ctx, k = renderer.ctx, len(surfaces)
    prog = renderer.compute(LAYER_COUNTS_COMP if min_fraction > 0 else DEEPEST_COMP, {"K": k})
    _bind_surfaces(renderer, prog, surfaces)
    renderer.uniforms.set(prog, "u_size", tuple(size))
    counts = ctx.buffer(np.zeros(k, np.uint32).tobytes())
    try:
        counts.bind_to_storage_buffer(3)
        if min_fraction > 0:
            prog.run((size[0] + 7) // 8, (size[1] + 7) // 8)
        else:
            prog.run(-(-size[0] // _GROUP), -(-size[1] // _DEEPEST_ROWS))
        ctx.memory_barrier()
        read = np.frombuffer(counts.read(), np.uint32).astype(np.int64)
    finally:
        counts.release()
    if min_fraction <= 0:
        return int(read[0])
    return min(rule.count(read.tolist()) for rule in standard_rules(None, min_fraction))


def _copied_layers(renderer: LayerRenderer, model, camera, size, max_layers, min_fraction, mesh=None) -> list:
    """Peel a pass a layer (``mesh``'s faces alone where given) and copy every layer's faces
    into a texture of its own on the GPU (copy_faces.comp), for renderers without the faces
    k-buffer."""
    ctx, pool = renderer.ctx, renderer.pool
    prog = renderer.compute(COPY_FACES_COMP)
    copies: list = []

    def visit(ids, depth, layer: int) -> None:
        target = pool.texture(f"vector.faces.{size[0]}x{size[1]}.{layer}", size, "r32i")
        ids.use(location=_COPY_UNITS[0])
        depth.use(location=_COPY_UNITS[1])
        renderer.uniforms.set(prog, "u_ids", _COPY_UNITS[0])
        renderer.uniforms.set(prog, "u_depth", _COPY_UNITS[1])
        renderer.uniforms.set(prog, "u_size", tuple(size))
        target.bind_to_image(7, read=False, write=True)
        prog.run((size[0] + 7) // 8, (size[1] + 7) // 8)
        ctx.memory_barrier()
        copies.append(target)

    renderer.each_face_layer(
        model, camera, visit, size=size, max_layers=max_layers, min_fraction=min_fraction, mesh=mesh
    )
    return copies


def gpu_levels(
    renderer: LayerRenderer,
    model: Model,
    camera: Camera,
    samples: Samples,
    planes: np.ndarray | FaceTables,
    size: tuple[int, int],
    *,
    max_layers: int | None,
    test: DepthTest,
    min_fraction: float = 0.0,
    offset: float = 1.0,
    drawn: FacesDrawn | None = None,
) -> GpuLevels | None:
    """Peel and classify every sample on the GPU: from the faces k-buffer where the renderer
    draws one, else from the layers peeled a pass a layer and copied on the GPU; None for more
    than ``MAX_LAYERS`` layers or more planes than a texture holds (then ``triangles_at`` and
    ``stack_levels``, or ``classify_samples`` without compute passes).

    Parameters as ``levels.classify_samples`` and ``levels.verify_creases`` (``test`` the depth
    test of both); ``planes`` from ``levels.face_planes``, or its tables made on the GPU
    (``FaceTables``: then every smooth contour's sample takes the grazing band's rule);
    ``size`` (width, height) in pixels; ``drawn`` the faces k-buffer of this model, camera,
    size and ``max_layers`` from ``draw_faces``, else drawn here.
    """
    if not table_fits(len(planes), renderer.max_texture):
        return None
    clock = time.perf_counter()
    if drawn is None:
        drawn = FacesDrawn(renderer.face_kbuffer(model, camera, size=size, max_layers=max_layers), 0.0)
    surfaces = drawn.surfaces
    layered = surfaces is None
    if not layered:
        layers = _layer_count(renderer, surfaces, size, min_fraction)  # reading the counts waits
    elif max_layers is None or max_layers > MAX_LAYERS:
        return None
    else:
        # the peel's stop rules decided which layers count: those it handed over
        surfaces = _copied_layers(renderer, model, camera, size, max_layers, min_fraction, drawn.mesh)
        layers = len(surfaces)
    peel_seconds = time.perf_counter() - clock + drawn.seconds

    def bind(prog) -> None:
        _bind_surfaces(renderer, prog, surfaces)
        renderer.uniforms.set(prog, "u_layers", layers)

    defines = {"K": len(surfaces), "LAYERED": layered, "STACKS": False}
    level, sides, checked = _classify(renderer, defines, bind, samples, planes, size, test, offset, layers)
    return GpuLevels(level, sides, checked, layers, peel_seconds)


def stack_levels(
    renderer: LayerRenderer,
    samples: Samples,
    planes: np.ndarray,
    peeled: PixelLayers,
    *,
    test: DepthTest,
    offset: float = 1.0,
) -> GpuLevels | None:
    """``gpu_levels`` from layers read back already (``triangles_at`` at ``pixels.probe_pixels``,
    or whole layers), any number of them: the stacks go to the GPU as a table, and the same
    compute pass classifies the samples and finds the faces to either side of mesh edges, as
    ``levels.classify_samples`` and ``levels.verify_creases`` do on the CPU. None where the
    renderer runs no compute passes or a table would not fit a texture.

    Parameters as ``gpu_levels``; ``peeled`` the faces of the layers at the pixels the samples
    probe. ``peel_seconds`` is 0: the layers were peeled by the caller.
    """
    renderer.make_current()
    height, width = peeled.height, peeled.width
    stacks, count = peeled.stacks, peeled.count
    faces = stacks[np.arange(stacks.shape[1]) < count[:, None]]
    if (
        renderer.ctx.version_code < 430
        or not table_fits(max(len(planes), len(faces)), renderer.max_texture)
        or max(width, height) > renderer.max_texture
    ):
        return None
    # a pixel's surfaces run from the front: its row of the table and their count, written at
    # the pixel's place in OpenGL's rows (bottom up)
    where = np.zeros((height * width, 2), np.int32)
    pixels = np.arange(height * width) if peeled.pixels is None else peeled.pixels
    y, x = np.divmod(pixels, width)
    texel = (height - 1 - y) * width + x
    where[texel, 0] = np.cumsum(count) - count
    where[texel, 1] = count
    ctx = renderer.ctx
    # a face -1 inside a stack (none there) reads the all-zero last plane, as on the CPU
    table = table_of(faces, np.int32)
    np.putmask(table, table < 0, len(planes) - 1)
    face_table = table_texture(ctx, table)
    where_texture = ctx.texture((width, height), 2, where, dtype="i4")
    del faces, table, where, pixels, y, x, texel  # uploaded: the pass reads the textures
    where_texture.filter = (ctx.NEAREST, ctx.NEAREST)

    def bind(prog) -> None:
        for unit, (name, texture) in enumerate((("u_where", where_texture), ("u_faces", face_table))):
            texture.use(location=unit)
            renderer.uniforms.set(prog, name, unit)

    try:
        defines = {"K": 1, "LAYERED": False, "STACKS": True}
        level, sides, checked = _classify(
            renderer, defines, bind, samples, planes, (width, height), test, offset, peeled.layers
        )
    finally:
        face_table.release()
        where_texture.release()
    sides[sides == len(planes) - 1] = -1
    return GpuLevels(level, sides, checked, peeled.layers, 0.0)


def _classify(renderer, defines, bind, samples, planes, size, test, offset, layers):
    """(level, sides, checked) of ``GpuLevels`` from occlusion.comp with ``defines``, its
    faces bound by ``bind(program)``, for ``layers`` layers."""
    count = len(samples.line)
    level = np.full(count, -1, np.int32)
    sides = np.full((count, 2), -1, np.int32)
    good, across = samples.across
    checked = _EDGE_KINDS[samples.kind] & samples.inside & good
    inside = np.flatnonzero(samples.inside)
    if len(inside) == 0:
        return level, sides, checked
    if layers == 0:
        level[inside] = 0
        return level, sides, checked
    whole = len(inside) == count
    made = isinstance(planes, FaceTables)
    banded = made or test.band is not None
    contour = contour_rows(samples, inside) if banded else np.zeros(len(inside), bool)

    ctx = renderer.ctx
    remap = planes.remap if made else None
    prog = renderer.compute(OCCLUSION_COMP, {**defines, "BAND": banded, "REMAP": remap is not None})
    bind(prog)
    put = renderer.uniforms.set
    put(prog, "u_count", len(inside))
    put(prog, "u_size", tuple(size))
    put(prog, "u_ortho", bool(test.ortho))
    put(prog, "u_tolerance", float(np.float32(test.tolerance)))
    put(prog, "u_footprint", float(test.footprint))
    if made:
        plane_texture, band_texture = planes.planes, planes.reach
    else:
        plane_texture = table_texture(ctx, table_of(planes, np.float32))
        band_texture = None
        if test.band is not None:
            band_texture = table_texture(ctx, (test.band * np.float32(GRAZING_REACH)).astype(np.float32))
    plane_texture.use(location=MAX_LAYERS)
    put(prog, "u_planes", MAX_LAYERS)
    if band_texture is not None:
        band_texture.use(location=MAX_LAYERS + 1)
        put(prog, "u_reach", MAX_LAYERS + 1)
    if remap is not None:
        remap.use(location=MAX_LAYERS + 2)
        put(prog, "u_remap", MAX_LAYERS + 2)
    # the samples packed and uploaded, and the results read, a step of rows at a time: the
    # host holds no copy of all of either beside the GPU's
    n = len(inside)
    steps = [(lo, min(lo + _STEP_ROWS, n)) for lo in range(0, n, _STEP_ROWS)]
    buffers = {0: ctx.buffer(reserve=4 * _SAMPLE_WORDS * n), 2: ctx.buffer(reserve=16 * n)}
    try:
        for lo, hi in steps:
            packed = _packed(samples, inside, whole, checked, contour, across, offset, lo, hi)
            buffers[0].write(packed, offset=4 * _SAMPLE_WORDS * lo)
        for binding, buffer in buffers.items():
            buffer.bind_to_storage_buffer(binding)
        run_over(prog, n, _GROUP)
        ctx.memory_barrier()
        for lo, hi in steps:
            result = np.frombuffer(buffers[2].read(16 * (hi - lo), offset=16 * lo), np.int32).reshape(-1, 4)
            rows = slice(lo, hi) if whole else inside[lo:hi]
            level[rows] = result[:, 0]
            sides[rows] = result[:, 1:3]
    finally:
        for buffer in buffers.values():
            buffer.release()
        if not made:  # (the caller's tables are the caller's to release)
            plane_texture.release()
            if band_texture is not None:
                band_texture.release()
    return level, sides, checked


def _packed(samples, inside: np.ndarray, whole: bool, checked, contour, across, offset: float, lo, hi):
    """occlusion.comp's Sample rows of the samples ``inside[lo:hi]`` (every sample where
    ``whole``): eye (float), flags, the 2 x 2 pixels' first, the pixels to either side of the
    line, own faces (int), written in place as its int32 words, a block of rows a thread."""
    packed = np.empty((hi - lo, _SAMPLE_WORDS), np.int32)

    def pack(a: int, b: int) -> None:
        # every sample inside the view (a drawing at scale): its columns read whole, not gathered
        rows = slice(lo + a, lo + b) if whole else inside[lo + a : lo + b]
        out = packed[a:b]
        out.view(np.float32)[:, :3] = samples.eye[rows]
        flags = np.logical_not(_CONTOUR_KINDS[samples.kind[rows]]).view(np.uint8)
        flags |= checked[rows].view(np.uint8) << 1
        flags |= contour[lo + a : lo + b].view(np.uint8) << 2
        out[:, 3] = flags
        # pixels floored here in double precision, as the CPU reference has them, in one
        # scratch array; those to the sides of samples not checked are not read
        pixel, step = samples.pixel[rows], offset * across[rows]
        floored = np.subtract(pixel, 0.5)
        out[:, 4:6] = np.floor(floored, out=floored)
        out[:, 6:8] = np.floor(np.add(pixel, step, out=floored), out=floored)
        out[:, 8:10] = np.floor(np.subtract(pixel, step, out=floored), out=floored)
        out[:, 10:] = samples.faces[rows]

    parallel.run(pack, hi - lo)
    return packed
