"""Line style files (TOML or JSON): per-level colour, width, dash and opacity for vector drawings
and pictures, from the command line too."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import ROOT, run_cli
from PIL import Image
from vector_helpers import svg_line_paths

from blueprint.errors import InputError
from blueprint.examples import gearbox
from blueprint.vector import LineStyle, draw_vector, load_vector_style, save_drawing, vector_style

EXAMPLE = ROOT / "examples" / "lines.toml"


def test_the_example_file():
    style = load_vector_style(EXAMPLE)
    assert style.name == "lines" and style.paper == (1.0, 1.0, 1.0)
    assert style.fade == 0.75 and style.highlight_width == 2.0
    assert len(style.levels) == 4
    assert style.levels[0] == LineStyle("#000000", 1.4, (), 1.0)
    assert style.levels[1] == LineStyle("#1d4f91", 0.7, (6.0, 3.0), 0.85)
    assert style.levels[2] == LineStyle("#1d4f91", 0.5, (3.0, 3.0), 0.6)
    # past the last level listed: the last one, fading
    assert style.level(5).opacity == pytest.approx(0.4 * 0.75**2)


def test_what_a_file_leaves_out_comes_from_its_base(tmp_path):
    path = tmp_path / "mine.json"
    path.write_text(json.dumps({"base": "blueprint", "levels": [{"width": 2}, {}], "paper": "none"}))
    style, base = load_vector_style(path), vector_style("blueprint")
    assert style.paper is None
    assert style.levels[0] == LineStyle(base.levels[0].color, 2.0, (), base.levels[0].opacity)
    assert style.levels[1] == base.levels[1]
    assert style.highlight_color == base.highlight_color and style.fade == base.fade
    empty = tmp_path / "empty.toml"
    empty.write_text("")
    assert load_vector_style(empty).levels == base.levels


BAD = [
    ("x.yaml", "", "line style file must end in .toml or .json"),
    ("x.toml", "levels = 3\n", "levels must be a non-empty list of tables"),
    ("x.toml", "colour = '#000000'\n", "unknown key 'colour'"),
    ("x.toml", "base = 'sepia'\n", "base must be one of blueprint, paper, transparent, wireframe"),
    ("x.toml", "paper = 'white'\n", "paper 'white' is not of the form #rrggbb"),
    ("x.toml", "fade = 2\n", "fade must be in [0, 1]"),
    ("x.toml", "[[levels]]\ncolor = 'navy'\n", "levels 0: color 'navy' is not of the form #rrggbb"),
    ("x.toml", "[[levels]]\n[[levels]]\ndash = [6, 3, 1]\n", "levels 1: dash must be an even count"),
    ("x.toml", "[[levels]]\nopacity = -0.5\n", "levels 0: opacity must be in [0, 1]"),
    ("x.toml", "[[levels]]\nwidth = 0\n", "levels 0: width must be in (0, 16]"),
    (
        "x.toml",
        "[[levels]]\nstyle = 1\n",
        "levels 0: unknown key 'style' (allowed: color, width, dash, opacity)",
    ),
    ("x.toml", "levels = [", "not valid TOML"),
]


@pytest.mark.parametrize(("name", "text", "message"), BAD, ids=[m for _, _, m in BAD])
def test_bad_files_name_the_file_and_the_entry(tmp_path, name, text, message):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError) as caught:
        load_vector_style(path)
    assert str(caught.value).startswith(str(path)) and message in str(caught.value)
    assert "\n" not in str(caught.value)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        load_vector_style(tmp_path / "gone.toml")


def test_svg_strokes_each_level_as_the_file_says(renderer, tmp_path):
    drawing = draw_vector(gearbox(), size=(200, 150), style=load_vector_style(EXAMPLE), renderer=renderer)
    save_drawing(tmp_path / "g.svg", drawing)
    # each level's stroke on its group, in the lines group's grid units (a tenth of a pixel)
    seen = {}
    for _, level, _, scale in svg_line_paths(tmp_path / "g.svg"):
        dash = level.get("stroke-dasharray")
        dash = dash and " ".join(f"{float(v) * scale:g}" for v in dash.split())
        seen[level.get("class")] = (level.get("stroke"), dash)
    assert seen["level-0"] == ("#000000", None)
    assert seen["level-1"] == ("#1d4f91", "6 3")
    assert seen["level-2"] == ("#1d4f91", "3 3")


def test_command_line(tmp_path):
    model = ROOT / "src" / "blueprint" / "data" / "gearbox.glb"
    svg = tmp_path / "g.svg"
    done = run_cli("render", model, "-o", svg, "--size", "96", "72", "--style", EXAMPLE)
    assert done.returncode == 0, done.stderr
    assert 'stroke="#1d4f91"' in svg.read_text()


def test_a_picture_takes_the_file_too(tmp_path):
    """``--style lines.toml`` for a PNG: the file's paper exactly, visible lines in level 0's
    colour (the darkest pixels), hidden ones in level 1's at its opacity."""
    model = ROOT / "src" / "blueprint" / "data" / "gearbox.glb"
    png = tmp_path / "g.png"
    done = run_cli("render", model, "-o", png, "--size", "256", "192", "--style", EXAMPLE)
    assert done.returncode == 0, done.stderr
    image = np.asarray(Image.open(png).convert("RGB")).astype(int)
    assert (image[0] == 255).all()  # paper "#ffffff" along the top margin
    assert (image.min(axis=(0, 1)) <= 2).all()  # level 0 black where a line covers a pixel
    # level 1 "#1d4f91" at 0.85 over white, give or take anti-aliasing, on many pixels
    hidden = np.round(0.85 * np.array([0x1D, 0x4F, 0x91]) + 0.15 * 255)
    tinted = (image[..., 2] - image[..., 0] > 20).sum()
    assert tinted > 100
    assert (image[..., 2] - image[..., 0]).max() <= hidden[2] - hidden[0] + 2


def test_a_picture_refuses_a_bad_file_in_one_line(tmp_path):
    model = ROOT / "src" / "blueprint" / "data" / "gearbox.glb"
    bad = tmp_path / "bad.toml"
    bad.write_text("[[levels]]\nwidth = 'wide'\n")
    png = tmp_path / "g.png"
    done = run_cli("render", model, "-o", png, "--style", bad)
    assert done.returncode == 2 and not png.exists()
    assert done.stderr.strip().count("\n") == 0
    assert f"{bad}: levels 0: width must be a number" in done.stderr, done.stderr


def test_a_pictures_style_follows_the_levels():
    """The raster style of the example file: each layer's ink is the file's level (colour and
    opacity, fading past the last) as the vector drawing strokes it; level 0's and 1's widths."""
    from blueprint.compose.linestyle import load_raster_style

    raster, vector = load_raster_style(EXAMPLE), load_vector_style(EXAMPLE)
    inks = raster.layer_inks(7)
    for k in range(7):
        line = vector.level(k)
        np.testing.assert_allclose(inks[k], (*line.color, line.opacity), atol=1e-6)
    assert raster.paper == (1.0, 1.0, 1.0, 1.0) and raster.width == 1.4 and raster.hidden_width == 0.7
    assert raster.highlight[:3] == vector.highlight_color and raster.highlight_width == 2.0


def test_a_pictures_highlight_width_is_checked_with_the_file_named(tmp_path):
    from blueprint.compose.linestyle import load_raster_style

    path = tmp_path / "thin.toml"
    path.write_text("highlight_width = 0.5\n")
    load_vector_style(path)  # a vector drawing takes it
    with pytest.raises(InputError, match=r"thin.toml: .*highlight_width must be in \[1, 8\]"):
        load_raster_style(path)
