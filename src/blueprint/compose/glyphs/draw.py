"""Drawing glyphs over a blueprint: ``draw_glyphs`` given the image's camera and front depth
layer, ``render_with_glyphs`` peeling that layer first (the only GPU use of glyphs)."""

from __future__ import annotations

import math
import os

import numpy as np

from blueprint.color import RGBA
from blueprint.compose.glyphs.marks import dimension_glyph_marks, draw_marks
from blueprint.compose.glyphs.parse import Glyphs, load_glyphs
from blueprint.compose.glyphs.projection import View
from blueprint.compose.glyphs.raster import draw_pieces, draw_text
from blueprint.compose.glyphs.strokes import arrow_stroke, box_corners, box_stroke, path_stroke, stroke_pieces
from blueprint.errors import InputError
from blueprint.render.renderer import LayerRenderer
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model
from blueprint.scene.sheet import picture_per_mm

__all__ = ["draw_glyphs", "glyph_labels", "render_with_glyphs"]


def glyph_labels(glyphs: Glyphs, view: View) -> list[tuple[np.ndarray, str, RGBA, float, str]]:
    """Every text to draw, including box, arrow and path labels: (point, text, colour, size, anchor)."""
    out = []
    for label in glyphs.labels:
        out.append((np.asarray(label.at, float), label.text, label.color, label.size, label.anchor))
    for box in glyphs.boxes:
        if box.label:
            corners = box_corners(box)
            clip = view.clip(corners)
            front = clip[:, 2] + clip[:, 3] > 0
            if front.any():
                xy, _ = view.screen(clip[front])
                top = np.lexsort((xy[:, 0], xy[:, 1]))[0]
                out.append((corners[front][top], box.label, box.color, 14.0, "bottom-left"))
    for arrow in glyphs.arrows:
        if arrow.label:
            clip = view.clip(np.array([arrow.start, arrow.end]))
            anchor = "right"
            if (clip[:, 2] + clip[:, 3] > 0).all():
                xy, _ = view.screen(clip)
                dx, dy = xy[1] - xy[0]
                if abs(dy) > 2 * abs(dx):
                    anchor = "bottom" if dy > 0 else "top"
                else:
                    anchor = "right" if dx >= 0 else "left"
            out.append((np.asarray(arrow.start, float), arrow.label, arrow.color, 14.0, anchor))
    for path in glyphs.paths:
        if path.label:
            out.append((np.asarray(path.points[0], float), path.label, path.color, 14.0, "bottom-left"))
    return out


def draw_glyphs(
    image: np.ndarray,
    glyphs: Glyphs,
    camera: Camera,
    depth: np.ndarray | None,
    *,
    line_scale: float = 1.0,
    mm_per_model: float = 1.0,
) -> np.ndarray:
    """Draw glyphs over a blueprint, hidden where the blueprint's front surface covers them.

    Every glyph segment is projected with ``camera`` (cut at the near plane) and sampled every
    ``strokes.SAMPLE_STEP`` pixels; a sample is hidden when the front surface at its pixel is
    nearer than it by more than ``projection.DEPTH_TOLERANCE`` of its eye depth (see there), and
    hidden pieces are drawn as ``glyphs.hidden`` says. Labels are tested at their anchor point.

    Parameters
    ----------
    image : (H, W, 4) uint8
        RGBA, straight alpha, row 0 at the top (``Frame.image``); (H, W, 3) is taken as opaque.
    glyphs : Glyphs
    camera : Camera
        The camera the image was drawn with (its aspect should be W / H).
    depth : (H, W) float or None
        Window depth in [0, 1] of the front surface (``Layers.depth[0]`` at the image size),
        1.0 where there is none, row 0 at the top. An (L, H, W) stack uses its layer 0.
        ``None``: nothing hides the glyphs.
    line_scale : float
        Multiplies line widths, dash lengths and text sizes (e.g. for larger prints).
    mm_per_model : float
        Millimetres per model unit: the values of the dimensions (drawn on top, never hidden).

    Returns
    -------
    np.ndarray
        A new image of the same shape and dtype uint8.

    Raises
    ------
    InputError
        A dimension given by edges that is not anchored to a model yet
        (``blueprint.anchor_glyphs``).
    """
    for i, dimension in enumerate(glyphs.dimensions, 1):
        if dimension.start is None:
            raise InputError(
                f"{glyphs.source}: dimension {i} is given by edges: anchor the glyphs to the model "
                "drawn first (blueprint.anchor_glyphs)"
            )
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] not in (3, 4) or image.dtype != np.uint8:
        raise ValueError(f"image must be (H, W, 4) uint8, got {image.shape} {image.dtype}")
    if not (math.isfinite(line_scale) and line_scale > 0):
        raise ValueError(f"line_scale must be a positive number, got {line_scale}")
    h, w = image.shape[:2]
    if depth is not None:
        depth = np.asarray(depth)
        if depth.ndim == 3:
            depth = depth[0] if len(depth) else None
    if depth is not None and depth.shape != (h, w):
        raise ValueError(f"depth must be ({h}, {w}) like the image, got {depth.shape}")
    view = View(camera, w, h, depth)
    if image.shape[2] == 4:
        canvas = image.copy()
    else:
        canvas = np.dstack([image, np.full((h, w), 255, np.uint8)])
    hidden = glyphs.hidden

    strokes = [path_stroke(p) for p in glyphs.paths]
    strokes += [box_stroke(b) for b in glyphs.boxes]
    strokes += [arrow_stroke(a, camera) for a in glyphs.arrows]
    for stroke in strokes:
        pieces, opacity = stroke_pieces(stroke, view, hidden, line_scale)
        draw_pieces(canvas, pieces, opacity, stroke.color, stroke.width * line_scale)

    for point, text, color, size, anchor in glyph_labels(glyphs, view):
        clip = view.clip(point)
        if clip[2] + clip[3] <= 0:
            continue
        xy, z = view.screen(clip)
        opacity = 1.0
        if view.hidden(xy[None], view.eye_depth(np.atleast_1d(z)))[0]:
            if hidden.mode == "none":
                continue
            opacity = hidden.opacity
        draw_text(canvas, xy, text, color, size * line_scale, anchor, opacity)

    per_mm = picture_per_mm((w, h)) * line_scale
    view_m, projection = camera.view_matrix(), camera.projection_matrix()
    for dimension in glyphs.dimensions:
        marks = dimension_glyph_marks(dimension, view_m, projection, (w, h), mm_per_model, per_mm)
        draw_marks(canvas, marks, dimension.color, dimension.width * line_scale)

    return canvas if image.shape[2] == 4 else canvas[..., :3].copy()


def render_with_glyphs(
    renderer: LayerRenderer,
    model: Model,
    camera: Camera,
    size: tuple[int, int],
    glyphs: Glyphs | str | os.PathLike,
    frame_image: np.ndarray,
    *,
    line_scale: float = 1.0,
    mm_per_model: float = 1.0,
) -> np.ndarray:
    """Peel the front depth layer of ``model`` at ``camera`` and ``size`` and draw ``glyphs``
    (a ``Glyphs`` or a glyph file) over ``frame_image`` (the blueprint drawn with the same
    camera and size); dimensions' values in mm from ``mm_per_model``. Returns a new
    (H, W, 4) uint8 image. Dimensions given by edges must be anchored first
    (``blueprint.anchor_glyphs(glyphs, model)``): ``blueprint.render`` does it."""
    if not isinstance(glyphs, Glyphs):
        glyphs = load_glyphs(glyphs)
    w, h = (int(v) for v in size)
    if frame_image.shape[:2] != (h, w):
        raise ValueError(f"frame_image is {frame_image.shape[1]}x{frame_image.shape[0]}, size is {w}x{h}")
    layers = renderer.peel(model, camera, size=(w, h), max_layers=1)
    depth = layers.depth[0] if len(layers.depth) else None
    return draw_glyphs(frame_image, glyphs, camera, depth, line_scale=line_scale, mm_per_model=mm_per_model)
