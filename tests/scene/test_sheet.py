"""Vector plan sheets: views laid out with even gaps and labelled, a border and an ISO 7200 title
block, --sheet paper with a standard scale that fits, Unicode text in PDF."""

from __future__ import annotations

import datetime
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from helpers import no_output, one_error, run_cli

from blueprint import load_model
from blueprint.api.files import render_vector_file
from blueprint.examples import gearbox
from blueprint.scene.sheet import PAPER_MM, fit_scale, place_views
from blueprint.vector import draw_vector_sheet
from blueprint.vector.pdf import unicode_font

SVG = "{http://www.w3.org/2000/svg}"


def test_standard_scales():
    assert [fit_scale(v) for v in (0.3, 1.0, 1.2, 2.0, 3.0, 7.0, 11.0, 49.0)] == [
        0.5,
        1.0,
        2.0,
        2.0,
        5.0,
        10.0,
        20.0,
        50.0,
    ]


def test_views_are_placed_with_even_gaps():
    extents = {
        "top": np.array([[10.0, 20.0], [50.0, 40.0]]),
        "front": np.array([[0.0, 5.0], [60.0, 15.0]]),
        "right": np.array([[30.0, 0.0], [40.0, 30.0]]),
        "iso": np.array([[0.0, 0.0], [20.0, 20.0]]),
    }
    cells = {"top": (0, 0), "iso": (1, 0), "front": (0, 1), "right": (1, 1)}
    shifts, (width, height) = place_views(extents, cells, gap=5.0, label=2.0)
    # a column spans its views' x in their cells: 0 to 60, then 0 to 40; a row their y: 0 to 40
    # (top from 20, iso from 0), then 0 to 30
    assert (width, height) == (5 + 60 + 5 + 40 + 5, 5 + 40 + 2 + 5 + 30 + 2 + 5)
    placed = {n: extents[n] + shifts[n] for n in extents}
    assert placed["front"][0, 0] == 5.0 and placed["top"][0, 0] == 15.0  # one column, aligned
    assert placed["iso"][0, 0] == 5 + 60 + 5 and placed["right"][0, 0] == 5 + 60 + 5 + 30
    assert placed["top"][0, 1] == 5.0 + 20 and placed["iso"][0, 1] == 5.0
    assert placed["right"][0, 1] == 5 + 40 + 2 + 5


def _texts(root) -> list[str]:
    group = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "sheet")
    return [t.text for t in group.iter(f"{SVG}text")]


def test_sheet_has_labels_border_and_title_block(renderer, tmp_path):
    path = tmp_path / "sheet.svg"
    render_vector_file(gearbox(), path, view="plan", size=(400, 300), renderer=renderer, title="Gear — box")
    texts = _texts(ET.parse(path).getroot())
    for label in ("TOP", "FRONT", "RIGHT", "ISO"):
        assert label in texts
    for field in ("TITLE", "SCALE", "UNITS", "DATE", "SHEET"):
        assert field in texts
    assert "Gear — box" in texts and datetime.date.today().isoformat() in texts
    assert "not to scale" in texts


def test_sheet_paper_and_fitted_scale(renderer, tmp_path, shared_models):
    path = tmp_path / "a3.svg"
    model = shared_models / "trimesh" / "featuretype.STL"  # 5 x 2.5 x 1.375 in
    render_vector_file(model, path, view="plan", units="in", sheet="A3", renderer=renderer)
    root = ET.parse(path).getroot()
    assert (root.get("width"), root.get("height")) == ("420mm", "297mm")
    texts = _texts(root)
    assert "A3" in texts and "mm (model in in)" in texts
    # 127 mm + 63.5 mm of views and the iso view fit A3 at 1:1, not at 2:1
    assert "1:1 (iso not to scale)" in texts
    sheet = draw_vector_sheet(load_model(model), (1024, 1024), units="in", sheet="A0", renderer=renderer)
    # the two columns of views, each about the iso view's 5 in wide, fit A0 (1129 mm within the
    # border and gaps) at 2:1 but not at 5:1
    assert sheet.page.scale == pytest.approx(0.5)
    assert (sheet.page.width, sheet.page.height) == pytest.approx(PAPER_MM["A0"])
    mm = sheet.points * sheet.page.factor
    assert mm[:, 0].min() > 20 and mm[:, 0].max() < 1189 - 10 and mm[:, 1].min() > 10
    assert np.ptp(mm[:, 0]) * 2.5 > 1189 - 30 - 30  # at 5:1 they would not fit


@pytest.mark.skipif(unicode_font() is None, reason="no Unicode TrueType font on this system")
def test_pdf_keeps_unicode_text(renderer, tmp_path):
    from pypdf import PdfReader

    path = tmp_path / "sheet.pdf"
    render_vector_file(gearbox(), path, view="plan", size=(400, 300), renderer=renderer, title="Gear — Ø 40")
    text = PdfReader(path).pages[0].extract_text()
    assert "Gear — Ø 40" in text
    assert "FRONT" in text


@pytest.mark.parametrize(
    "args, mentions",
    [
        (["-o", "x.svg", "--view", "plan", "--sheet", "B5"], ["unknown sheet 'B5'", "A4, A3, A2, A1, A0"]),
        (["-o", "x.svg", "--view", "top", "--sheet", "A4"], ["--sheet A4", "--view plan"]),
        (["-o", "x.png", "--view", "plan", "--sheet", "A4"], ["for vector drawings"]),
    ],
)
def test_bad_sheet(tmp_path, args, mentions):
    model = tmp_path / "box.obj"
    model.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    folder = tmp_path / "out"
    folder.mkdir()
    args = [folder / a if a.startswith("x.") else a for a in args]
    proc = run_cli("render", model, "--size", 64, 64, *args)
    one_error(proc, *mentions)
    no_output(folder)


def test_dimensions_of_featuretype_to_scale_in_inches(tmp_path, shared_models):
    model = shared_models / "trimesh" / "featuretype.STL"  # 5 x 2.5 x 1.375 in
    path = tmp_path / "dims.svg"
    proc = run_cli(
        "render", model, "-o", path, "--view", "plan", "--units", "in", "--sheet", "A3", "--dimensions"
    )
    assert proc.returncode == 0, proc.stderr
    texts = _texts(ET.parse(path).getroot())
    # width and depth on top, width and height on front, depth and height on right
    assert sorted(t for t in texts if re.fullmatch(r"[0-9.]+", t)) == sorted(
        ["127", "63.5", "127", "34.9", "63.5", "34.9"]
    )


def test_dimension_lines_span_the_view(renderer, shared_models):
    from blueprint.scene.camera import fit_camera
    from blueprint.vector import draw_vector

    model = load_model(shared_models / "trimesh" / "featuretype.STL")
    size = (400, 300)
    camera = fit_camera(model, size, "front", ortho=True)
    drawing = draw_vector(model, camera, size, renderer=renderer, dimensions=True, scale="1:1", units="in")
    # the overall width and height, and the hole seen along its axis from the front
    assert [t.text for t in drawing.marks.texts] == ["127", "34.9", "Ø 9.9"]
    assert drawing.marks.texts[1].angle == 90.0
    # the dimension line under the view runs between the extension lines at the model's ends
    per_px = camera.height / size[1]
    lines = drawing.marks.lines
    horizontal = lines[np.isclose(lines[:, 0, 1], lines[:, 1, 1])]
    longest = np.abs(horizontal[:, 1, 0] - horizontal[:, 0, 0]).max()
    assert longest * per_px == pytest.approx(5.0, rel=1e-6)
    span = np.ptp(drawing.points[:, 0])
    assert longest == pytest.approx(span, abs=0.6)


@pytest.mark.parametrize(
    "args, mentions",
    [
        (["-o", "x.svg", "--view", "iso", "--dimensions"], ["dimensions need an orthographic view"]),
        (["-o", "x.png", "--view", "front", "--dimensions"], ["dimensions need an orthographic view"]),
        (["-o", "x.png", "--view", "front", "--title", "T"], ["--title", "--view plan"]),
        (["-o", "x.png", "--view", "plan", "--units", "parsec"], ["unknown units 'parsec'", "mm, cm, m"]),
    ],
)
def test_bad_dimensions(tmp_path, args, mentions):
    test_bad_sheet(tmp_path, args, mentions)
