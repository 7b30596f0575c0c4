"""What is drawn besides the model's lines carries its kind too: a sheet's own marks
(``sheet``), dimensions (``dimension``), glyphs (``glyph``) and a section's hatching and
outline (``hatch``, ``section``), in SVG (``data-kind``), DXF (layers and XDATA) and PDF (the
kinds' optional content groups)."""

import re
import xml.etree.ElementTree as ET

import ezdxf
import numpy as np
import pypdf
import pytest
import trimesh
from vector_helpers import parse_path

import blueprint
from blueprint.scene.model import Model
from blueprint.vector import KINDS, save_drawing

SVG = "{http://www.w3.org/2000/svg}"
SIZE = (320, 240)
# a dimension's value: a number in mm, or a diameter
VALUE = re.compile(r"^(\d+× )?(Ø )?\d+(\.\d)?$")


def _box() -> Model:
    mesh = trimesh.creation.box((50.0, 20.0, 10.0))
    return Model.from_arrays(mesh.vertices, mesh.faces, part_names=["box"], up="z")


@pytest.fixture(scope="module")
def view(renderer):
    """A front view cut by a section, with its dimensions and a glyph file's label and
    dimension."""
    glyphs = blueprint.Glyphs.from_dict(
        {
            "label": [{"at": [0, 0, 5], "text": "lid"}],
            "dimension": [{"from": [-25, -10, 5], "to": [25, -10, 5], "text": "50 h7", "offset": 20}],
        },
        "marks.toml",
    )
    options = {"size": SIZE, "view": "front", "ortho": True, "units": "mm", "dimensions": True}
    return blueprint.draw(_box(), section="y=0", glyphs=glyphs, vector=True, **options).lines


@pytest.fixture(scope="module")
def sheet(renderer):
    return blueprint.draw(
        _box(), size=(640, 480), view="plan", units="mm", dimensions=True, vector=True
    ).lines


def _sheet_svg(path):
    root = ET.parse(path).getroot()
    group = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "sheet")
    lines: dict[str, int] = {}
    for element in group.iter(f"{SVG}path"):
        kind = element.get("data-kind")
        lines[kind] = lines.get(kind, 0) + len(parse_path(element.get("d")))
    texts = [(t.get("data-kind"), t.text) for t in group.iter(f"{SVG}text")]
    return root, lines, texts


@pytest.mark.parametrize("which", ["view", "sheet"])
def test_the_svg_tags_sheet_marks_and_dimensions(which, view, sheet, tmp_path):
    drawing = view if which == "view" else sheet
    _, lines, texts = _sheet_svg(save_drawing(tmp_path / "d.svg", drawing))
    # the values are the dimensions', every other text the sheet's own
    assert texts and all(
        (kind == "dimension") == bool(VALUE.match(text) or text == "50 h7") for kind, text in texts
    )
    expected = {kind: int((drawing.marks.kinds == kind).sum()) for kind in ("sheet", "dimension")}
    assert lines == {kind: n for kind, n in expected.items() if n}
    # a dimension is 9 lines: two extension lines, the dimension line, two arrowheads of 3
    assert expected["dimension"] % 9 == 0 and expected["dimension"] >= 9 * 2
    assert (expected["sheet"] > 0) == (which == "sheet")


def test_the_svg_tags_glyphs_and_the_section(view, tmp_path):
    root = ET.parse(save_drawing(tmp_path / "d.svg", view)).getroot()
    glyphs = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "glyphs")
    assert glyphs.get("data-kind") == "glyph"
    section = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "section")
    assert [p.get("data-kind") for p in section.iter(f"{SVG}path")] == ["hatch", "section"]


def test_dxf_marks_section_and_glyphs_carry_their_kind(view, sheet, tmp_path):
    doc = ezdxf.readfile(save_drawing(tmp_path / "d.dxf", view))
    msp = doc.modelspace()

    def kinds(query):
        return [e.get_xdata("BLUEPRINT") for e in msp.query(query)]

    assert kinds('LINE[layer=="DIMENSIONS"]') == [[(1000, "dimension")]] * int(len(view.marks.lines))
    assert kinds('TEXT[layer=="DIMENSIONS"]') == [[(1000, "dimension")]] * len(view.marks.texts)
    section = kinds('LINE[layer=="SECTION"]')
    assert section == [[(1000, "hatch")]] * len(view.section.hatch) + [[(1000, "section")]] * len(
        view.section.outline
    )
    assert len(view.section.hatch) > 0 and len(view.section.outline) >= 4
    glyphs = kinds('LWPOLYLINE TEXT[layer=="GLYPHS"]')
    assert glyphs == [[(1000, "glyph")]] * len(glyphs) and len(glyphs) == 1  # the label
    assert "SHEET" not in doc.layers
    # a plan sheet: its own marks on SHEET, its dimensions apart
    doc = ezdxf.readfile(save_drawing(tmp_path / "s.dxf", sheet))
    on_sheet = doc.modelspace().query('LINE[layer=="SHEET"]')
    assert len(on_sheet) == int((sheet.marks.kinds == "sheet").sum())
    assert {e.get_xdata("BLUEPRINT")[0] for e in on_sheet} == {(1000, "sheet")}
    sheet_texts = [e.dxf.text for e in doc.modelspace().query('TEXT[layer=="SHEET"]')]
    assert "FRONT" in sheet_texts and not any(VALUE.match(t) for t in sheet_texts)


def test_pdf_marks_section_and_glyphs_are_content_of_their_kinds_layers(view, sheet, tmp_path):
    reader = pypdf.PdfReader(save_drawing(tmp_path / "d.pdf", view))
    keys = reader.pages[0]["/Resources"]["/Properties"]
    names = {key: str(ref.get_object()["/Name"]) for key, ref in keys.items()}
    content = reader.pages[0].get_contents().get_data().decode("latin-1")
    for kind, count in (
        ("dimension", len(view.marks.lines)),
        ("hatch", len(view.section.hatch)),
        ("section", len(view.section.outline)),
    ):
        assert names[f"/K{KINDS.index(kind)}"] == kind
        (body,) = re.findall(rf"/OC /K{KINDS.index(kind)} BDC\n(.*?)\nEMC", content, re.S)
        assert len(re.findall(r" l S", body)) == count, kind
    assert names[f"/K{KINDS.index('glyph')}"] == "glyph"
    assert f"/OC /GLYPHS BDC\n/OC /K{KINDS.index('glyph')} BDC" in content
    assert f"/K{KINDS.index('sheet')}" not in names
    order = reader.trailer["/Root"]["/OCProperties"]["/D"]["/Order"]
    listed = [str(g.get_object()["/Name"]) for g in order[1][1:]]
    assert listed[-4:] == ["section", "hatch", "glyph", "dimension"]
    reader = pypdf.PdfReader(save_drawing(tmp_path / "s.pdf", sheet))
    content = reader.pages[0].get_contents().get_data().decode("latin-1")
    (body,) = re.findall(rf"/OC /K{KINDS.index('sheet')} BDC\n(.*?)\nEMC", content, re.S)
    assert len(re.findall(r" l S", body)) == int((sheet.marks.kinds == "sheet").sum())


def test_marks_keep_their_kinds_when_moved_and_joined(sheet):
    kinds = sheet.marks.kinds
    assert set(kinds.tolist()) == {"sheet", "dimension"}
    moved = sheet.marks.shifted(np.array([3.0, 4.0]))
    assert (moved.kinds == kinds).all()
    both = blueprint.Marks.concatenate([sheet.marks, moved])
    assert both.kinds.tolist() == kinds.tolist() * 2
