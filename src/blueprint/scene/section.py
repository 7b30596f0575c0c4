"""Section views on the CPU: a plane cuts every part, the material in front of it is removed and
each part's cut face is capped, so that the ordinary peel draws what lies behind the cut (and its
hidden lines) while the cap triangles, marked, are where the hatching goes.

``--section x=VALUE`` (``y=``, ``z=``) cuts across an axis and removes the side facing the camera;
``--section-plane PX,PY,PZ,NX,NY,NZ`` gives a point of the plane and a normal pointing at the side
removed. Parts matched by ``--section-keep`` are drawn whole and uncut, as drawings show shafts,
bolts and pins.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from blueprint.errors import InputError
from blueprint.scene.model import Model
from blueprint.sorting import grouped, renumbered

__all__ = ["Cut", "SectionPlane", "cut_model", "parse_section"]

log = logging.getLogger("blueprint")

_AXES = {"x": 0, "y": 1, "z": 2}
_SECTION_FORMS = "x=VALUE, y=VALUE or z=VALUE (model units)"
_PLANE_FORMS = "PX,PY,PZ,NX,NY,NZ: a point of the plane and a normal towards the side removed"


@dataclass(frozen=True, eq=False)
class SectionPlane:
    """A cutting plane.

    Attributes
    ----------
    point : (3,) float64
        A point of the plane, in model coordinates.
    normal : (3,) float64
        Unit normal pointing at the side that is removed.
    axis : {"x", "y", "z"} or None
        Set for a cut across an axis whose normal is yet to be turned towards the camera that
        draws it (``facing``); None once turned, and for a plane given by its normal.
    text : str
        The plane as the user gave it, for messages.
    """

    point: np.ndarray
    normal: np.ndarray
    axis: str | None
    text: str

    def facing(self, eye: Sequence[float], target: Sequence[float]) -> SectionPlane:
        """This plane with an axis cut's normal turned towards the eye (the side in front of the
        plane as the camera sees it is removed), for good; a plane seen edge-on removes the
        positive side."""
        if self.axis is None:
            return self
        toward = np.asarray(eye, np.float64) - np.asarray(target, np.float64)
        along = float(toward[_AXES[self.axis]])
        sign = -1.0 if along < -1e-9 * float(np.linalg.norm(toward)) else 1.0
        normal = np.zeros(3)
        normal[_AXES[self.axis]] = sign
        return SectionPlane(self.point, normal, None, self.text)


def _numbers(text: str, count: int, what: str, forms: str) -> list[float]:
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise InputError(f"{what} {text!r} is not {count} numbers (give {forms})")
    return values


def parse_section(
    section: str | None = None, plane: str | Sequence[float] | None = None
) -> SectionPlane | None:
    """The cutting plane of ``--section`` (``"x=12.5"``) or ``--section-plane``
    (``"0,0,5,0,0,1"`` or six numbers); None when neither is given.

    Raises
    ------
    InputError
        Both are given, or either is malformed: the message names the accepted forms.
    """
    if section is not None and plane is not None:
        raise InputError("give --section or --section-plane, not both")
    if section is not None:
        match = re.fullmatch(r"\s*([xyzXYZ])\s*=\s*(\S+)\s*", str(section))
        value = None
        if match:
            try:
                value = float(match.group(2))
            except ValueError:
                value = None
        if value is None or not math.isfinite(value):
            raise InputError(f"section {section!r} is not of the form {_SECTION_FORMS}")
        axis = match.group(1).lower()
        point = np.zeros(3)
        point[_AXES[axis]] = value
        normal = np.zeros(3)
        normal[_AXES[axis]] = 1.0
        return SectionPlane(point, normal, axis, f"{axis}={value:g}")
    if plane is not None:
        text = plane if isinstance(plane, str) else ",".join(str(v) for v in plane)
        values = _numbers(text, 6, "section plane", _PLANE_FORMS)
        normal = np.array(values[3:], np.float64)
        length = float(np.linalg.norm(normal))
        if length == 0.0 or not math.isfinite(length):
            raise InputError(f"section plane {text!r} has no normal (give {_PLANE_FORMS})")
        return SectionPlane(np.array(values[:3], np.float64), normal / length, None, text)
    return None


@dataclass(frozen=True, eq=False)
class Cut:
    """A model cut by a section plane.

    Attributes
    ----------
    model : Model
        What is left behind the plane, each cut part capped; the same parts (and part indices)
        as the model cut, a part wholly in front of the plane having no faces.
    cap : (F,) bool
        The faces of ``model`` that close a cut: the section's cut faces.
    plane : SectionPlane
        The plane, its normal pointing at the side removed.
    keep : (P,) bool or None
        The parts left whole (drawn uncut by convention); None: none.
    """

    model: Model
    cap: np.ndarray
    plane: SectionPlane
    keep: np.ndarray | None = None

    def cap_parts(self) -> np.ndarray:
        """Indices of the parts with a cut face, ascending."""
        return np.unique(self.model.face_part[self.cap])

    def cap_area(self) -> float:
        """Area of the cut faces in model units squared."""
        tri = self.model.positions[self.model.faces[self.cap]].astype(np.float64)
        return float(
            0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
        )


def cut_model(model: Model, plane: SectionPlane, keep: np.ndarray | None = None) -> Cut:
    """Cut every part of ``model`` by ``plane``, removing the side its normal points at, and
    cap each cut part; parts flagged in ``keep`` ((P,) bool) stay whole.

    Parts wholly behind the plane, or kept, pass through as arrays; parts wholly in front are
    dropped; only the parts the plane runs through are sliced and capped one at a time, each
    as a mesh of its own vertices (so that a plane through a few parts of an assembly of
    thousands costs those few).

    Raises
    ------
    InputError
        The plane cuts none of the parts (it misses the model, or cuts only parts kept whole).
    """
    count = len(model.part_names)
    keep = np.zeros(count, bool) if keep is None else np.asarray(keep, bool)
    extent = float(np.ptp(model.bounds, axis=0).max()) or 1.0
    eps = 1e-6 * extent
    good = ~model.degenerate_faces()
    faces, part = model.faces[good], model.face_part[good]
    vertices = model.positions.astype(np.float64)
    height = (vertices - plane.point) @ plane.normal
    lowest, highest = _part_extremes(height[faces], part, count)
    whole = keep | (highest <= 0)  # parts without faces come out with neither
    sliced = ~whole & (lowest < 0) & (highest > 0)
    # the parts drawn as they are, a face a row in model order, on their own vertices
    flat = whole[part]
    used, at = renumbered(faces[flat].reshape(-1))
    at = at.reshape(-1, 3)
    pieces = [(vertices[used], at, part[flat])]
    caps = [_cap_faces(vertices[used], at, height[used], plane, eps) & ~keep[part[flat]]]
    offset = len(used)
    # the faces of the parts the plane runs through, a part at a time
    through = np.flatnonzero(sliced[part])
    for index, which in grouped(part[through]):
        mesh = _slice(_part_mesh(vertices, faces[through[which]]), plane, model.part_names[index])
        if len(mesh.faces) == 0:
            continue
        v = np.asarray(mesh.vertices, np.float64)
        f = np.asarray(mesh.faces, np.int64)
        pieces.append((v, f + offset, np.full(len(f), index, np.int32)))
        caps.append(_cap_faces(v, f, (v - plane.point) @ plane.normal, plane, eps))
        offset += len(v)
    cap = np.concatenate(caps)
    if not cap.any():
        low, high = model.bounds
        raise InputError(
            f"section {plane.text} misses the model (or cuts only parts kept whole): the model lies "
            f"within x {low[0]:g} to {high[0]:g}, y {low[1]:g} to {high[1]:g}, z {low[2]:g} to {high[2]:g}"
        )
    # the parts in model order, each one's faces in theirs
    face_part = np.concatenate([p for _, _, p in pieces]).astype(np.int32)
    order = np.argsort(face_part, kind="stable")
    cut = Model(
        np.ascontiguousarray(np.concatenate([v for v, _, _ in pieces]), np.float32),
        np.ascontiguousarray(np.concatenate([f for _, f, _ in pieces])[order], np.int32),
        face_part[order],
        model.part_names,
        model.up,
        model.source,
        unit=model.unit,
        unit_reason=model.unit_reason,
    )
    return Cut(cut, cap[order], plane, keep)


def _part_extremes(corner: np.ndarray, part: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """(count,) each: the least and the greatest of each part's faces' ``corner`` values ((F, 3)),
    +inf and -inf for a part without faces."""
    lowest, highest = np.full(count, np.inf), np.full(count, -np.inf)
    if len(part) == 0:
        return lowest, highest
    low, high = corner.min(axis=1), corner.max(axis=1)
    if (part[1:] >= part[:-1]).all():
        # faces in runs of a part, as loaders make them: one reduction a run
        starts = np.flatnonzero(np.r_[True, part[1:] != part[:-1]])
        lowest[part[starts]] = np.minimum.reduceat(low, starts)
        highest[part[starts]] = np.maximum.reduceat(high, starts)
    else:
        np.minimum.at(lowest, part, low)
        np.maximum.at(highest, part, high)
    return lowest, highest


def _part_mesh(vertices: np.ndarray, faces: np.ndarray):
    """A part's faces as a trimesh of its own vertices (``renumbered``: a table over the range
    of the vertices they use, or a sort of its corners, never a pass over every vertex of the
    model), merged where they coincide."""
    import trimesh

    used, at = renumbered(faces.reshape(-1))
    mesh = trimesh.Trimesh(vertices[used], at.reshape(-1, 3), process=True)
    mesh.remove_unreferenced_vertices()
    return mesh


# The shortest cross product of a face's edges that gives it a direction, as trimesh's face
# normals have it (shorter: a sliver of the slicing, no cap)
_NO_NORMAL = 1e-13


def _cap_faces(vertices: np.ndarray, faces: np.ndarray, height: np.ndarray, plane, eps: float) -> np.ndarray:
    """(F,) bool: faces that lie in the plane (every corner within ``eps``, ``height`` a
    vertex's) and face the side removed, that is, the camera: a cut's cap."""
    if len(faces) == 0:
        return np.zeros(0, bool)
    corner = vertices[faces]
    normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    length = np.linalg.norm(normal, axis=1)
    facing = (normal @ plane.normal > 0.99 * length) & (length > _NO_NORMAL)
    return (np.abs(height[faces]) <= eps).all(axis=1) & facing


def _slice(mesh, plane: SectionPlane, name: str):
    """The part behind the plane, which runs through it, capped; uncapped, with a warning,
    where the part is not a closed surface (its cut then has no inside to fill)."""
    import trimesh

    origin, inward = plane.point, -plane.normal
    if mesh.is_watertight:
        try:
            return trimesh.intersections.slice_mesh_plane(mesh, inward, origin, cap=True)
        except ValueError:
            pass  # a cut outline earcut cannot triangulate: cut without the cap
    log.warning("part %s is not a closed surface: its cut is not hatched", name)
    return trimesh.intersections.slice_mesh_plane(mesh, inward, origin, cap=False)
