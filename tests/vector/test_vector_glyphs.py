"""Glyphs in vector drawings: a glyph behind a wall comes out dashed (SVG, PDF, DXF), dimmed or
left out as the glyph file says, and the command line takes --glyphs for vector files."""

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from helpers import project, run_cli
from vector_helpers import SVG, parse_path

from blueprint.compose.glyphs import Glyphs
from blueprint.examples import assemble, box
from blueprint.scene.camera import Camera
from blueprint.vector import draw_vector, save_drawing

SIZE = (128, 128)
WALL = ((-2.0, -2.0, -0.1), (2.0, 2.0, 0.1))


def _scene(renderer, mode="dashed"):
    """A wall seen from the front; a red path runs across behind it, a label floats in front."""
    model = assemble({"wall": box(*WALL)})
    camera = Camera.fit(np.array([[-3, -3, -3], [3, 3, 3.0]]), "front", aspect=1.0, ortho=True)
    glyphs = Glyphs.from_dict(
        {
            "hidden": {"mode": mode, "dash": [4, 3], "opacity": 0.25},
            "path": [{"points": [[-3, 0, -1], [3, 0, -1]], "color": "#ff0000"}],
            "label": [{"at": [0, 2.5, 1], "text": "front"}, {"at": [0, -1, -1], "text": "back"}],
        }
    )
    drawing = draw_vector(model, camera, SIZE, renderer=renderer, glyphs=glyphs)
    view, proj = camera.view_matrix(), camera.projection_matrix()
    wall_x = project(np.array([[WALL[0][0], 0, 0.1], [WALL[1][0], 0, 0.1]]), view, proj, SIZE)[:, 0]
    path_x = project(np.array([[-3, 0, -1], [3, 0, -1.0]]), view, proj, SIZE)[:, 0]
    return drawing, wall_x, path_x


def _glyph_paths(svg_path):
    root = ET.parse(svg_path).getroot()
    group = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "glyphs")
    return group, [(p.get("class"), p.attrib, parse_path(p.get("d"))[0]) for p in group.findall(f"{SVG}path")]


def test_a_glyph_behind_a_wall_comes_out_dashed(renderer, tmp_path):
    drawing, wall_x, path_x = _scene(renderer)
    group, paths = _glyph_paths(save_drawing(tmp_path / "glyphs.svg", drawing))
    kinds = [kind for kind, _, _ in paths]
    assert kinds == ["glyph", "glyph-hidden", "glyph"]
    # the hidden stretch is exactly the wall's width on screen (within the depth test's pixel)
    _, hidden_attrs, hidden = paths[1]
    assert hidden_attrs["stroke-dasharray"] == "4 3" and hidden_attrs["stroke"] == "#ff0000"
    assert sorted(hidden[:, 0]) == pytest.approx(sorted(wall_x), abs=1.5)
    # the visible stretches run from the path's ends to the wall, solid
    for _, attrs, _ in (paths[0], paths[2]):
        assert "stroke-dasharray" not in attrs
    ends = sorted(np.concatenate([paths[0][2][:, 0], paths[2][2][:, 0]]))
    assert ends[0] == pytest.approx(path_x.min(), abs=0.6) and ends[-1] == pytest.approx(
        path_x.max(), abs=0.6
    )
    # the label in front is plain, the one behind the wall marked hidden
    texts = {t.text: t.get("class") for t in group.findall(f"{SVG}text")}
    assert texts == {"front": "glyph", "back": "glyph-hidden"}


def test_the_pdf_and_dxf_dash_the_same_stretch(renderer, tmp_path):
    import ezdxf
    import pypdf

    drawing, wall_x, _ = _scene(renderer)
    reader = pypdf.PdfReader(save_drawing(tmp_path / "glyphs.pdf", drawing))
    names = [g.get_object()["/Name"] for g in reader.trailer["/Root"]["/OCProperties"]["/OCGs"]]
    assert "glyphs" in names
    content = reader.pages[0].get_contents().get_data().decode("latin-1")
    glyphs = re.search(r"/OC /GLYPHS BDC\n(.*?)\nEMC", content, re.S).group(1)
    # three polylines, the middle one with a 4 on, 3 off dash (0.75 pt a pixel)
    dashes = re.findall(r"\[([0-9. ]+)\] [0-9.]+ d", glyphs)
    assert [d.split() for d in dashes if d.strip()] == [["3.000", "2.250"]]
    doc = ezdxf.readfile(save_drawing(tmp_path / "glyphs.dxf", drawing))
    hidden = [e for e in doc.modelspace().query("LWPOLYLINE") if e.dxf.layer == "GLYPHS-HIDDEN"]
    assert len(hidden) == 1
    assert doc.layers.get("GLYPHS-HIDDEN").dxf.linetype == "BP_GLYPH_HIDDEN"
    xs = sorted(p[0] for p in hidden[0].get_points("xy"))
    assert xs == pytest.approx(sorted(wall_x), abs=1.5)


def test_dim_and_none_modes(renderer, tmp_path):
    dim, _, _ = _scene(renderer, "dim")
    _, paths = _glyph_paths(save_drawing(tmp_path / "dim.svg", dim))
    assert [kind for kind, _, _ in paths] == ["glyph", "glyph-hidden", "glyph"]
    assert paths[1][1]["stroke-opacity"] == "0.25" and "stroke-dasharray" not in paths[1][1]
    none, _, _ = _scene(renderer, "none")
    group, paths = _glyph_paths(save_drawing(tmp_path / "none.svg", none))
    assert [kind for kind, _, _ in paths] == ["glyph", "glyph"]
    assert [t.text for t in group.findall(f"{SVG}text")] == ["front"]


def test_glyphs_on_the_command_line_for_an_svg(tmp_path):
    from blueprint.examples import gearbox, write_glb

    model = tmp_path / "gearbox.glb"
    write_glb(gearbox(), model)
    glyph_file = tmp_path / "marks.toml"
    glyph_file.write_text('[[box]]\nmin = [-7, 14, -26]\nmax = [7, 66, 26]\nlabel = "gear"\n')
    out = tmp_path / "g.svg"
    result = run_cli("render", model, "-o", out, "--size", 160, 120, "--glyphs", glyph_file)
    assert result.returncode == 0, result.stderr
    root = ET.parse(out).getroot()
    group = next(g for g in root.iter(f"{SVG}g") if g.get("id") == "glyphs")
    assert len(group.findall(f"{SVG}path")) >= 2 and [t.text for t in group.findall(f"{SVG}text")] == ["gear"]
    bad = tmp_path / "bad.toml"
    bad.write_text("[[box]]\nmin = [0, 0]\n")
    result = run_cli("render", model, "-o", tmp_path / "b.svg", "--glyphs", bad)
    assert result.returncode == 2 and "bad.toml" in result.stderr and "Traceback" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "b.svg").exists()
