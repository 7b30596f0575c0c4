"""Smooth contours for pictures: the lines where a smooth surface turns from the view
(``smooth_contour_segments``, as the vector drawings draw them), cut where their occlusion
level changes, for the raster blueprint to draw into its layers' edge maps in place of the
mesh's own outline there. On a scan the mesh's outline zigzags across the triangles and its
noise folds leave specks of border and jump in the hidden layers; the contour of the smooth
surface runs on through them (Hertzmann and Zorin, "Illustrating smooth surfaces")."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from blueprint.render.renderer import LayerRenderer
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model

from .lines import join_polylines, smooth_contour_segments

__all__ = ["DENSE", "ContourInk", "contour_ink"]

# A mesh of more triangles than this a pixel of the view has its contours found on the GPU
# (``contour_gpu``): there the CPU's adjacency and edges cost more than the picture, and a
# fitted model's triangles are some two pixels across or less, so the bridges to the mesh's
# silhouettes, which only the CPU's lines draw, would span no more.
DENSE = 0.25


@dataclass(frozen=True)
class ContourInk:
    """The smooth contours of one view, in pieces of one occlusion level each.

    Attributes
    ----------
    points : (N, 2) float64
        Pixels at ``size``: x right, y down, origin top-left.
    offsets : (P + 1,) int64
        Piece ``i`` is ``points[offsets[i]:offsets[i + 1]]``.
    level : (P,) int32
        Surfaces in front of each piece: the depth layer whose edge map it is drawn into.
    contoured : (F,) bool
        The model's faces whose outline these lines draw in the first ``layers`` depth layers:
        the edges of a picture leave their borders and jumps out there.
    size : (int, int)
        Width and height the points are in.
    layers : int
        The depth layers whose contours these are (levels 0 to ``layers - 1``); deeper ones
        keep the mesh's outline.
    """

    points: np.ndarray
    offsets: np.ndarray
    level: np.ndarray
    contoured: np.ndarray
    size: tuple[int, int]
    layers: int

    def __len__(self) -> int:
        return len(self.offsets) - 1


def contour_ink(
    renderer: LayerRenderer,
    model: Model,
    camera: Camera,
    size: tuple[int, int],
    *,
    crease_angle: float = 30.0,
    max_layers: int | None = None,
) -> ContourInk | None:
    """The smooth contours of ``model`` seen by ``camera`` at ``size`` (width, height) pixels,
    their levels found against its surfaces peeled up to ``max_layers`` (None: all), as a
    vector drawing finds them, but of no more layers than one pass of the faces k-buffer finds
    (``MAX_LAYERS``: a layer a pass past them would peel the model again and again); None for a
    model kept as instances, whose meshes' outlines the picture draws as they are, and where no
    face is smooth. A mesh of more than ``DENSE`` triangles a pixel has them found on the GPU
    (``contour_gpu``), or where the renderer cannot (no compute passes, a mesh drawn in chunks),
    not at all (None): on the CPU they would cost more than the picture, and a mesh too large
    for the GPU's memory many times that."""
    if model.instances is not None:
        return None
    view = np.asarray(camera.view_matrix(), np.float64)
    projection = np.asarray(camera.projection_matrix(), np.float64)
    if model.triangle_count > DENSE * size[0] * size[1]:
        from .contour_gpu import gpu_contours

        max_layers = _capped(max_layers)
        found = gpu_contours(renderer, model, view, projection, size, crease_angle, max_layers)
        if found is None:
            return None
        try:
            return _dense_ink(renderer, model, camera, (view, projection), size, max_layers, found)
        finally:
            found.release()
    segments, contoured = smooth_contour_segments(model, view, projection, size, crease_angle)
    if not contoured.any():
        return None  # no face's outline to draw otherwise: the picture as it was
    from .drawing import Occlusion, ViewFrame
    from .occlusion import draw_faces, face_planes, sample_polylines

    max_layers = _capped(max_layers)

    if len(segments) == 0:
        none = np.zeros(0, np.int32)
        return ContourInk(np.zeros((0, 2)), np.zeros(1, np.int64), none, contoured, size, max_layers)
    # the faces k-buffer drawn by the driver while the lines are sampled
    drawn = draw_faces(renderer, model, camera, size, max_layers)
    lines = join_polylines(segments)
    samples = sample_polylines(lines, view, projection, size)
    # (the faces' planes in the model are made once a mesh: no corners held for them)
    planes = face_planes(model, view)
    frame = ViewFrame(camera, tuple(size), view, projection, max_layers)
    occlusion = Occlusion(renderer, model, frame, samples, planes, crease_angle, None, drawn)
    levels, count = occlusion.levels(time.perf_counter(), {})
    return _ink(renderer, samples, levels, count, lines, contoured, size)


def _capped(max_layers: int | None) -> int:
    """``max_layers`` (None: all) capped at the faces k-buffer's one pass (``MAX_LAYERS``)."""
    # the levels' machinery loads with the first picture that has smooth contours to draw
    from .occlusion.gpu import MAX_LAYERS

    return MAX_LAYERS if max_layers is None or max_layers > MAX_LAYERS else max_layers


def _dense_ink(
    renderer, model: Model, camera: Camera, matrices, size, max_layers: int, found
) -> ContourInk | None:
    """``contour_ink`` of the contours ``found`` on the GPU (``contour_gpu.GpuContours``) for
    ``camera`` and its (view, projection) ``matrices``, their levels from the faces k-buffer
    and the tables the contour pass made (no mesh edge among them: none is a phantom of a flat
    surface)."""
    from blueprint.render.gbuffer import depth_tolerance

    from .contour_gpu import near_faces
    from .occlusion import DepthTest, draw_faces, gpu_levels, sample_polylines

    contoured = found.contoured
    if not contoured.any():
        return None
    lines = found.lines
    if len(lines) == 0:
        none = np.zeros(0, np.int32)
        return ContourInk(np.zeros((0, 2)), np.zeros(1, np.int64), none, contoured, size, max_layers)
    samples = sample_polylines(lines, *matrices, size)
    # the faces k-buffer (or the peel in its place) draws the faces near the samples alone
    near = near_faces(renderer, found, samples.pixel[samples.inside], size)
    tables = found.tables
    try:
        drawn = draw_faces(renderer, model, camera, size, max_layers, None if near is None else near[0])
        if near is not None:
            tables = replace(tables, remap=near[1])
        test = DepthTest(camera.ortho, camera.pixel_angle(size[1]), depth_tolerance(camera, model.bounds))
        on_gpu = gpu_levels(
            renderer, model, camera, samples, tables, size, max_layers=max_layers, test=test, drawn=drawn
        )
    finally:
        if near is not None:
            for held in near:
                held.release()
    if on_gpu is None:
        return None
    # the faces near the samples hold every surface at them, not the whole picture's deepest:
    # the lines stand for the contoured faces' outline in every layer up to the cap (there are
    # no deeper surfaces at the samples, nor lines there)
    layers = max_layers if tables.remap is not None else on_gpu.layers
    return _ink(renderer, samples, on_gpu.level, layers, lines, contoured, size)


def _ink(renderer, samples, levels, count: int, lines, contoured, size) -> ContourInk:
    """The ``ContourInk`` of sampled ``lines`` at their ``levels`` (``count`` layers counted)."""
    from .occlusion import split_by_level

    pieces = split_by_level(samples, levels, lines.part, max(count - 1, 0), renderer=renderer)
    level = pieces.level.astype(np.int32)
    return ContourInk(pieces.points, pieces.offsets, level, contoured, tuple(size), max(count, 1))
