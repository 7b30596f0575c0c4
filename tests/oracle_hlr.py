"""Exact hidden-line removal as an oracle for the drawings of STEP parts: Open CASCADE's
``HLRBRep_Algo`` (through the ``OCP`` bindings, a test extra) on the file's B-rep, for the named
orthographic views, sampled as 2-D polylines in the pixels of blueprint's SVG.

The views' directions and up vectors are written out here for Z-up models (STEP's convention),
not read from ``blueprint.scene.camera``; only the framing's input, the mesh blueprint draws (its
vertices' projected extents), comes from blueprint, since the fit is defined on those.

Lines come in classes ``(visibility, kind)``: visibility ``"visible"`` or ``"hidden"``, kind
``"sharp"`` (edges between faces meeting at an angle), ``"smooth"`` (tangent-continuous edges,
as where a fillet meets a face) or ``"outline"`` (silhouettes of curved faces, and the tangent
edges and seams that lie on them). Other seams of closed surfaces and iso-lines are left out: no
drawing has them.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import cache

import numpy as np
import shapely

VISIBILITIES = ("visible", "hidden")
KINDS = ("sharp", "smooth", "outline")

# towards the eye and the picture's right for a Z-up model, as a drawing's named views have them:
# the front looks along +Y, the top down -Z with the front at the bottom, iso from the front right
VIEW_AXES: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "top": ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),
    "front": ((0.0, -1.0, 0.0), (1.0, 0.0, 0.0)),
    "right": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "iso": ((1.0, -1.0, 1.0), (1.0, 1.0, 0.0)),
}
MARGIN = 0.05  # the fraction of the picture a drawing keeps free at each side


def have_ocp() -> bool:
    """Whether Open CASCADE's Python bindings can be imported."""
    try:
        import OCP.HLRBRep  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass
class HLRLines:
    """The exact drawing of one view: ``lines[(visibility, kind)]`` is a list of (N, 2) float64
    polylines in SVG pixels (x right, y down from the top-left corner)."""

    lines: dict[tuple[str, str], list[np.ndarray]] = field(default_factory=dict)

    def of(self, visibility: str, kinds=KINDS) -> list[np.ndarray]:
        """The polylines of one visibility and the given kinds."""
        return [line for kind in kinds for line in self.lines.get((visibility, kind), [])]


def read_step(path: str | os.PathLike):
    """(shape, metres per shape unit) of a STEP file read by Open CASCADE, which converts the
    file's unit to its own system unit (``SystemLengthUnit``, in millimetres)."""
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPControl import STEPControl_Reader

    reader = STEPControl_Reader()
    if reader.ReadFile(str(path)) != IFSelect_RetDone:
        raise ValueError(f"{path}: Open CASCADE cannot read it as STEP")
    reader.TransferRoots()
    return reader.OneShape(), reader.SystemLengthUnit() / 1000.0


def view_basis(view: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit (right, up, towards the eye) 3-vectors of a named view of a Z-up model."""
    toward, right = (np.array(v) / np.linalg.norm(v) for v in VIEW_AXES[view])
    return right, np.cross(toward, right), toward


def framing(positions: np.ndarray, view: str, size: tuple[int, int]) -> tuple[np.ndarray, float]:
    """(centre (2,) in view-plane model units, pixels per model unit) that fit ``positions``
    (N, 3), the drawn mesh's vertices, in a picture of ``size`` with ``MARGIN`` free at each side:
    centred on their projected extents, the wider of the two spans filling the rest."""
    right, up, _ = view_basis(view)
    plane = np.asarray(positions, np.float64) @ np.stack([right, up], axis=1)
    lo, hi = plane.min(axis=0), plane.max(axis=0)
    width, height = size
    span = max((hi[1] - lo[1]) / height, (hi[0] - lo[0]) / width) / (1 - 2 * MARGIN)
    return (lo + hi) / 2, 1.0 / span


def _edge_points(edge, deflection: float) -> np.ndarray:
    """(N, 3) points along an edge, no farther than ``deflection`` from the curve between them."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.GCPnts import GCPnts_QuasiUniformDeflection

    curve = BRepAdaptor_Curve(edge)
    points = GCPnts_QuasiUniformDeflection(curve, deflection)
    if not points.IsDone() or points.NbPoints() < 2:
        ends = (curve.FirstParameter(), curve.LastParameter())
        return np.array([curve.Value(t).Coord() for t in ends])
    return np.array([points.Value(i).Coord() for i in range(1, points.NbPoints() + 1)])


def _compound_lines(compound, deflection: float) -> list[np.ndarray]:
    """(N, 2) polylines of the edges of one of ``HLRBRep_HLRToShape``'s compounds (edges in the
    view plane, z = 0)."""
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    lines = []
    if not compound.IsNull():
        explorer = TopExp_Explorer(compound, TopAbs_EDGE)
        while explorer.More():
            lines.append(_edge_points(TopoDS.Edge(explorer.Current()), deflection)[:, :2])
            explorer.Next()
    return lines


def edges_on_outline(shape, view: str, deflection: float, samples: int = 5) -> list[np.ndarray]:
    """(N, 2) view-plane polylines of the edges of ``shape`` along which a face they bound turns
    edge-on to the view (its normal perpendicular to the view direction at ``samples`` points):
    the outline there runs along the edge, and ``HLRBRep`` reports that line as the edge, a seam
    or a tangent edge, not as outline."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d, BRepAdaptor_Surface
    from OCP.gp import gp_Pnt, gp_Vec
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    right, up, toward = view_basis(view)
    found = []
    faces = TopExp_Explorer(shape, TopAbs_FACE)
    while faces.More():
        face = TopoDS.Face(faces.Current())
        surface = BRepAdaptor_Surface(face)
        edges = TopExp_Explorer(face, TopAbs_EDGE)
        while edges.More():
            edge = TopoDS.Edge(edges.Current())
            pcurve = BRepAdaptor_Curve2d(edge, face)
            normals = []
            for t in np.linspace(pcurve.FirstParameter(), pcurve.LastParameter(), samples):
                uv = pcurve.Value(float(t))
                point, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
                surface.D1(uv.X(), uv.Y(), point, du, dv)
                normals.append(np.cross(du.Coord(), dv.Coord()))
            normals = np.array(normals)
            lengths = np.linalg.norm(normals, axis=1)
            if (lengths > 0).all() and (np.abs(normals @ toward) <= 1e-9 * lengths).all():
                found.append(_edge_points(edge, deflection) @ np.stack([right, up], axis=1))
            edges.Next()
        faces.Next()
    return found


def hidden_lines(shape, view: str, deflection: float) -> dict[tuple[str, str], list[np.ndarray]]:
    """Exact hidden-line removal of ``shape`` seen from ``view``: ``{(visibility, kind): (N, 2)
    polylines}`` in the view plane (right, up), in the shape's units, each within ``deflection``
    of the exact projected curve. A seam or tangent edge lying on the outline (``edges_on_outline``)
    counts as outline; other seams are left out."""
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt
    from OCP.HLRAlgo import HLRAlgo_Projector
    from OCP.HLRBRep import HLRBRep_Algo, HLRBRep_HLRToShape

    right, _, toward = view_basis(view)
    algo = HLRBRep_Algo()
    algo.Add(shape)
    # the projector's axis points at the eye and its X direction is the picture's right
    algo.Projector(HLRAlgo_Projector(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(*toward), gp_Dir(*right))))
    algo.Update()
    algo.Hide()
    result = HLRBRep_HLRToShape(algo)
    on_outline = edges_on_outline(shape, view, deflection)
    found: dict[tuple[str, str], list[np.ndarray]] = {}
    for visibility in VISIBILITIES:
        suffix = "VCompound" if visibility == "visible" else "HCompound"

        def lines(prefix: str, suffix=suffix) -> list[np.ndarray]:
            return _compound_lines(getattr(result, prefix + suffix)(), deflection)

        # a line of the result lies on an outline edge, all along it, to within the sampling
        # of both
        def on(line: np.ndarray) -> bool:
            length = np.linalg.norm(np.diff(line, axis=0), axis=1).sum()
            along = resample([line], max(length, deflection) / 16)
            return bool(distances(along, on_outline).max() <= 2 * deflection)

        tangent, seams = lines("Rg1Line"), lines("RgNLine")
        found[(visibility, "sharp")] = lines("")
        found[(visibility, "outline")] = lines("OutLine") + [line for line in tangent + seams if on(line)]
        found[(visibility, "smooth")] = [line for line in tangent if not on(line)]
    return found


@cache
def model_of(path: str):
    """The ``blueprint.Model`` blueprint makes of a file, loaded once a session."""
    import blueprint

    return blueprint.load_model(path)


@cache
def _step(path: str):
    """``read_step``, once a session: Open CASCADE reads a file once for all its views."""
    return read_step(path)


def _picture(path: str, view: str, size: tuple[int, int]):
    """(shape, deflection, to_pixels) of the STEP file at ``path`` seen from ``view``, framed as
    blueprint frames the mesh it makes of the file (``model_of``): its shape, a hundredth of a
    pixel in the shape's units (polylines that near stand for the exact curves at the tests'
    scale), and the map from (N, 2) view-plane points in those units to the picture's pixels."""
    shape, metres = _step(path)
    centre, scale = framing(model_of(path).positions, view, size)
    width, height = size
    half = np.array([width / 2, height / 2])
    flip = np.array([1.0, -1.0])

    def to_pixels(points: np.ndarray) -> np.ndarray:
        return half + (points * metres - centre) * scale * flip

    return shape, 0.01 / (scale * metres), to_pixels


@cache
def oracle(path: str, view: str, size: tuple[int, int] = (1024, 1024)) -> HLRLines:
    """The exact drawing of the STEP file at ``path`` from ``view``, orthographic, framed as
    blueprint frames the mesh it makes of the file (``model_of``), in that picture's pixels;
    cached per (file, view, size) for the session."""
    shape, deflection, to_pixels = _picture(path, view, size)
    plane = hidden_lines(shape, view, deflection)
    return HLRLines({key: [to_pixels(line) for line in lines] for key, lines in plane.items()})


def edge_in_picture(path: str, view: str, size: tuple[int, int], chosen) -> np.ndarray:
    """(N, 2) pixels, within a hundredth of a pixel, of the one edge of the STEP file's shape
    that ``chosen(face, edge)`` (``TopoDS`` objects) accepts, in the picture ``oracle`` draws."""
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    shape, deflection, to_pixels = _picture(path, view, size)
    right, up, _ = view_basis(view)
    found = []
    faces = TopExp_Explorer(shape, TopAbs_FACE)
    while faces.More():
        face = TopoDS.Face(faces.Current())
        edges = TopExp_Explorer(face, TopAbs_EDGE)
        while edges.More():
            edge = TopoDS.Edge(edges.Current())
            if chosen(face, edge):
                found.append(edge)
            edges.Next()
        faces.Next()
    if len(found) != 1:
        raise ValueError(f"{path}: {len(found)} edges chosen, not one")
    return to_pixels(_edge_points(found[0], deflection) @ np.stack([right, up], axis=1))


def resample(polylines: list[np.ndarray], spacing: float) -> np.ndarray:
    """(M, 2) points along polylines, one every ``spacing`` of arc length (both ends of each
    segment's run included), so counting points weighs lines by their length."""
    out = []
    for line in polylines:
        step = np.linalg.norm(np.diff(line, axis=0), axis=1)
        arc = np.r_[0.0, np.cumsum(step)]
        if arc[-1] == 0:
            continue
        at = np.linspace(0.0, arc[-1], max(int(np.ceil(arc[-1] / spacing)), 1) + 1)
        out.append(np.stack([np.interp(at, arc, line[:, 0]), np.interp(at, arc, line[:, 1])], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2))


def distances(points: np.ndarray, polylines: list[np.ndarray]) -> np.ndarray:
    """(M,) exact distance from each 2-D point to the nearest of ``polylines`` (inf if none)."""
    if len(points) == 0:
        return np.zeros(0)
    lines = [shapely.linestrings(p) for p in polylines if len(p) >= 2]
    if not lines:
        return np.full(len(points), np.inf)
    tree = shapely.STRtree(lines)
    (which, _), found = tree.query_nearest(shapely.points(points), return_distance=True, all_matches=False)
    out = np.full(len(points), np.inf)
    out[which] = found
    return out
