"""Shaded parts in vector drawings: filled faces in depth order, lit as the raster lights them,
with the lines behind them drawn before them and the rest after."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest
from helpers import project
from vector_helpers import SVG, parse_path

from blueprint.compose.style import STYLES
from blueprint.examples import assemble, box
from blueprint.scene.camera import Camera
from blueprint.vector import draw_vector, save_drawing

SIZE = (160, 160)
PLATE = ((-1.0, -1.0, 0.5), (1.0, 1.0, 0.7))
BLOCK = ((-2.0, -0.5, -1.0), (2.0, 0.5, -0.2))


def _scene(renderer, **options):
    """A plate in front of a long block, seen from the front: the block's middle is behind the
    plate, its ends stick out left and right."""
    model = assemble({"plate": box(*PLATE), "block": box(*BLOCK)})
    camera = Camera.fit(np.array([[-2.5, -2.5, -2.5], [2.5, 2.5, 2.5]]), "front", aspect=1.0, ortho=True)
    drawing = draw_vector(model, camera, SIZE, renderer=renderer, shade="plate", **options)
    view, proj = camera.view_matrix(), camera.projection_matrix()
    corners = project(np.array([PLATE[0], PLATE[1]]), view, proj, SIZE)
    return model, drawing, np.sort(corners, axis=0)


def test_lines_behind_the_shaded_plate_go_under_it(renderer, tmp_path):
    model, drawing, (lo, hi) = _scene(renderer)
    block = model.part_names.index("block")
    assert drawing.behind is not None and drawing.behind.any() and (~drawing.behind).any()
    for i in range(len(drawing)):
        points = drawing.polyline(i)
        inside = np.all((points >= lo - 1.5) & (points <= hi + 1.5), axis=1)
        if drawing.behind[i]:
            # behind the plate: the block's lines there, inside the plate's outline
            assert drawing.part[i] == block and inside.all()
        elif drawing.part[i] == block:
            # the rest of the block's lines lie outside the plate (up to its edge)
            strictly = np.all((points > lo + 1.5) & (points < hi - 1.5), axis=1)
            assert not strictly.any()
    root = ET.parse(save_drawing(tmp_path / "shade.svg", drawing)).getroot()
    order = [g.get("id") for g in root if g.tag == f"{SVG}g"]
    assert order == ["lines-behind-shading", "shading", "lines"]
    under = next(g for g in root if g.get("id") == "lines-behind-shading")
    drawn = [line for p in under.iter(f"{SVG}path") for line in parse_path(p.get("d"))]
    assert len(drawn) == int(drawing.behind.sum())


def test_lines_behind_the_shading_read_the_one_faces_kbuffer(renderer, monkeypatch):
    """The count of the shaded parts' surfaces in front reads the faces k-buffer that the
    occlusion levels read: it is drawn once a drawing."""
    calls = []
    draw = renderer.face_kbuffer

    def counted(*args, **kwargs):
        calls.append(args)
        return draw(*args, **kwargs)

    monkeypatch.setattr(renderer, "face_kbuffer", counted)
    _, drawing, _ = _scene(renderer)
    assert drawing.behind.any()
    assert len(calls) == 1


def test_one_part_index_alone_shades_as_a_list_of_it(renderer, tmp_path):
    from blueprint.api.files import render_vector_file

    model = assemble({"plate": box(*PLATE), "block": box(*BLOCK)})
    alone, listed = tmp_path / "alone.svg", tmp_path / "listed.svg"
    for path, shade in ((alone, 0), (listed, [0]), (tmp_path / "numpy.svg", np.int64(0))):
        render_vector_file(model, path, size=SIZE, view="front", shade=shade, renderer=renderer)
    assert alone.read_bytes() == listed.read_bytes() == (tmp_path / "numpy.svg").read_bytes()
    assert b'id="shading"' in alone.read_bytes()


def test_shaded_faces_back_to_front_in_the_style_colour(renderer, tmp_path):
    _, drawing, (lo, hi) = _scene(renderer, style="paper")
    shading = drawing.shading
    # of the plate's 12 triangles, seen from the front, its four sides are edge-on: the back
    # pair comes first, the front pair last, both lit head-on: exactly the style's shade colour
    assert len(shading) == 4
    front = shading.points[-2:].reshape(-1, 2)
    assert np.allclose(front.min(axis=0), lo) and np.allclose(front.max(axis=0), hi)
    np.testing.assert_allclose(shading.color, [STYLES["paper"].shade[:3]] * 4)
    import ezdxf
    import pypdf

    doc = ezdxf.readfile(save_drawing(tmp_path / "shade.dxf", drawing))
    assert len(doc.modelspace().query("SOLID")) == 4
    reader = pypdf.PdfReader(save_drawing(tmp_path / "shade.pdf", drawing))
    names = [g.get_object()["/Name"] for g in reader.trailer["/Root"]["/OCProperties"]["/OCGs"]]
    assert "shading" in names


def test_see_through_shading_and_bad_opacity(renderer, tmp_path):
    from blueprint.errors import InputError

    _, drawing, _ = _scene(renderer, shade_opacity=0.4)
    root = ET.parse(save_drawing(tmp_path / "half.svg", drawing)).getroot()
    shading = next(g for g in root if g.get("id") == "shading")
    assert shading.get("opacity") == "0.4"
    with pytest.raises(InputError, match="shade_opacity"):
        _scene(renderer, shade_opacity=0.0)


def test_faces_come_back_to_front_and_lit_by_their_turn_to_the_eye():
    from blueprint.scene.model import Model
    from blueprint.vector.shade import AMBIENT, shaded_faces

    # three triangles listed near to far, the nearest tilted 60 degrees from the view
    tilt = np.radians(60)
    positions = np.array(
        [
            [0, 0, 1],
            [1, 0, 1 - np.tan(tilt)],
            [0, 1, 1],
            [0, 0, 0],
            [1, 0, 0],
            [0, 1, 0],
            [0, 0, -5],
            [1, 0, -5],
            [0, 1, -5],
        ],
        float,
    )
    model = Model.from_arrays(positions, np.arange(9).reshape(3, 3), np.zeros(3, int), ("p",))
    camera = Camera.fit(positions, "front", aspect=1.0, ortho=True)
    got = shaded_faces(
        model, np.arange(3), camera.view_matrix(), camera.projection_matrix(), (64, 64), (1.0, 0.5, 0.25), 1.0
    )
    # painted far to near: the tilted one last
    light = np.array([1.0, 1.0, AMBIENT + (1 - AMBIENT) * np.cos(tilt)])
    np.testing.assert_allclose(got.color, light[:, None] * [1.0, 0.5, 0.25])
