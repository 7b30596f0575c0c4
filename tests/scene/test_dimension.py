"""Dimensions after ISO 129: the geometry of a dimension on hand-computed points, the values of
generated parts' extents and circle diameters (vector lines and pictures alike), a glyph file's
[[dimension]] entries, and bad input."""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import shapely.geometry as sg
import trimesh
from helpers import no_output, one_error, run_cli

import blueprint
from blueprint.api.files import render_vector_file
from blueprint.compose.glyphs import Dimension, Glyphs
from blueprint.compose.glyphs.marks import dimension_glyph_marks
from blueprint.scene.camera import fit_camera
from blueprint.scene.dimension import diameter_marks, format_value, linear_dimension
from blueprint.scene.model import Model
from blueprint.vector.dimension import dimension_marks, find_circles

SVG = "{http://www.w3.org/2000/svg}"


def _model(mesh: trimesh.Trimesh, name: str = "part") -> Model:
    return Model.from_arrays(mesh.vertices, mesh.faces, part_names=[name], up="z")


@pytest.fixture(scope="module")
def cylinder() -> Model:
    """Ø 25 x 10, its axis along z (up), 64 sides."""
    return _model(trimesh.creation.cylinder(radius=12.5, height=10.0, sections=64), "cylinder")


@pytest.fixture(scope="module")
def ring() -> Model:
    """A ring of Ø 40 outside and Ø 16 inside, 6 high: seen from the top, the rims of each
    circle lie on one another."""
    outline = sg.Point(0, 0).buffer(20.0, quad_segs=32).difference(sg.Point(0, 0).buffer(8.0, quad_segs=32))
    return _model(trimesh.creation.extrude_polygon(outline, 6.0), "ring")


def test_values_are_printed_with_at_most_one_decimal():
    assert [format_value(v) for v in (127.0, 63.5, 34.925, 0.04, -0.01, 12.25)] == [
        "127",
        "63.5",
        "34.9",
        "0",
        "0",
        "12.2",
    ]


def test_a_horizontal_dimension_by_hand():
    # 1 pixel a millimetre: the gap 1, the overshoot 2, the offset 8, the arrow 3, the text 3.5
    marks = linear_dimension([10.0, 50.0], [110.0, 50.0], [0.0, 1.0], "100", per_mm=1.0)
    first, second, line = marks.lines[:3]
    np.testing.assert_allclose(first, [[10, 51], [10, 60]])
    np.testing.assert_allclose(second, [[110, 51], [110, 60]])
    np.testing.assert_allclose(line, [[10, 58], [110, 58]])
    # arrowheads: tips at the line's ends, 3 long, 15° to each side
    spread = 3 * math.tan(math.radians(15))
    left, right = marks.lines[3:6], marks.lines[6:9]
    np.testing.assert_allclose(left[:2, 0], [[10, 58], [10, 58]])
    np.testing.assert_allclose(sorted(left[:2, 1].tolist()), [[13, 58 - spread], [13, 58 + spread]])
    np.testing.assert_allclose(sorted(right[:2, 1].tolist()), [[107, 58 - spread], [107, 58 + spread]])
    (text,) = marks.texts
    assert (text.x, text.y, text.height, text.text, text.anchor, text.angle) == (
        60.0,
        pytest.approx(58 - 1.4),
        3.5,
        "100",
        "middle",
        0.0,
    )
    assert np.all(marks.widths == 0.7)


def test_a_vertical_dimension_reads_from_the_right():
    marks = linear_dimension([200.0, 10.0], [200.0, 90.0], [1.0, 0.0], "80", per_mm=2.0)
    np.testing.assert_allclose(marks.lines[2], [[216, 10], [216, 90]])
    (text,) = marks.texts
    # turned a quarter anticlockwise, its baseline left of the line
    assert text.angle == pytest.approx(90.0) and text.x == pytest.approx(216 - 0.4 * 7.0)
    assert text.y == pytest.approx(50.0)


def test_a_diameter_by_hand():
    marks = diameter_marks([100.0, 100.0], 20.0, "Ø 10", per_mm=1.0)
    u = np.array([1.0, -1.0]) / math.sqrt(2)
    np.testing.assert_allclose(marks.lines[0], [[100, 100] - 20 * u, [100, 100] + 20 * u])
    (text,) = marks.texts
    assert text.text == "Ø 10" and text.x > 100 + 20 / math.sqrt(2)


def test_cylinder_diameter_and_extents(cylinder):
    size = (400, 300)
    top = fit_camera(cylinder, size, "top", ortho=True)
    rims = find_circles(cylinder, top.view_matrix(), top.projection_matrix(), size)
    assert [c.radius for c in rims] == pytest.approx([12.5, 12.5], rel=1e-6)
    np.testing.assert_allclose(sorted(c.centre.tolist() for c in rims), [[0, 0, -5], [0, 0, 5]], atol=1e-5)
    marks = dimension_marks(cylinder, top.view_matrix(), top.projection_matrix(), size, 1.0, None)
    assert [t.text for t in marks.texts] == ["25", "25", "Ø 25"]
    # in inches, the same numbers in millimetres
    marks = dimension_marks(cylinder, top.view_matrix(), top.projection_matrix(), size, 25.4, None)
    assert [t.text for t in marks.texts] == ["635", "635", "Ø 635"]
    # seen from the front the circles are edge-on: no diameter
    front = fit_camera(cylinder, size, "front", ortho=True)
    marks = dimension_marks(cylinder, front.view_matrix(), front.projection_matrix(), size, 1.0, None)
    assert [t.text for t in marks.texts] == ["25", "10"]


def test_rims_seen_on_one_another_are_dimensioned_once(ring):
    size = (300, 300)
    top = fit_camera(ring, size, "top", ortho=True)
    circles = find_circles(ring, top.view_matrix(), top.projection_matrix(), size)
    # the top and bottom rims of each circle
    assert sorted(round(2 * c.radius, 6) for c in circles) == [16.0, 16.0, 40.0, 40.0]
    marks = dimension_marks(ring, top.view_matrix(), top.projection_matrix(), size, 1.0, None)
    assert sorted(t.text for t in marks.texts) == sorted(["40", "40", "Ø 40", "Ø 16"])


def test_a_polygon_is_not_a_circle():
    hexagon = _model(trimesh.creation.cylinder(radius=10.0, height=4.0, sections=6))
    camera = fit_camera(hexagon, (200, 200), "top", ortho=True)
    assert find_circles(hexagon, camera.view_matrix(), camera.projection_matrix(), (200, 200)) == []


def test_picture_and_vectors_print_the_same_numbers(renderer, cylinder, tmp_path):
    frame = blueprint.render_frame(
        cylinder, size=(400, 300), view="top", ortho=True, dimensions=True, units="cm", renderer=renderer
    )
    assert [t.text for t in frame.marks.texts] == ["250", "250", "Ø 250"]
    path = tmp_path / "top.svg"
    render_vector_file(
        cylinder,
        path,
        size=(400, 300),
        view="top",
        ortho=True,
        dimensions=True,
        units="cm",
        renderer=renderer,
    )
    texts = [t.text for t in ET.parse(path).getroot().iter(f"{SVG}text")]
    assert texts[-3:] == ["250", "250", "Ø 250"]


def test_picture_draws_the_dimension_lines_where_the_marks_are(renderer, cylinder):
    size = (400, 300)
    plain = blueprint.render_frame(cylinder, size=size, view="front", ortho=True, renderer=renderer)
    frame = blueprint.render_frame(
        cylinder, size=size, view="front", ortho=True, dimensions=True, renderer=renderer
    )
    camera = frame.camera
    (width_line,) = [seg for seg in frame.marks.lines[:3] if seg[0, 1] == seg[1, 1]]
    (x0, y), (x1, _) = width_line
    # the line spans the cylinder's 25 exactly
    assert (x1 - x0) * camera.height / size[1] == pytest.approx(25.0, rel=1e-9)
    row = int(y)
    inked = np.abs(frame.image.astype(int) - plain.image.astype(int)).max(axis=2) > 40
    columns = np.flatnonzero(inked[row - 1 : row + 2].any(axis=0))
    assert columns.min() == pytest.approx(x0, abs=1.5) and columns.max() == pytest.approx(x1, abs=1.5)


def test_dimension_glyph_between_two_points():
    cylinder = trimesh.creation.cylinder(radius=12.5, height=10.0, sections=64)
    model = _model(cylinder)
    camera = fit_camera(model, (400, 300), "front", ortho=True)
    view, projection = camera.view_matrix(), camera.projection_matrix()
    dimension = Dimension((-12.5, 0.0, -5.0), (12.5, 0.0, -5.0), offset=-6.0)
    marks = dimension_glyph_marks(dimension, view, projection, (400, 300), 1.0, 1.0)
    assert [t.text for t in marks.texts] == ["25"]
    per_px = camera.height / 300
    line = marks.lines[2]
    # 6 model units below the points (to the right of from -> to), 25 long
    assert np.ptp(line[:, 0]) * per_px == pytest.approx(25.0)
    below = (line[0, 1] - marks.lines[0, 0, 1] + 1.0) * per_px  # the extension line's gap is 1 px
    assert below == pytest.approx(6.0)
    texted = dimension_glyph_marks(Dimension((0, 0, 0), (0, 0, 1), "h7"), view, projection, (400, 300), 1, 1)
    assert [t.text for t in texted.texts] == ["h7"]
    # seen end on, nothing to draw
    end_on = Dimension((0.0, -5.0, 0.0), (0.0, 5.0, 0.0))
    assert len(dimension_glyph_marks(end_on, view, projection, (400, 300), 1.0, 1.0).lines) == 0


def test_glyph_file_dimensions_in_picture_and_vectors(renderer, tmp_path):
    model = _model(trimesh.creation.box((50.0, 20.0, 10.0)))
    glyphs = tmp_path / "dims.toml"
    glyphs.write_text(
        "[[dimension]]\nfrom = [-25, 0, 5]\nto = [25, 0, 5]\n\n"
        '[[dimension]]\nfrom = [0, 0, -5]\nto = [0, 0, 5]\ntext = "10 h7"\ncolor = "#00ff00"\n'
    )
    size = (400, 300)
    plain = blueprint.render(model, size=size, view="front", ortho=True, style="paper", renderer=renderer)
    image = blueprint.render(
        model,
        size=size,
        view="front",
        ortho=True,
        style="paper",
        glyphs=glyphs,
        units="in",
        renderer=renderer,
    )
    green = (image[..., 1].astype(int) - image[..., 0] > 80) & (
        np.abs(image.astype(int) - plain).max(axis=2) > 40
    )
    assert green.sum() > 50  # the second dimension, in its colour
    path = tmp_path / "front.svg"
    render_vector_file(
        model, path, size=size, view="front", ortho=True, glyphs=glyphs, units="in", renderer=renderer
    )
    texts = [t.text for t in ET.parse(path).getroot().iter(f"{SVG}text")]
    assert "1270" in texts and "10 h7" in texts


def test_vector_drawings_take_dimensions_beside_other_glyphs(renderer, tmp_path):
    """A glyph file's labels are drawn by the vector glyphs, its dimensions as dimensions: both
    in one drawing."""
    model = _model(trimesh.creation.box((50.0, 20.0, 10.0)))
    glyphs = Glyphs.from_dict(
        {
            "label": [{"at": [0, 0, 5], "text": "lid"}],
            "dimension": [{"from": [-25, -10, 5], "to": [25, -10, 5], "text": "50 h7"}],
        },
        "marks.toml",
    )
    path = tmp_path / "front.svg"
    render_vector_file(
        model, path, size=(200, 120), view="front", ortho=True, glyphs=glyphs, renderer=renderer
    )
    texts = [t.text for t in ET.parse(path).getroot().iter(f"{SVG}text")]
    assert "lid" in texts and "50 h7" in texts


@pytest.mark.parametrize(
    "entry, mentions",
    [
        (
            "from = [0, 0]\nto = [1, 0, 0]",
            ["dimension 1: from must be 3 numbers [x, y, z] in model coordinates, got [0, 0]"],
        ),
        ('from = [0, 0, 0]\nto = "1,0,0"', ["dimension 1: to must be 3 numbers [x, y, z]"]),
        ("from = [0, 0, 0]\nto = [0, 0, 0]", ["dimension 1: from and to are the same point"]),
        ("from = [0, 0, 0]\nto = [1, 0, 0]\noffset = 'far'", ["dimension 1: offset must be a number"]),
        ("from = [0, 0, 0]", ["dimension 1", "to"]),
    ],
)
@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_bad_dimension_glyph_is_one_line(tmp_path, entry, mentions, suffix):
    model = tmp_path / "box.obj"
    model.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    glyphs = tmp_path / "dims.toml"
    glyphs.write_text(f"[[dimension]]\n{entry}\n")
    folder = tmp_path / "out"
    folder.mkdir()
    proc = run_cli(
        "render",
        model,
        "-o",
        folder / f"x{suffix}",
        "--size",
        64,
        64,
        "--view",
        "front",
        "--ortho",
        "--glyphs",
        glyphs,
    )
    one_error(proc, str(glyphs), *mentions)
    no_output(folder)


def test_featuretype_plan_picture_shows_the_extents_in_mm(renderer, shared_models):
    model = blueprint.load_model(shared_models / "trimesh" / "featuretype.STL")  # 5 x 2.5 x 1.375 in
    frame = blueprint.render_frame(
        model, size=(800, 600), view="plan", dimensions=True, units="in", renderer=renderer
    )
    numbers = sorted(t.text for t in frame.marks.texts if re.fullmatch(r"[0-9.]+", t.text))
    assert numbers == sorted(["127", "63.5", "127", "34.9", "63.5", "34.9"])
    assert {"Ø 9.9", "8× Ø 6.8", "8× Ø 11.1"} <= {t.text for t in frame.marks.texts}
