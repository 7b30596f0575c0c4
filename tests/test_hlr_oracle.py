"""Drawings of STEP parts against exact hidden-line removal (tests/oracle_hlr.py: Open CASCADE's
``HLRBRep_Algo`` on the file's B-rep), issue 39.

``blueprint render PART.STEP -o part.svg --view V --ortho --size 1024 1024`` (drawn in this
process through ``render_vector_file``, the command's own function, with each model loaded once;
one case checks that the command writes the same file); the SVG's polylines by class (level 0
visible, deeper levels hidden) against the oracle's of the same class, both sampled every half
pixel of arc length, at 1 px:

* recall: the share of the oracle's sharp edges and outlines within 1 px of the drawing's lines.
  Tangent edges (where a fillet meets a face) are left out: a drawing may draw them or not.
  Hidden lines within 1 px of a visible line of the oracle are left out too: the drawing drops
  hidden lines lying under visible ones on purpose.
* precision: the share of the drawing's lines within 1 px of the oracle's (tangent edges
  included).

Targets (issue 39): visible recall and precision >= 0.995, hidden >= 0.99. A case below them
today is marked ``xfail(strict=True)`` with its measured figure (benchmarks/notes/hlr-oracle.md
lists every case's), so it shows up both when it fails and when a fix lifts it over the target.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest
import shapely
from helpers import needs_cli, run_cli
from oracle_hlr import distances, edge_in_picture, have_ocp, model_of, oracle, resample
from vector_helpers import svg_lines

from blueprint.api.files import render_vector_file

pytestmark = pytest.mark.skipif(
    not have_ocp(), reason="Open CASCADE's Python bindings (cadquery-ocp-novtk, a test extra) are absent"
)

SIZE = (1024, 1024)
TOLERANCE = 1.0  # pixels
SPACING = 0.5  # pixels of arc length between samples
TARGETS = {
    "visible recall": 0.995,
    "visible precision": 0.995,
    "hidden recall": 0.99,
    "hidden precision": 0.99,
}
VIEWS = ("top", "front", "right", "iso")
SHARED = {"featuretype": "trimesh/featuretype.STEP", "box_sides": "trimesh/box_sides.STEP"}
GENERATED = ("block", "bracket")

# (model, view, measure): the figure measured below its target on llvmpipe, at the commit that
# added this test; issue 39 names the causes (benchmarks/notes/hlr-oracle.md)
BELOW_TARGET: dict[tuple[str, str, str], float] = {}


# -- generated parts: Open CASCADE's own modelling, written as STEP ------------------------------
def _box(x, y, z, dx, dy, dz):
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.gp import gp_Pnt

    return BRepPrimAPI_MakeBox(gp_Pnt(x, y, z), dx, dy, dz).Shape()


def _cylinder(x, y, z, radius, height, axis=(0.0, 0.0, 1.0)):
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(x, y, z), gp_Dir(*axis)), radius, height).Shape()


def _cut(shape, *tools):
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut

    for tool in tools:
        shape = BRepAlgoAPI_Cut(shape, tool).Shape()
    return shape


def _fillet(shape, radius: float, chosen) -> object:
    """``shape`` with the straight edges whose two ends ``chosen(a, b)`` accepts rounded (the
    fillet runs on along edges tangent to them)."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
    from OCP.GeomAbs import GeomAbs_Line
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    maker = BRepFilletAPI_MakeFillet(shape)
    explorer = TopExp_Explorer(shape, TopAbs_EDGE)
    while explorer.More():
        edge = TopoDS.Edge(explorer.Current())
        curve = BRepAdaptor_Curve(edge)
        ends = [np.array(curve.Value(t).Coord()) for t in (curve.FirstParameter(), curve.LastParameter())]
        if curve.GetType() == GeomAbs_Line and chosen(*ends):
            maker.Add(radius, edge)
        explorer.Next()
    return maker.Shape()


def block():
    """An 80 x 50 x 20 mm plate: vertical corners rounded (r 6), its top rim rounded (r 4), two
    through holes, a blind hole, a through slot with round ends and a cross hole along x."""
    shape = _box(0, 0, 0, 80, 50, 20)
    shape = _fillet(shape, 6.0, lambda a, b: np.allclose(a[:2], b[:2]))
    shape = _fillet(shape, 4.0, lambda a, b: a[2] == b[2] == 20 and a[1] == b[1] == 0)
    return _cut(
        shape,
        _cylinder(15, 35, -1, 5, 22),
        _cylinder(65, 35, -1, 5, 22),
        _cylinder(40, 38, 8, 4, 13),
        _box(28, 14, -1, 24, 8, 22),
        _cylinder(28, 18, -1, 4, 22),
        _cylinder(52, 18, -1, 4, 22),
        _cylinder(-1, 8, 8, 3, 82, axis=(1.0, 0.0, 0.0)),
    )


def bracket():
    """A 60 x 40 x 40 mm L bracket: a base with a counterbored hole and a pocket, an upright with
    a cross hole, the inside of the L's corner rounded (r 5)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse

    shape = BRepAlgoAPI_Fuse(_box(0, 0, 0, 60, 40, 10), _box(0, 30, 0, 60, 10, 40)).Shape()
    shape = _fillet(shape, 5.0, lambda a, b: a[1] == b[1] == 30 and a[2] == b[2] == 10)
    return _cut(
        shape,
        _cylinder(15, 15, -1, 4, 12),
        _cylinder(15, 15, 6, 7, 5),
        _box(32, 6, 5, 20, 14, 6),
        _cylinder(30, 29, 28, 6, 12, axis=(0.0, 1.0, 0.0)),
    )


def write_step(shape, path: Path, unit: str = "MM") -> Path:
    """``shape`` (in millimetres) written to ``path`` as STEP in ``unit`` (Open CASCADE's names:
    MM, M, IN, ...)."""
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    previous = Interface_Static.CVal_s("write.step.unit")
    Interface_Static.SetCVal_s("write.step.unit", unit)
    try:
        writer = STEPControl_Writer()
        writer.Transfer(shape, STEPControl_AsIs)
        assert writer.Write(str(path)) == IFSelect_RetDone
    finally:
        Interface_Static.SetCVal_s("write.step.unit", previous)
    return path


@pytest.fixture(scope="session")
def generated_parts(tmp_path_factory) -> dict[str, Path]:
    """The generated parts as STEP files, the bracket in inches (the oracle scales each file's
    unit to blueprint's metres)."""
    folder = tmp_path_factory.mktemp("hlr-parts")
    return {
        "block": write_step(block(), folder / "block.step"),
        "bracket": write_step(bracket(), folder / "bracket.step", unit="IN"),
    }


# -- the measure ---------------------------------------------------------------------------------
def share_within(d: np.ndarray) -> float:
    """The share of distances within ``TOLERANCE``; 1.0 where there is nothing to measure."""
    return float((d <= TOLERANCE).mean()) if len(d) else 1.0


def figures(svg: Path, path: Path, view: str) -> dict[str, float]:
    """Recall and precision of a drawing's visible and hidden lines against the oracle's."""
    exact = oracle(str(path), view, SIZE)
    drawn = svg_lines(svg)
    visible = [line for (_, level), lines in drawn.items() if level == 0 for line in lines]
    hidden = [line for (_, level), lines in drawn.items() if level > 0 for line in lines]
    wanted_visible = resample(exact.of("visible", ("sharp", "outline")), SPACING)
    wanted_hidden = resample(exact.of("hidden", ("sharp", "outline")), SPACING)
    wanted_hidden = wanted_hidden[distances(wanted_hidden, exact.of("visible")) > TOLERANCE]
    return {
        "visible recall": share_within(distances(wanted_visible, visible)),
        "visible precision": share_within(distances(resample(visible, SPACING), exact.of("visible"))),
        "hidden recall": share_within(distances(wanted_hidden, hidden)),
        "hidden precision": share_within(distances(resample(hidden, SPACING), exact.of("hidden"))),
    }


@pytest.fixture(scope="session")
def drawn(tmp_path_factory, renderer):
    """``drawn(path, view)``: the SVG blueprint draws of a STEP file, once per (file, view) in the
    session."""
    folder = tmp_path_factory.mktemp("hlr-svg")

    @cache
    def draw(path: Path, view: str) -> Path:
        svg = folder / f"{path.stem}-{view}.svg"
        render_vector_file(model_of(str(path)), svg, view=view, ortho=True, size=SIZE, renderer=renderer)
        return svg

    return draw


@pytest.fixture(scope="session")
def measure(drawn):
    """``measure(path, view)``: ``figures`` of a drawing, once per (file, view) in the session."""

    @cache
    def measured(path: Path, view: str) -> dict[str, float]:
        return figures(drawn(path, view), path, view)

    return measured


def _cases():
    for model in (*SHARED, *GENERATED):
        for view in VIEWS:
            for name, target in TARGETS.items():
                below = BELOW_TARGET.get((model, view, name))
                marks = ()
                if below is not None:
                    reason = f"issue 39: {model} {view} {name} measured {below:.4f} < {target}"
                    marks = pytest.mark.xfail(strict=True, reason=reason)
                yield pytest.param(
                    model, view, name, marks=marks, id=f"{model}-{view}-{name.replace(' ', '-')}"
                )


@pytest.mark.parametrize(("model", "view", "name"), list(_cases()))
def test_drawing_matches_exact_hidden_lines(model, view, name, measure, request):
    if model in SHARED:
        path = request.getfixturevalue("shared_models") / SHARED[model]
    else:
        path = request.getfixturevalue("generated_parts")[model]
    figure = measure(path, view)[name]
    assert figure >= TARGETS[name], f"{model} {view}: {name} {figure:.4f} < {TARGETS[name]}"


@needs_cli
def test_the_command_writes_the_same_drawing(shared_models, drawn, tmp_path):
    path = shared_models / SHARED["featuretype"]
    svg = tmp_path / "featuretype-iso.svg"
    proc = run_cli("render", path, "-o", svg, "--view", "iso", "--ortho", "--size", *SIZE)
    assert proc.returncode == 0, proc.stderr
    assert svg.read_bytes() == drawn(path, "iso").read_bytes()


def _highest_curve_of_spline_face(face, edge) -> bool:
    """Whether ``edge`` is the upper of the B-spline edges of a B-spline face: the top edge of
    featuretype's S-shaped pocket wall, the part's one such face."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_BSplineCurve, GeomAbs_BSplineSurface
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    def height(e) -> float | None:
        curve = BRepAdaptor_Curve(e)
        if curve.GetType() != GeomAbs_BSplineCurve:
            return None
        return curve.Value(curve.FirstParameter()).Z()

    if BRepAdaptor_Surface(face).GetType() != GeomAbs_BSplineSurface or height(edge) is None:
        return False
    heights = []
    explorer = TopExp_Explorer(face, TopAbs_EDGE)
    while explorer.More():
        heights.append(height(TopoDS.Edge(explorer.Current())))
        explorer.Next()
    return height(edge) == max(h for h in heights if h is not None)


def test_the_pocket_walls_top_edge_is_whole_from_the_top(shared_models, drawn):
    """featuretype.STEP from the top: the S-shaped pocket wall is seen edge-on, and its top edge
    comes out as visible lines that run its whole length within 1 px of it, with no gap
    along it over 1 px (issue 39, point 5)."""
    path = shared_models / SHARED["featuretype"]
    edge = edge_in_picture(str(path), "top", SIZE, _highest_curve_of_spline_face)
    drawing = svg_lines(drawn(path, "top"))
    visible = [line for (_, level), lines in drawing.items() if level == 0 for line in lines]
    # every point of the edge is near a visible line
    assert distances(resample([edge], 0.25), visible).max() <= TOLERANCE
    # and the visible lines near it and along it leave no stretch of it out: where each of their
    # points lies along the edge (its arc length), from points a quarter pixel apart
    exact = shapely.linestrings(edge)
    near = []
    for line in visible:
        points = resample([line], 0.25)
        step = np.diff(points, axis=0)
        keep = np.linalg.norm(step, axis=1) > 0
        points, step = points[:-1][keep], step[keep] / np.linalg.norm(step[keep], axis=1)[:, None]
        at = shapely.line_locate_point(exact, shapely.points(points))
        ahead = shapely.get_coordinates(shapely.line_interpolate_point(exact, at + 0.1))
        behind = shapely.get_coordinates(shapely.line_interpolate_point(exact, at - 0.1))
        tangent = (ahead - behind) / np.linalg.norm(ahead - behind, axis=1)[:, None]
        along = np.abs(np.einsum("ij,ij->i", step, tangent)) > np.cos(np.radians(30))
        close = shapely.distance(exact, shapely.points(points)) <= TOLERANCE
        near.append(at[along & close])
    at = np.sort(np.concatenate(near))
    length = exact.length
    assert length > 300  # the edge runs 328 px from the top
    covered = np.r_[0.0, at, length]
    assert np.diff(covered).max() <= TOLERANCE, f"a gap of {np.diff(covered).max():.2f} px at {at}"


# -- the oracle itself ---------------------------------------------------------------------------
def _on_box_or_circle(points, corners, centre, radius) -> np.ndarray:
    """Distance of (M, 2) points to the nearest of a rectangle's sides and a circle."""
    (x0, y0), (x1, y1) = corners
    px, py = points[:, 0], points[:, 1]
    beyond_x = np.maximum.reduce([x0 - px, px - x1, np.zeros(len(px))])
    beyond_y = np.maximum.reduce([y0 - py, py - y1, np.zeros(len(py))])
    sides = np.stack(
        [
            np.hypot(px - x0, beyond_y),
            np.hypot(px - x1, beyond_y),
            np.hypot(beyond_x, py - y0),
            np.hypot(beyond_x, py - y1),
            np.abs(np.linalg.norm(points - centre, axis=1) - radius),
        ]
    )
    return sides.min(axis=0)


def test_oracle_draws_a_holed_plate_where_its_geometry_says(tmp_path):
    """A 40 x 20 x 10 mm plate (written in metres) with a 4 mm hole through its middle: the plate
    fills 90 % of 1024 px across, 23.04 px a millimetre, centred. From the top: the rim and the
    hole's circle visible, the bottom ones hidden beneath them; from the front: the hole's
    outlines hidden, 92.16 px either side of the middle."""
    plate = write_step(
        _cut(_box(-20, -10, 0, 40, 20, 10), _cylinder(0, 0, -1, 4, 12)), tmp_path / "p.step", "M"
    )
    mm = 1024 * 0.9 / 40
    centre = np.array([512.0, 512.0])

    top = oracle(str(plate), "top", SIZE)
    corners = (centre - [20 * mm, 10 * mm], centre + [20 * mm, 10 * mm])
    for visibility in ("visible", "hidden"):
        points = resample(top.of(visibility), SPACING)
        # the circle's polyline keeps within 0.01 px of it (oracle_hlr's deflection), the rest
        # within the float32 rounding of the mesh that frames the view
        assert _on_box_or_circle(points, corners, centre, 4 * mm).max() < 0.0101
        # the rectangle and the circle, once each
        length = 2 * (60 * mm) + 2 * np.pi * 4 * mm
        drawn = sum(np.linalg.norm(np.diff(line, axis=0), axis=1).sum() for line in top.of(visibility))
        assert drawn == pytest.approx(length, rel=1e-4)
    assert top.of("visible", ("outline", "smooth")) == []

    front = oracle(str(plate), "front", SIZE)
    # the hole's sides: one an outline, the other its seam, which HLRBRep reports as an edge
    inside = [
        line
        for line in front.of("hidden", ("sharp", "outline"))
        if np.ptp(line[:, 0]) < 1e-4 and 100 < line[0, 0] < 900
    ]
    assert sorted(float(line[:, 0].mean()) for line in inside) == pytest.approx(
        [512 - 4 * mm, 512 + 4 * mm], abs=1e-4
    )
    for line in inside:
        assert sorted(line[[0, -1], 1]) == pytest.approx([512 - 5 * mm, 512 + 5 * mm], abs=1e-4)
    # from the right, the seam runs down the middle of the hole's side: no line of a drawing
    right = oracle(str(plate), "right", SIZE)
    upright = [line for line in right.of("visible") + right.of("hidden") if np.ptp(line[:, 0]) < 1e-4]
    assert len(upright) > 2
    assert not [line for line in upright if abs(line[0, 0] - 512) < 1]


def test_distances_are_to_the_nearest_segment():
    polylines = [np.array([[0.0, 0.0], [10.0, 0.0]]), np.array([[0.0, 5.0], [0.0, 9.0]])]
    points = np.array([[5.0, 1.0], [-3.0, 0.0], [1.0, 7.0], [0.0, 4.0]])
    assert distances(points, polylines) == pytest.approx([1.0, 3.0, 1.0, 1.0])
    assert np.isinf(distances(points, [])).all()
