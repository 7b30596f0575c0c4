"""SVG, PDF and DXF files: structure, groups per part and level, styles, scale, empty drawings."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest
from vector_helpers import SVG, svg_line_paths, svg_lines

from blueprint.api.files import render_vector_file
from blueprint.errors import InputError
from blueprint.examples import assemble, box, gearbox
from blueprint.scene.camera import Camera
from blueprint.vector import (
    LineStyle,
    VectorStyle,
    draw_vector,
    parse_scale,
    save_drawing,
    vector_style,
)
from blueprint.vector.dxf import layer_name
from blueprint.vector.linework import KINDS
from blueprint.vector.svg import safe_id

SIZE = (200, 160)


@pytest.fixture(scope="module")
def gear_drawing(renderer):
    model = gearbox()
    return draw_vector(model, size=SIZE, style="paper", highlight=["gear"], renderer=renderer)


def test_svg_parses_with_the_image_as_view_box_and_groups_per_part(gear_drawing, tmp_path):
    path = save_drawing(tmp_path / "gear.svg", gear_drawing)
    root = ET.parse(path).getroot()
    assert root.tag == f"{SVG}svg"
    assert root.get("viewBox") == "0 0 200 160"
    assert (root.get("width"), root.get("height")) == ("200", "160")
    groups = {g.get("id"): g for g in root.iter(f"{SVG}g") if g.get("data-part") is not None}
    assert set(groups) <= set(gear_drawing.part_names)
    assert {"base", "gear", "shaft", "cover"} <= set(groups)
    lines = svg_lines(path)
    levels = {level for _, level in lines}
    assert {0, 1, 2} <= levels
    # every coordinate inside the view box, and as many polylines as the drawing has
    points = np.concatenate([p for polylines in lines.values() for p in polylines])
    assert points.min() >= -0.05 and points[:, 0].max() <= 200.05 and points[:, 1].max() <= 160.05
    assert sum(len(v) for v in lines.values()) == len(gear_drawing)
    # level 0 solid in the ink, deeper levels dashed and fading; the highlighted part orange
    paths = {(part.get("id"), level.get("class")): level for part, level, _, _ in svg_line_paths(path)}
    base0, base1 = paths[("base", "level-0")], paths.get(("base", "level-1"))
    assert base0.get("stroke") == "#0a1f44" and base0.get("stroke-dasharray") is None
    deeper = [p for (gid, cls), p in paths.items() if cls != "level-0" and gid != "gear"]
    assert deeper and all(p.get("stroke-dasharray") for p in deeper)
    assert all(float(p.get("stroke-opacity")) < 1 for p in deeper)
    # hidden lines half as wide as visible ones (ISO 128)
    assert all(float(p.get("stroke-width")) == 0.5 * float(base0.get("stroke-width")) for p in deeper)
    if base1 is not None:
        assert base1.get("stroke") == "#4f5d75"
    assert all(p.get("stroke") != "#0a1f44" for (gid, _), p in paths.items() if gid == "gear")


def test_svg_text_written_in_blocks_of_groups_on_several_threads_is_one_threads(gear_drawing, monkeypatch):
    """The paths' text and source edges are written a block of groups at a time side by side
    on the pool: over blocks of a few points on three threads, the same bytes as one block."""
    from blueprint import parallel, settings
    from blueprint.vector.svg import svg_bytes

    monkeypatch.setattr(settings, "THREADS", 1)
    want = svg_bytes(gear_drawing)
    monkeypatch.setattr(settings, "THREADS", 3)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)
    assert svg_bytes(gear_drawing) == want
    assert want.count(b"<path") > 20 and b"data-edges" in want


def test_dxf_parts_whose_names_sanitise_alike_get_layers_of_their_own(renderer, tmp_path):
    import ezdxf

    model = assemble({"a/b": box((0, 0, 0), (1, 1, 1)), "a:b": box((2, 0, 0), (3, 1, 1))})
    drawing = draw_vector(model, size=SIZE, renderer=renderer)
    doc = ezdxf.readfile(save_drawing(tmp_path / "alike.dxf", drawing))
    by_layer = {}
    for entity in doc.modelspace().query("LWPOLYLINE"):
        by_layer.setdefault(entity.dxf.layer, []).append(min(x for x, *_ in entity.get_points()))
    visible = {name: xs for name, xs in by_layer.items() if name.endswith("-silhouette-L0")}
    assert set(visible) == {layer_name("a/b", 0, "silhouette"), "a_b_1-silhouette-L0"}
    # each layer holds one box's lines: the boxes lie apart along x
    left, right = max(visible[layer_name("a/b", 0, "silhouette")]), min(visible["a_b_1-silhouette-L0"])
    assert left < right


def test_svg_parses_back_to_the_drawing_within_the_output_grid(gear_drawing, tmp_path):
    path = save_drawing(tmp_path / "gear.svg", gear_drawing)
    lines = svg_lines(path)
    by_group = {}
    for part, _, level, index in gear_drawing.groups():
        by_group.setdefault((gear_drawing.part_names[part], level), []).extend(
            gear_drawing.polyline(i) for i in index
        )
    for key, polylines in lines.items():
        original = by_group[key]
        assert len(polylines) == len(original)
        # a path's lines go in the order of their edges: matched here by their first point
        for got in polylines:
            # repeated points on the 0.1 px grid are dropped, the rest round to it
            want = min(original, key=lambda w: np.abs(w[0] - got[0]).max() + np.abs(w[-1] - got[-1]).max())
            assert np.abs(got[0] - want[0]).max() <= 0.05 + 1e-9
            assert np.abs(got[-1] - want[-1]).max() <= 0.05 + 1e-6


def test_dxf_opens_with_one_layer_per_part_and_level(gear_drawing, tmp_path):
    import ezdxf

    path = save_drawing(tmp_path / "gear.dxf", gear_drawing)
    doc = ezdxf.readfile(path)
    polylines = doc.modelspace().query("LWPOLYLINE")
    assert len(polylines) == len(gear_drawing)
    base1 = next(c for p, c, k, _ in gear_drawing.groups() if gear_drawing.part_names[p] == "base" and k == 1)
    base0 = next(c for p, c, k, _ in gear_drawing.groups() if gear_drawing.part_names[p] == "base" and k == 0)
    expected = {layer_name(gear_drawing.part_names[p], k, KINDS[c]) for p, c, k, _ in gear_drawing.groups()}
    assert expected <= {layer.dxf.name for layer in doc.layers}
    assert {e.dxf.layer for e in polylines} == expected
    hidden = doc.layers.get(layer_name("base", 1, KINDS[base1]))
    assert hidden.dxf.linetype == "BP_L1" and hidden.transparency > 0
    assert doc.layers.get(layer_name("base", 0, KINDS[base0])).dxf.linetype == "CONTINUOUS"
    # y points up in DXF
    ys = np.concatenate([np.array(e.get_points("xy"))[:, 1] for e in polylines])
    assert ys.min() >= -0.05 and ys.max() <= 160.05


def test_pdf_has_a_layer_per_part_and_per_level_as_the_svg_has(gear_drawing, tmp_path):
    """pypdf lists the optional content groups: every part drawn and every level, named as
    the SVG's part layers and level classes; every group of lines is marked as content of its
    part's layer and its level's, and holds that group's polylines, no more and no less."""
    import re

    import pypdf

    reader = pypdf.PdfReader(save_drawing(tmp_path / "gear.pdf", gear_drawing))
    properties = reader.trailer["/Root"]["/OCProperties"]
    names = [group.get_object()["/Name"] for group in properties["/OCGs"]]
    drawn_parts = sorted(set(gear_drawing.part.tolist()))
    drawn_kinds = sorted(set(gear_drawing.kind.tolist()))
    drawn_levels = sorted(set(gear_drawing.level.tolist()))
    assert names == [gear_drawing.part_names[p] for p in drawn_parts] + [KINDS[k] for k in drawn_kinds] + [
        "visible" if k == 0 else f"hidden {k}" for k in drawn_levels
    ]
    assert len(drawn_parts) == 13 and len(drawn_levels) >= 6
    # the SVG's groups carry the same names and levels
    svg = svg_lines(save_drawing(tmp_path / "gear.svg", gear_drawing))
    assert {level for _, level in svg} == set(drawn_levels)
    # the viewer's panel: parts, kinds, then levels
    order = properties["/D"]["/Order"]
    assert [branch[0] for branch in order] == ["parts", "kinds", "levels"]
    assert len(order[0]) == 1 + len(drawn_parts) and len(order[2]) == 1 + len(drawn_levels)
    assert len(order[1]) == 1 + len(drawn_kinds)
    page = reader.pages[0]
    keys = page["/Resources"]["/Properties"]
    assert keys["/P6"].get_object()["/Name"] == "gear" and keys["/L0"].get_object()["/Name"] == "visible"
    content = page.get_contents().get_data().decode("latin-1")
    marked = re.findall(
        r"/OC /P(\d+) BDC\n/OC /K(\d+) BDC\n/OC /L(\d+) BDC\n(.*?)EMC\nEMC\nEMC", content, re.S
    )
    assert len(marked) == len(list(gear_drawing.groups()))
    for (part, kind, level, index), (p, c, k, body) in zip(gear_drawing.groups(), marked, strict=True):
        assert (int(p), int(c), int(k)) == (part, kind, level)
        strokes = len(re.findall(r"^ ?S$", body, re.M))
        assert strokes == len(index)


def test_pdf_opens_with_the_drawing_size(gear_drawing, tmp_path):
    import pypdf

    path = save_drawing(tmp_path / "gear.pdf", gear_drawing)
    reader = pypdf.PdfReader(path)
    assert len(reader.pages) == 1
    box_ = reader.pages[0].mediabox
    assert float(box_.width) == pytest.approx(200 * 0.75) and float(box_.height) == pytest.approx(160 * 0.75)
    assert len(reader.pages[0].get_contents().get_data()) > 1000


def test_plan_view_to_scale(renderer, tmp_path):
    # a 1000 x 400 mm plate seen from the top at 1:50 is 20 x 8 mm on paper
    model = assemble({"plate": box((0, 0, 0), (1000, 10, 400))})
    summary = render_vector_file(
        model, tmp_path / "plan.svg", size=(256, 256), view="top", scale="1:50", units="mm", renderer=renderer
    )
    # the outline, one closed line (the bottom's edges lie right under it, one level down)
    assert summary["format"] == "svg" and summary["lines"][0] == 1
    root = ET.parse(tmp_path / "plan.svg").getroot()
    width = float(root.get("width")[:-2])
    assert root.get("width").endswith("mm") and root.get("viewBox") == f"0 0 {width:.6g} {width:.6g}"
    points = np.concatenate([p for v in svg_lines(tmp_path / "plan.svg").values() for p in v])
    extent = np.ptp(points, axis=0)
    assert sorted(extent) == pytest.approx([8.0, 20.0], abs=0.02)
    title = root.find(f"{SVG}text")
    assert "top view" in title.text and "1:50" in title.text and "(mm)" in title.text


def test_empty_drawing_writes_valid_files(renderer, tmp_path):
    model = assemble({"cube": box((-1, -1, -1), (1, 1, 1))})
    away = Camera(eye=(0, 0, 10), target=(0, 0, 20), up=(0, 1, 0), near=0.1, far=100.0)
    drawing = draw_vector(model, away, (64, 48), renderer=renderer)
    root = ET.parse(save_drawing(tmp_path / "empty.svg", drawing)).getroot()
    assert root.get("viewBox") == "0 0 64 48" and not list(root.iter(f"{SVG}path"))
    import ezdxf

    assert len(ezdxf.readfile(save_drawing(tmp_path / "empty.dxf", drawing)).modelspace()) == 0
    import pypdf

    assert len(pypdf.PdfReader(save_drawing(tmp_path / "empty.pdf", drawing)).pages) == 1


def test_render_vector_file_summary_and_errors(renderer, tmp_path):
    model = assemble({"cube": box((-1, -1, -1), (1, 1, 1))})
    summary = render_vector_file(model, tmp_path / "cube.svg", size=(96, 96), renderer=renderer)
    # visible: the outline as one closed line, the 3 near edges as 2 (two chain through the
    # corner); the 3 hidden edges stop short of the far corner, which the near one covers
    assert summary["lines"] == {0: 3, 1: 3}
    assert summary["bytes"] == (tmp_path / "cube.svg").stat().st_size
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cube.svg"]  # no temporary files left
    with pytest.raises(InputError, match="must end in"):
        render_vector_file(model, tmp_path / "cube.png", renderer=renderer)
    with pytest.raises(InputError, match="no part matches .nope."):
        render_vector_file(model, tmp_path / "x.svg", size=(32, 32), highlight=["nope"], renderer=renderer)
    with pytest.raises(InputError, match="units"):
        render_vector_file(model, tmp_path / "x.svg", scale="1:10", units="furlong", renderer=renderer)
    with pytest.raises(InputError, match="orthographic"):
        draw_vector(model, Camera.fit(model.positions, "top"), (32, 32), scale="1:10", renderer=renderer)


def test_scale_parsing_styles_and_names():
    assert parse_scale("1:50") == 50 and parse_scale("2:1") == 0.5 and parse_scale(100) == 100
    assert parse_scale(None) is None
    with pytest.raises(InputError):
        parse_scale("fifty")
    style = vector_style("blueprint")
    assert style.level(0).dash == () and style.level(0).hex == "#ffffff"
    assert style.level(1).dash and style.level(2).opacity < style.level(1).opacity
    assert style.level(9).opacity < style.level(3).opacity  # past the table: fading on
    assert vector_style("wireframe", dashes=False).level(2).dash == ()
    custom = VectorStyle(levels=(LineStyle("#ff0000", 2.0), LineStyle((0, 0, 1), 1.0, (2, 1), 0.5)))
    assert custom.level(1, highlighted=True).width == pytest.approx(1.5)
    with pytest.raises(InputError):
        LineStyle("#ff0000", opacity=2.0)
    taken = set()
    assert safe_id("gear wheel", taken) == "gear_wheel" and safe_id("gear wheel", taken) == "gear_wheel-2"
    assert safe_id("12 bolt", taken) == "p_12_bolt" and safe_id("<>", taken) == "part"
    assert layer_name('a/b:"c"', 2) == "a_b_c_-L2"


def test_plan_sheet_is_four_views_in_their_cells(renderer):
    """Top above front, right beside it, iso in the free corner: every view holds exactly the
    lines of its view drawn alone, moved into place, the projections kept aligned (top over
    front, right beside front) and the views apart by one gap."""
    from blueprint.scene.camera import SHEET_CELLS, sheet_cameras
    from blueprint.vector import draw_vector_sheet

    model = gearbox()
    size = (320, 240)
    sheet = draw_vector_sheet(model, size, renderer=renderer)
    w, h = size[0] // 2, size[1] // 2
    cameras = sheet_cameras(model, (w, h), 30.0)
    assert sheet.camera == cameras["front"]
    start, shifts, boxes = 0, {}, {}
    for name in SHEET_CELLS:
        alone = draw_vector(model, cameras[name], (w, h), renderer=renderer)
        count = len(alone)
        assert count > 10, name
        chunk = slice(sheet.offsets[start], sheet.offsets[start + count])
        points = sheet.points[chunk]
        shifts[name] = points[0] - alone.points[0]
        np.testing.assert_allclose(points, alone.points + shifts[name], atol=1e-9)
        np.testing.assert_array_equal(sheet.level[start : start + count], alone.level)
        boxes[name] = (points.min(axis=0), points.max(axis=0))
        start += count
    assert start == len(sheet)
    assert shifts["top"][0] == pytest.approx(shifts["front"][0])
    assert shifts["front"][1] == pytest.approx(shifts["right"][1])
    assert shifts["top"][1] == pytest.approx(shifts["iso"][1])
    # third angle: the top view above the front view, the right view to its right
    assert boxes["top"][1][1] < boxes["front"][0][1] and boxes["front"][1][0] < boxes["right"][0][0]
    # the three orthographic views share one scale
    assert cameras["top"].height == cameras["front"].height == cameras["right"].height


def test_plan_sheet_to_scale(renderer, tmp_path):
    model = gearbox()
    summary = render_vector_file(
        model,
        tmp_path / "sheet.svg",
        size=(400, 300),
        view="plan",
        scale="1:2",
        units="mm",
        renderer=renderer,
    )
    assert summary["lines"]
    root = ET.parse(tmp_path / "sheet.svg").getroot()
    from blueprint.scene.camera import sheet_cameras
    from blueprint.vector import draw_vector_sheet

    mm_per_px = sheet_cameras(model, (200, 150), 30.0)["front"].height / 150 / 2
    sheet = draw_vector_sheet(model, (400, 300), scale="1:2", units="mm", renderer=renderer)
    assert sheet.page.factor == pytest.approx(mm_per_px, rel=1e-9)
    assert float(root.get("width").removesuffix("mm")) == pytest.approx(sheet.page.width, rel=1e-5)
    assert float(root.get("height").removesuffix("mm")) == pytest.approx(sheet.page.height, rel=1e-5)
    assert "1:2" in "".join(root.itertext())
