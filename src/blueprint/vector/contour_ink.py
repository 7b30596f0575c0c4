"""Smooth contours for pictures: the lines where a smooth surface turns from the view
(``smooth_contour_segments``, as the vector drawings draw them), cut where their occlusion
level changes, for the raster blueprint to draw into its layers' edge maps in place of the
mesh's own outline there. On a scan the mesh's outline zigzags across the triangles and its
noise folds leave specks of border and jump in the hidden layers; the contour of the smooth
surface runs on through them (Hertzmann and Zorin, "Illustrating smooth surfaces")."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from blueprint.render.renderer import LayerRenderer
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model

from .lines import join_polylines, smooth_contour_segments

__all__ = ["ContourInk", "contour_ink"]


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
    face is smooth."""
    if model.instances is not None:
        return None
    view = np.asarray(camera.view_matrix(), np.float64)
    projection = np.asarray(camera.projection_matrix(), np.float64)
    segments, contoured = smooth_contour_segments(model, view, projection, size, crease_angle)
    if not contoured.any():
        return None  # no face's outline to draw otherwise: the picture as it was
    # the levels' machinery loads with the first picture that has smooth contours to draw
    from .drawing import Occlusion, ViewFrame
    from .occlusion import draw_faces, face_planes, sample_polylines, split_by_level
    from .occlusion.gpu import MAX_LAYERS

    if max_layers is None or max_layers > MAX_LAYERS:
        max_layers = MAX_LAYERS
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
    pieces = split_by_level(samples, levels, lines.part, max(count - 1, 0), renderer=renderer)
    level = pieces.level.astype(np.int32)
    return ContourInk(pieces.points, pieces.offsets, level, contoured, tuple(size), max(count, 1))
