"""Line style files (TOML or JSON): per-level colour, width, dash and opacity for vector drawings,
from the command line too."""

from __future__ import annotations

import json
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from vector_helpers import SVG

from blueprint.errors import InputError
from blueprint.examples import gearbox
from blueprint.vector import LineStyle, draw_vector, load_vector_style, save_drawing, vector_style

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "lines.toml"
BLUEPRINT = Path(sys.executable).parent / "blueprint"


def test_the_example_file():
    style = load_vector_style(EXAMPLE)
    assert style.name == "lines" and style.paper == (1.0, 1.0, 1.0)
    assert style.fade == 0.75 and style.highlight_width == 2.0
    assert len(style.levels) == 4
    assert style.levels[0] == LineStyle("#000000", 1.4, (), 1.0)
    assert style.levels[1] == LineStyle("#1d4f91", 1.0, (6.0, 3.0), 0.85)
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
    paths = ET.parse(tmp_path / "g.svg").getroot().iter(f"{SVG}path")
    seen = {p.get("class"): (p.get("stroke"), p.get("stroke-dasharray")) for p in paths}
    assert seen["level-0"] == ("#000000", None)
    assert seen["level-1"] == ("#1d4f91", "6 3")
    assert seen["level-2"] == ("#1d4f91", "3 3")


def test_command_line(tmp_path):
    model = ROOT / "src" / "blueprint" / "data" / "gearbox.glb"
    svg = tmp_path / "g.svg"
    done = subprocess.run(
        [BLUEPRINT, "render", model, "-o", svg, "--size", "96", "72", "--style", EXAMPLE],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    assert 'stroke="#1d4f91"' in svg.read_text()
    png = tmp_path / "g.png"
    done = subprocess.run(
        [BLUEPRINT, "render", model, "-o", png, "--style", EXAMPLE], capture_output=True, text=True
    )
    assert done.returncode == 2 and not png.exists()
    assert done.stderr.strip().count("\n") == 0 and "line style files are for vector drawings" in done.stderr
