"""Section views: the cut on the CPU against analytic areas, the raster hatching from the first
layer's triangle IDs, the vector hatching and outline as their own groups, and bad input."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import shapely.geometry as sg
import trimesh
from helpers import no_output, one_error, run_cli

import blueprint
from blueprint.api.files import render_vector_file
from blueprint.compose.hatch import HATCH_PATTERNS, hatch_overlay, hatch_patterns
from blueprint.errors import InputError
from blueprint.scene.camera import fit_camera
from blueprint.scene.model import Model
from blueprint.scene.section import cut_model, parse_section
from blueprint.vector.drawing import draw_vector

SVG = "{http://www.w3.org/2000/svg}"
# a 40 x 30 x 20 block with a vertical hole of radius 8 through its middle
W, D, H, R = 40.0, 30.0, 20.0, 8.0
CUT_AREA = W * D - math.pi * R * R  # across z: the block's face less the hole


def block_with_hole() -> trimesh.Trimesh:
    outline = sg.box(-W / 2, -D / 2, W / 2, D / 2).difference(sg.Point(0, 0).buffer(R, quad_segs=64))
    return trimesh.creation.extrude_polygon(outline, H)


@pytest.fixture(scope="module")
def block() -> Model:
    mesh = block_with_hole()
    return Model.from_arrays(mesh.vertices, mesh.faces, part_names=["block"], up="z")


@pytest.fixture(scope="module")
def two_parts(tmp_path_factory):
    """The block and a post beside it whose cut faces touch the block's (a GLB, Z up)."""
    post = trimesh.creation.box((10.0, 10.0, 40.0))
    post.apply_translation((W / 2 + 5.0, 0.0, 10.0))
    path = tmp_path_factory.mktemp("section") / "two.glb"
    trimesh.Scene({"block": block_with_hole(), "post": post}).export(path)
    return path


def top_cut(model: Model, z: float = 10.0, keep=None):
    plane = parse_section(f"z={z}").facing((0.0, 0.0, 100.0), (0.0, 0.0, 0.0))
    return cut_model(model, plane, keep)


# -- the plane -----------------------------------------------------------------------------------


def test_section_forms():
    plane = parse_section("y = -2.5")
    assert plane.axis == "y" and plane.point.tolist() == [0, -2.5, 0] and plane.normal.tolist() == [0, 1, 0]
    plane = parse_section(None, "1,2,3,0,0,-2")
    assert plane.axis is None and plane.point.tolist() == [1, 2, 3] and plane.normal.tolist() == [0, 0, -1]
    assert parse_section(None, None) is None


def test_axis_section_removes_the_side_facing_the_camera():
    plane = parse_section("x=1")
    assert plane.facing((-5, 0, 0), (0, 0, 0)).normal.tolist() == [-1, 0, 0]
    assert plane.facing((5, 1, 1), (0, 0, 0)).normal.tolist() == [1, 0, 0]
    # seen edge-on, the positive side goes
    assert plane.facing((0, -5, 0), (0, 0, 0)).normal.tolist() == [1, 0, 0]


@pytest.mark.parametrize(
    "section, plane, message",
    [
        ("x", None, "section 'x' is not of the form x=VALUE, y=VALUE or z=VALUE"),
        ("w=3", None, "section 'w=3' is not of the form"),
        ("x=nan", None, "section 'x=nan' is not of the form"),
        ("x=1", "0,0,0,1,0,0", "give --section or --section-plane, not both"),
        (None, "0,0,0,1,0", "section plane '0,0,0,1,0' is not 6 numbers (give PX,PY,PZ,NX,NY,NZ"),
        (None, "0,0,0,a,b,c", "is not 6 numbers"),
        (None, "0,0,0,0,0,0", "section plane '0,0,0,0,0,0' has no normal"),
    ],
)
def test_bad_section_is_one_clear_message(section, plane, message):
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        parse_section(section, plane)


# -- the cut -------------------------------------------------------------------------------------


def test_cut_faces_have_the_analytic_area(block):
    cut = top_cut(block)
    # the hole is a 256-gon: its area is within 0.01 % of the circle's
    assert cut.cap_area() == pytest.approx(CUT_AREA, rel=1e-3)
    assert cut.model.bounds[1, 2] == pytest.approx(10.0, abs=1e-5)
    assert cut.model.bounds[0, 2] == pytest.approx(0.0, abs=1e-5)
    capped = cut.model.positions[cut.model.faces[cut.cap]]
    assert np.allclose(capped[..., 2], 10.0, atol=1e-5)


def test_cut_model_holds_the_volume_behind_the_plane(block):
    cut = top_cut(block)
    mesh = trimesh.Trimesh(cut.model.positions.astype(np.float64), cut.model.faces)
    assert mesh.volume == pytest.approx(CUT_AREA * 10.0, rel=1e-3)


def test_plane_missing_the_model(block):
    with pytest.raises(InputError, match=r"section z=25 misses the model .* z 0 to 20"):
        top_cut(block, 25.0)
    # everything is in front of the plane
    with pytest.raises(InputError, match="misses the model"):
        top_cut(block, -1.0)


def test_kept_parts_stay_whole(two_parts):
    model = blueprint.load_model(two_parts)
    post = model.part_names.index("post")
    keep = np.zeros(len(model.part_names), bool)
    keep[post] = True
    cut = top_cut(model, 10.0, keep)
    assert cut.cap_parts().tolist() == [model.part_names.index("block")]
    faces = cut.model.face_part == post
    assert faces.sum() == (model.face_part == post).sum()
    assert cut.model.positions[cut.model.faces[faces]][..., 2].max() == pytest.approx(30.0)
    with pytest.raises(InputError, match="misses the model"):
        top_cut(model, 25.0, keep)  # above the block, only the post is there, and it is kept


def test_a_plane_through_a_few_parts_of_many_slices_those_alone(monkeypatch):
    """200 unit cubes in a row along x, a plane at x = 10.5 (its normal +x): the 10 cubes behind
    it pass through whole, the 189 in front are dropped, and the one it runs through alone is
    sliced and capped (a 1 x 1 cap at the plane), its faces in part order."""
    from blueprint.examples import assemble, box
    from blueprint.scene import section

    model = assemble({f"cube{k:03d}": box((k, 0, 0), (k + 0.75, 1, 1)) for k in range(200)}, up="z")
    sliced = []
    made = section._part_mesh

    def counted(vertices, faces):
        sliced.append(len(faces))
        return made(vertices, faces)

    monkeypatch.setattr(section, "_part_mesh", counted)
    plane = parse_section("x=10.5").facing((100.0, 0.5, 0.5), (0.0, 0.5, 0.5))
    cut = cut_model(model, plane)
    assert sliced == [12]
    parts = np.unique(cut.model.face_part)
    assert parts.tolist() == list(range(11))
    assert (np.diff(cut.model.face_part) >= 0).all()
    for k in range(10):
        assert (cut.model.face_part == k).sum() == 12
    assert cut.cap_parts().tolist() == [10]
    assert cut.cap_area() == pytest.approx(1.0)
    assert cut.model.bounds[1, 0] == pytest.approx(10.5)
    # the vertices the whole cubes use, and no others
    assert len(cut.model.positions) == len(np.unique(cut.model.faces))


# -- raster --------------------------------------------------------------------------------------


def test_raster_hatched_area_matches_the_analytic_area(renderer, block):
    size = (600, 600)
    camera = fit_camera(block, size, "top", ortho=True)
    cut = top_cut(block)
    tri = renderer.peel(cut.model, camera, size=size, max_layers=1, normals=False).triangle[0]
    hatched = (tri >= 0) & cut.cap[np.maximum(tri, 0)]
    per_px = camera.height / size[1]
    assert hatched.sum() * per_px**2 == pytest.approx(CUT_AREA, rel=0.01)


def test_raster_section_draws_hatching_only_on_the_cut(renderer, block):
    size = (300, 300)
    plain = blueprint.render(block, size=size, view="top", ortho=True, renderer=renderer)
    cut = top_cut(block)
    drawn_cut = blueprint.render(cut.model, size=size, view="top", ortho=True, renderer=renderer)
    image = blueprint.render(block, size=size, view="top", ortho=True, section="z=10", renderer=renderer)
    camera = fit_camera(block, size, "top", ortho=True)
    tri = renderer.peel(cut.model, camera, size=size, max_layers=1, normals=False).triangle[0]
    on_cap = (tri >= 0) & cut.cap[np.maximum(tri, 0)]
    # from the top the cut model looks like the whole block; outside the cut (and the outline
    # around it) the section is that drawing
    assert np.abs(plain.astype(int) - drawn_cut.astype(int)).max() <= 64
    from scipy import ndimage

    away = ~ndimage.binary_dilation(on_cap, iterations=3)
    assert np.array_equal(image[away], drawn_cut[away])
    # inside, the hatching inks a share of the cut near its line width over the spacing
    changed = np.abs(image.astype(int) - drawn_cut.astype(int)).max(axis=2) > 40
    inner = ndimage.binary_erosion(on_cap, iterations=4)
    share = changed[inner].mean()
    spacing = max(5.0, 300 / 90)
    assert 0.6 / spacing < share < 2.0 / spacing


def test_hatch_lines_run_at_45_degrees():
    tri = np.full((40, 40), -1, np.int32)
    tri[5:35, 5:35] = 0
    image = np.zeros((40, 40, 4), np.uint8)
    out = hatch_overlay(
        image, tri, np.zeros(1, np.int32), np.ones(1, bool), (1, 1, 1, 1), spacing=2 * math.sqrt(2)
    )
    inked = out[..., 3] > 127
    # the outline, two pixels wide, straddles the cut's edge; nothing further out is inked
    near = np.zeros_like(inked)
    near[4:36, 4:36] = True
    assert not inked[~near].any()
    assert inked[4:6, 5:35].all() and inked[34:36, 5:35].all() and inked[5:35, 4:6].all()
    inside = inked[8:32, 8:32]
    # lines at 45° spaced 2√2 apart cross a row every 4 pixels and move one pixel a row
    assert np.array_equal(inside[:, :-4], inside[:, 4:])
    assert np.array_equal(inside[1:, :-1], inside[:-1, 1:])
    assert 0.2 <= inside.mean() <= 0.5


def test_touching_parts_get_different_patterns():
    image = np.full((10, 30), -1)
    image[:, 0:10], image[:, 10:20], image[:, 22:30] = 3, 5, 7
    chosen = hatch_patterns(image, np.array([3, 5, 7]))
    assert chosen[3] != chosen[5]
    assert chosen[7] == chosen[3] == 0  # 7 touches nothing
    assert HATCH_PATTERNS[chosen[3]] != HATCH_PATTERNS[chosen[5]]


# -- vectors -------------------------------------------------------------------------------------


def test_vector_hatched_area_and_spacing(renderer, block):
    size = (500, 500)
    camera = fit_camera(block, size, "top", ortho=True)
    cut = top_cut(block)
    drawing = draw_vector(cut.model, camera, size, renderer=renderer, section=cut)
    per_px = camera.height / size[1]
    section = drawing.section
    assert section.area[0] * per_px**2 == pytest.approx(CUT_AREA, rel=0.01)
    # parallel lines ``spacing`` apart: their length times the spacing is the area they fill
    length = np.linalg.norm(section.hatch[:, 1] - section.hatch[:, 0], axis=1).sum()
    spacing = max(5.0, 500 / 90)
    assert length * spacing == pytest.approx(section.area[0], rel=0.03)
    # the outline is the block's rectangle and the hole's polygon
    outline = np.linalg.norm(section.outline[:, 1] - section.outline[:, 0], axis=1).sum()
    assert outline * per_px == pytest.approx(2 * (W + D) + 2 * math.pi * R, rel=0.01)
    directions = section.hatch[:, 1] - section.hatch[:, 0]
    assert np.allclose(np.abs(directions[:, 0]), np.abs(directions[:, 1]))


def test_svg_pdf_dxf_have_a_section_group(renderer, two_parts, tmp_path):
    import ezdxf
    from pypdf import PdfReader

    options = dict(view="top", ortho=True, section="z=10", up="z", size=(400, 400), renderer=renderer)
    render_vector_file(two_parts, tmp_path / "s.svg", **options)
    root = ET.parse(tmp_path / "s.svg").getroot()
    group = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "section")
    classes = sorted(p.get("class") for p in group.iter(f"{SVG}path"))
    assert classes == ["section-hatch", "section-outline"]
    widths = {p.get("class"): float(p.get("stroke-width")) for p in group.iter(f"{SVG}path")}
    assert widths["section-outline"] > 2 * widths["section-hatch"]

    render_vector_file(two_parts, tmp_path / "s.dxf", **options)
    doc = ezdxf.readfile(tmp_path / "s.dxf")
    lines = doc.modelspace().query('LINE[layer=="SECTION"]')
    assert len(lines) > 50
    cut, camera = _cut_two(two_parts)
    # the same lines, drawn without a file
    drawing = draw_vector(cut.model, camera, (400, 400), renderer=renderer, section=cut)
    assert len(lines) == len(drawing.section.hatch) + len(drawing.section.outline)

    render_vector_file(two_parts, tmp_path / "s.pdf", **options)
    content = PdfReader(tmp_path / "s.pdf").pages[0].get_contents().get_data().decode("latin-1")
    assert content.count(" l S") + content.count(" l\nS") >= len(drawing.section.hatch)


def _cut_two(path):
    model = blueprint.load_model(path, up="z")
    camera = fit_camera(model, (400, 400), "top", ortho=True)
    return cut_model(model, parse_section("z=10").facing(camera.eye, camera.target)), camera


def test_adjacent_parts_hatched_differently_in_vectors(renderer, two_parts):
    model = blueprint.load_model(two_parts, up="z")
    camera = fit_camera(model, (400, 400), "top", ortho=True)
    cut = cut_model(model, parse_section("z=10").facing(camera.eye, camera.target))
    section = draw_vector(cut.model, camera, (400, 400), renderer=renderer, section=cut).section
    slopes = {}
    for part in (0, 1):
        d = section.hatch[section.hatch_part == part]
        d = d[:, 1] - d[:, 0]
        slopes[part] = set(np.sign(d[:, 0] * d[:, 1]).astype(int).tolist())
    assert len(slopes[0]) == 1 and len(slopes[1]) == 1
    assert slopes[0] != slopes[1]


# -- the command line ----------------------------------------------------------------------------


def test_cli_section_png_and_plan_sheet(two_parts, tmp_path):
    for name, extra in (("s.png", ["--view", "front"]), ("p.svg", ["--view", "plan"])):
        proc = run_cli(
            "render",
            two_parts,
            "--up",
            "z",
            "-o",
            tmp_path / name,
            "--size",
            200,
            200,
            "--section",
            "y=0",
            *extra,
        )
        assert proc.returncode == 0, proc.stderr
    root = ET.parse(tmp_path / "p.svg").getroot()
    assert any(g.get("id") == "section" for g in root.iter(f"{SVG}g"))


@pytest.mark.parametrize(
    "args, mentions",
    [
        (["--section", "q=1"], ["section 'q=1'", "x=VALUE, y=VALUE or z=VALUE"]),
        (["--section", "x=1", "--section-plane", "0,0,0,1,0,0"], ["not both"]),
        (["--section-plane", "1,2,3"], ["not 6 numbers", "PX,PY,PZ,NX,NY,NZ"]),
        (["--section", "z=500"], ["misses the model"]),
        (["--section-keep", "post"], ["--section-keep", "give --section"]),
    ],
)
@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_cli_bad_section(two_parts, tmp_path, args, mentions, suffix):
    folder = tmp_path / "out"
    folder.mkdir()
    proc = run_cli("render", two_parts, "--up", "z", "-o", folder / f"x{suffix}", "--size", 64, 64, *args)
    one_error(proc, *mentions)
    no_output(folder)


def test_a_part_kept_whole_does_not_clip_the_hatching_of_the_parts_cut(renderer):
    """A washer (radius 12, kept whole) lies on the block above its hole (radius 8): from the
    top it covers the ring 8 < r < 12 of the block's cut face at z = 10, which is hatched all
    the same, as in the vector drawing."""
    washer = trimesh.creation.cylinder(radius=12.0, height=4.0, sections=96)
    washer.apply_translation((0.0, 0.0, H + 2.0))
    block = block_with_hole()
    positions = np.concatenate([block.vertices, washer.vertices])
    faces = np.concatenate([block.faces, washer.faces + len(block.vertices)])
    parts = np.r_[np.zeros(len(block.faces), np.int32), np.ones(len(washer.faces), np.int32)]
    model = Model(positions.astype(np.float32), faces.astype(np.int32), parts, ("block", "washer"), "z")
    size = (400, 400)
    camera = fit_camera(model, size, "top", ortho=True)
    hatched = blueprint.render(
        model, camera=camera, size=size, section="z=10", section_keep="washer", renderer=renderer
    )
    keep = np.array([False, True])
    unhatched = blueprint.render(
        top_cut(model, 10.0, keep).model, camera=camera, size=size, renderer=renderer
    )
    changed = np.abs(hatched.astype(int) - unhatched.astype(int)).max(axis=2) > 40
    # pixel centres in model units, the camera looking down on the origin
    per_px = camera.height / size[1]
    y, x = (np.mgrid[0 : size[1], 0 : size[0]] + 0.5 - np.array(size[::-1])[:, None, None] / 2) * per_px
    r = np.hypot(x, y)
    ring = (r > 9.0) & (r < 11.0)  # under the washer, away from its outline and the hole's
    spacing = max(5.0, 400 / 90)
    assert changed[ring].mean() > 0.6 / spacing
    # and the washer itself, above the plane, is not hatched
    assert changed[r < 7.0].mean() == 0.0


def test_vector_hatch_patterns_differ_between_regions_that_touch():
    """Each part takes the first pattern no earlier part within half a pixel has: squares in a
    row alternate, a square touching two of them takes a third, a square apart the first, and
    regions 0.5 px apart or more do not count as touching."""
    from blueprint.vector.section import _patterns

    row = {k: sg.box(10 * k, 0, 10 * k + 10, 10) for k in range(5)}
    above = {5: sg.box(5, 10, 15, 20)}  # on squares 0 and 1
    apart = {6: sg.box(100, 100, 110, 110), 7: sg.box(110.5, 100, 120, 110), 8: sg.box(120.4, 100, 130, 110)}
    patterns = _patterns({**row, **above, **apart})
    assert [patterns[k] for k in range(5)] == [0, 1, 0, 1, 0]
    assert patterns[5] == 2
    assert (patterns[6], patterns[7], patterns[8]) == (0, 0, 1)
