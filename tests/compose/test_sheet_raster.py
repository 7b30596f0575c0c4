"""Plan sheets as pictures: the one layout of pictures and vector sheets (boxes apart, inside the
border, clear of the title block), the title block's fields in the picture's pixels, nothing
drawn outside the border, and the paper the views lie on equal to the compositor's."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest
from helpers import run_cli

import blueprint
from blueprint.compose.lookup import get_style
from blueprint.compose.sheet import over, paper_image
from blueprint.examples import gearbox
from blueprint.scene.camera import SHEET_CELLS
from blueprint.scene.sheet import BORDER_WIDTH, RULE_WIDTH, lay_out_sheet, picture_per_mm, sheet_fields

EXTENTS = {
    "top": np.array([[10.0, 20.0], [150.0, 90.0]]),
    "front": np.array([[10.0, 40.0], [150.0, 100.0]]),
    "right": np.array([[30.0, 40.0], [90.0, 100.0]]),
    "iso": np.array([[0.0, 0.0], [120.0, 110.0]]),
}


def _apart(a: np.ndarray, b: np.ndarray) -> bool:
    return bool((a[1] <= b[0]).any() or (b[1] <= a[0]).any())


@pytest.mark.parametrize(
    "mm_per_px, paper", [(None, None), (None, (800.0, 600.0)), (0.5, None), (0.5, (297.0 / 0.5, 210.0 / 0.5))]
)
def test_layout_boxes_lie_apart_inside_the_border_above_the_title_block(mm_per_px, paper):
    layout = lay_out_sheet(EXTENTS, 5, (200, 150), mm_per_px, paper)
    assert layout.overflow <= 1.0
    (fx0, fy0), (fx1, fy1) = layout.frame
    assert 0 < fx0 < fx1 < layout.width and 0 < fy0 < fy1 < layout.height
    for name, box in layout.boxes.items():
        # the view's extent, moved by its shift, and inside the border
        np.testing.assert_allclose(box, EXTENTS[name] + layout.shifts[name])
        assert (box[0] > layout.frame[0]).all() and (box[1] < layout.frame[1]).all()
        assert box[1, 1] < layout.block[0, 1]  # above the title block: it spans the sheet's bottom
    for a, b in itertools.combinations(layout.boxes.values(), 2):
        assert _apart(a, b)
    # third angle: top above front, right beside front, in one column and one row
    boxes = layout.boxes
    assert boxes["top"][0, 0] == pytest.approx(boxes["front"][0, 0])
    assert boxes["top"][1, 1] < boxes["front"][0, 1] and boxes["front"][1, 0] < boxes["right"][0, 0]
    assert boxes["front"][0, 1] == pytest.approx(boxes["right"][0, 1])
    # each label under its view, centred on it
    for text in layout.labels:
        box = boxes[text.text.lower()]
        assert text.x == pytest.approx(box[:, 0].mean()) and text.y > box[1, 1]
    assert {t.text for t in layout.labels} == {n.upper() for n in SHEET_CELLS}


def test_title_block_fields():
    fields = sheet_fields("Gear — box", "1:2", "in", "a3")
    assert list(fields) == ["title", "scale", "units", "date", "sheet"]
    assert fields["scale"] == "1:2 (iso not to scale)" and fields["units"] == "mm (model in in)"
    assert fields["sheet"] == "A3"
    assert sheet_fields("x", None, None, "400 x 300 px")["units"] == "px (not to scale)"


def test_sheet_date_follows_source_date_epoch(monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", str(86400 * 365))
    assert sheet_fields("x", None, "mm", "A4")["date"] == "1971-01-01"


def _block_cells(marks) -> list[np.ndarray]:
    """The title block's value cells, top to bottom, from its rules: (2, 2) pixel boxes."""
    rules = marks.lines[marks.widths <= RULE_WIDTH]
    horizontal = rules[np.isclose(rules[:, 0, 1], rules[:, 1, 1])]
    vertical = rules[np.isclose(rules[:, 0, 0], rules[:, 1, 0])]
    border = marks.lines[marks.widths == BORDER_WIDTH]
    right, bottom = border[:, :, 0].max(), border[:, :, 1].max()
    rows = sorted({float(y) for y in horizontal[:, 0, 1]}) + [bottom]
    divider = vertical[:, 0, 0].max()  # the rule between names and values
    return [np.array([[divider, a], [right, b]]) for a, b in zip(rows[:-1], rows[1:], strict=True)]


@pytest.fixture(scope="module")
def sheets(renderer):
    model = gearbox()
    options = dict(size=(800, 600), view="plan", style="paper", renderer=renderer)
    return (
        blueprint.render_frame(model, title="Gearbox", **options),
        blueprint.render_frame(model, title="Another title", **options),
    )


def test_picture_title_block_carries_its_fields(sheets):
    first, second = sheets
    texts = [t.text for t in first.marks.texts]
    for name in ("TITLE", "SCALE", "UNITS", "DATE", "SHEET", "TOP", "FRONT", "RIGHT", "ISO"):
        assert name in texts
    assert "Gearbox" in texts and "800 x 600 px" in texts and "not to scale" in texts
    cells = _block_cells(first.marks)
    assert len(cells) == 5
    image = first.image.astype(int)
    ink = np.abs(image - image[0, 0]).max(axis=-1) > 60
    for (x0, y0), (x1, y1) in cells:
        inside = ink[int(y0) + 3 : int(y1) - 2, int(x0) + 3 : int(x1) - 3]
        # each field's value is written in its cell (the units' inks 1.3 % of it in DejaVu
        # Sans, 0.9 % in Pillow's own font, where the system has none of SHEET_FONTS)
        assert inside.mean() > 0.005
    # another title changes the title's cell, and nothing else
    changed = np.abs(first.image.astype(int) - second.image.astype(int)).max(axis=-1) > 0
    (x0, y0), (x1, y1) = cells[0]
    assert changed[int(y0) + 2 : int(y1) - 1, int(x0) + 2 : int(x1)].sum() > 30
    changed[int(y0) + 2 : int(y1) - 1, int(x0) + 2 : int(x1)] = False
    assert not changed.any()


def test_nothing_is_drawn_outside_the_border(sheets):
    frame = sheets[0]
    border = frame.marks.lines[frame.marks.widths == BORDER_WIDTH]
    x0, y0 = border[:, :, 0].min(), border[:, :, 1].min()
    x1, y1 = border[:, :, 0].max(), border[:, :, 1].max()
    reach = BORDER_WIDTH / 2 + 1
    paper = frame.image[0, 0]
    outside = np.ones(frame.image.shape[:2], bool)
    outside[
        int(y0 - reach) : int(np.ceil(y1 + reach)) + 1, int(x0 - reach) : int(np.ceil(x1 + reach)) + 1
    ] = False
    assert (frame.image[outside] == paper).all()
    # and the views fill the room: the border a few pixels in, the views near it
    assert x0 < 0.04 * 800 and y0 < 0.04 * 600


@pytest.mark.parametrize("grid", [0.0, 16.0])
def test_sheet_paper_is_the_compositors(renderer, grid):
    style = get_style("blueprint", grid)
    model = gearbox()
    drawn = blueprint.render(model, size=(300, 200), view="front", ortho=True, style=style, renderer=renderer)
    clear = blueprint.render(
        model,
        size=(300, 200),
        view="front",
        ortho=True,
        style=replace(style, paper=None, grid=0.0),
        renderer=renderer,
    )
    sheet = paper_image(style, (300, 200))
    assert (sheet[clear[..., 3] == 0] == drawn[clear[..., 3] == 0]).all()
    over(sheet, clear, 0, 0)
    assert np.abs(sheet.astype(int) - drawn).max() <= 1


def test_small_pictures_take_smaller_measures():
    assert picture_per_mm(None) == pytest.approx(96 / 25.4)
    assert picture_per_mm((1024, 768)) == pytest.approx(96 / 25.4)
    assert picture_per_mm((256, 192)) == pytest.approx(1.92)


def test_cli_plan_picture_with_title_and_dimensions(tmp_path):
    out = tmp_path / "sheet.png"
    model = tmp_path / "box.obj"
    model.write_text("v 0 0 0\nv 2 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    proc = run_cli(
        "render", model, "-o", out, "--size", 320, 240, "--view", "plan", "--title", "Wedge", "--dimensions"
    )
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_size > 0
