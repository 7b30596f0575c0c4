"""Dimensions of an orthographic view from its vector lines: the overall width and height of
the model, and the diameters of the circles that the lines find (chains of segments whose points
fit a circle in a plane facing the camera, closed alone or with other arcs of the same circle),
drawn after ISO 129
(``blueprint.scene.dimension``) with the values in millimetres.

The values come from the model's vertices in model coordinates, exact, not from the pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from blueprint.compose.glyphs import Glyphs
from blueprint.compose.glyphs.marks import dimension_glyph_marks
from blueprint.scene.camera import to_pixels
from blueprint.scene.dimension import diameter_marks, format_value, overall_dimensions
from blueprint.scene.model import Model
from blueprint.scene.sheet import Marks

from .lines import join_polylines, model_segments

__all__ = ["Circle", "dimension_marks", "find_circles", "with_dimension_glyphs"]

# A chain is a circle when its points lie this close (relative to the radius) to a circle in a
# plane: a tessellated circle's vertices lie on it exactly, up to float32 rounding.
_ROUND = 2e-3
# ... and the arcs of one circle close it with at least this many segments (a hexagon is a
# hexagon), each arc having three at least.
_MIN_SEGMENTS = 8
_MIN_ARC = 3
# A circle is seen as one where its plane faces the camera this squarely.
_FACING = 0.999


@dataclass(frozen=True)
class Circle:
    """A circle of the model's lines: ``centre`` and unit ``normal`` (3,), ``radius``, in model
    coordinates."""

    centre: np.ndarray
    normal: np.ndarray
    radius: float


def _fit(points: np.ndarray) -> tuple[Circle, float] | None:
    """The circle through a chain's (N, 3) points, if they lie on one in a plane, and the angle
    in radians that the chain turns around its centre."""
    mean = points.mean(axis=0)
    centred = points - mean
    _, sv, vt = np.linalg.svd(centred, full_matrices=False)
    extent = float(sv[0]) / np.sqrt(len(points))
    if extent == 0.0 or float(sv[2]) / np.sqrt(len(points)) > _ROUND * extent:
        return None
    plane = centred @ vt[:2].T
    # algebraic fit: x² + y² + D x + E y + F = 0
    rows = np.c_[plane, np.ones(len(plane))]
    rhs = -(plane**2).sum(axis=1)
    (d, e, f), *_ = np.linalg.lstsq(rows, rhs, rcond=None)
    centre2 = np.array([-d / 2, -e / 2])
    squared = centre2 @ centre2 - f
    if squared <= 0:
        return None
    radius = float(np.sqrt(squared))
    around = plane - centre2
    if np.abs(np.linalg.norm(around, axis=1) - radius).max() > _ROUND * radius:
        return None
    turns = np.arctan2(around[1:, 1], around[1:, 0]) - np.arctan2(around[:-1, 1], around[:-1, 0])
    angle = float(np.abs(np.mod(turns + np.pi, 2 * np.pi) - np.pi).sum())
    return Circle(mean + centre2 @ vt[:2], vt[2], radius), angle


def find_circles(
    model: Model, view: np.ndarray, projection: np.ndarray, size: tuple[int, int], crease_angle: float = 30.0
) -> list[Circle]:
    """The circles among the model's lines (creases and part boundaries) whose plane faces the
    camera: arcs of at least 3 segments whose points fit one circle and that, together, go
    round it with 8 segments at least (a hole's rim is often chained in halves, stopped where
    the wall's seam meets it)."""
    lines = join_polylines(model_segments(model, view, projection, size, crease_angle, intersections=False))
    sight = np.asarray(view, np.float64)[2, :3]
    sight = sight / np.linalg.norm(sight)
    found: list[list] = []  # [circle, angle turned, segments]
    for i in range(len(lines)):
        points = lines.points[lines.offsets[i] : lines.offsets[i + 1]].astype(np.float64)
        if len(points) < _MIN_ARC + 1:
            continue
        fitted = _fit(points[:-1] if np.allclose(points[0], points[-1]) else points)
        if fitted is None or abs(float(fitted[0].normal @ sight)) < _FACING:
            continue
        circle, angle = fitted
        if np.allclose(points[0], points[-1]):
            angle = 2 * np.pi
        for entry in found:
            other = entry[0]
            if (
                np.linalg.norm(other.centre - circle.centre) <= _ROUND * other.radius
                and abs(other.radius - circle.radius) <= _ROUND * other.radius
            ):
                entry[1] += angle
                entry[2] += len(points) - 1
                break
        else:
            found.append([circle, angle, len(points) - 1])
    return [c for c, angle, count in found if angle >= 2 * np.pi * (1 - 1e-3) and count >= _MIN_SEGMENTS]


def dimension_marks(
    model: Model,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    mm_per_model: float,
    mm_per_px: float | None,
    crease_angle: float = 30.0,
    circles: list[Circle] | None = None,
) -> Marks:
    """The overall width (below the view) and height (right of it) of ``model``'s used vertices
    as an orthographic camera sees them, and the diameter of every circle the lines find,
    once per value ("2× Ø 10" where two circles have it).

    Parameters
    ----------
    model : Model
    view, projection : (4, 4) float64
        The camera's matrices (orthographic).
    size : (int, int)
        The view in pixels.
    mm_per_model : float
        Millimetres per model unit (the values printed).
    mm_per_px : float or None
        Page millimetres per pixel on a drawing to scale; None for a drawing in pixels (ISO's
        measures taken at 96 pixels an inch).
    crease_angle : float
        Degrees: the lines' creases, as the drawing has them.
    circles : list of Circle, optional
        The circles ``find_circles`` finds for this camera's direction, if already found.
    """
    per_mm = 1.0 / mm_per_px if mm_per_px else 96.0 / 25.4
    view, projection = np.asarray(view, np.float64), np.asarray(projection, np.float64)
    used = model.positions[model.faces.reshape(-1)].astype(np.float64)
    marks = [overall_dimensions(used, view, projection, size, mm_per_model, per_mm)]
    # circles seen on screen once: a through hole's two rims lie on one circle there
    seen: dict[str, list[tuple[np.ndarray, float]]] = {}
    model_per_px = 2.0 / (float(projection[1, 1]) * size[1])
    if circles is None:
        circles = find_circles(model, view, projection, size, crease_angle)
    for circle in circles:
        centre = to_pixels(circle.centre[None], view, projection, size)[0]
        radius = circle.radius / model_per_px
        value = format_value(2.0 * circle.radius * mm_per_model)
        places = seen.setdefault(value, [])
        if not any(np.linalg.norm(c - centre) < 0.5 and abs(r - radius) < 0.5 for c, r in places):
            places.append((centre, radius))
    marked: list[np.ndarray] = []
    for value, places in seen.items():
        # the top-left circle carries the value for all of its size, unless one of another size
        # around the same centre (a counterbore's) carries its own: then the next one does, or,
        # with none left, the same one on its other side
        places = sorted(places, key=lambda p: (round(float(p[0][1]), 3), float(p[0][0])))
        free = [p for p in places if not any(np.linalg.norm(p[0] - c) < 0.5 for c in marked)]
        centre, radius = (free or places)[0]
        count = f"{len(places)}× " if len(places) > 1 else ""
        toward = "right" if free else "left"
        marks.append(diameter_marks(centre, radius, f"{count}Ø {value}", per_mm, toward))
        marked.append(centre)
    return Marks.concatenate(marks)


def with_dimension_glyphs(drawing, glyphs: Glyphs, mm_per_model: float):
    """``drawing`` (a one-view ``VectorDrawing``) with the dimensions of ``glyphs`` added to its marks,
    as a picture draws them (``blueprint.compose.glyphs.marks``), in mm from ``mm_per_model``
    (its boxes, arrows, paths and labels are the vector glyphs', ``blueprint.vector.glyphs``);
    those given by edges anchored already (``blueprint.vector.anchors.anchor_glyphs``).
    """
    if not glyphs.dimensions:
        return drawing
    camera = drawing.camera
    view, projection = camera.view_matrix(), camera.projection_matrix()
    size = (drawing.width, drawing.height)
    per_mm = 1.0 / drawing.page.factor if drawing.page.unit == "mm" else 96.0 / 25.4
    marks = [
        dimension_glyph_marks(d, view, projection, size, mm_per_model, per_mm) for d in glyphs.dimensions
    ]
    if drawing.marks is not None:
        marks.insert(0, drawing.marks)
    return replace(drawing, marks=Marks.concatenate(marks))
