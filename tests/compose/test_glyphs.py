"""Glyphs drawn into the blueprint's depth: where they land, what hides them, how hidden pieces
look in each mode, labels, and one-line errors for bad glyph files.

Positions are checked against the camera's own matrices, projected by the tests' own helper;
hidden or visible is decided by hand-built scenes (a cube, a thin wall in front of a line), so
every expected pixel is known without the code under test.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers import ROOT, project

from blueprint import Camera, InputError, examples
from blueprint.compose.glyphs import Glyphs, draw_glyphs, load_glyphs, render_with_glyphs


# -- helpers -----------------------------------------------------------------------------------
def alpha_at(image, camera, point, size, radius: int = 0) -> int:
    """Largest alpha within ``radius`` pixels of the point's pixel."""
    x, y = (int(np.floor(v)) for v in project(point, camera, size=size))
    patch = image[max(y - radius, 0) : y + radius + 1, max(x - radius, 0) : x + radius + 1, 3]
    return int(patch.max())


def _distance(point, segment) -> float:
    """Distance from a 2D point to a 2D segment (2, 2)."""
    p, a, b = np.asarray(point), segment[0], segment[1]
    t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0, 1)
    return float(np.linalg.norm(p - a - t * (b - a)))


def front_depth(renderer, model, camera, size) -> np.ndarray:
    return renderer.peel(model, camera, size=size, max_layers=1).depth[0]


def blank(size) -> np.ndarray:
    return np.zeros((size[1], size[0], 4), np.uint8)


def glyphs(hidden="none", **kinds) -> Glyphs:
    return Glyphs.from_dict({"hidden": {"mode": hidden}, **kinds}, "test")


GREEN = (0, 255, 0)


# -- a box glyph around a cube -----------------------------------------------------------------
CUBE = examples.assemble({"cube": examples.box((-1, -1, -1), (1, 1, 1))})
CUBE_SIZE = (160, 160)
CORNERS = [np.array([x, y, z]) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
# not the exact iso view, where the nearest and the farthest corner fall on one pixel
CUBE_CAMERA = Camera.fit(1.3 * np.array(CORNERS), "iso", azimuth=30, elevation=25)
FAR = np.array([-1, -1, -1])  # the iso camera looks from +x +y +z


@pytest.fixture(scope="module")
def cube_depth(renderer):
    return front_depth(renderer, CUBE, CUBE_CAMERA, CUBE_SIZE)


def test_box_glyph_lands_on_its_projected_corners(cube_depth):
    box = {"min": [-1.25] * 3, "max": [1.25] * 3, "color": "#00ff00", "width": 3}
    image = draw_glyphs(blank(CUBE_SIZE), glyphs("none", box=[box]), CUBE_CAMERA, cube_depth)
    for corner in CORNERS:
        point = corner * 1.25
        x, y = (int(np.floor(v)) for v in project(point, CUBE_CAMERA, size=CUBE_SIZE))
        if (corner == FAR).all():
            # behind the cube, with the three edges that meet there: nothing in mode none
            assert image[y - 2 : y + 3, x - 2 : x + 3, 3].max() == 0
        else:
            assert tuple(image[y, x, :3]) == GREEN and image[y, x, 3] >= 200, corner


def test_hidden_corner_is_dimmed_in_dim_mode(cube_depth):
    data = {"hidden": {"mode": "dim", "opacity": 0.4}, "box": [{"min": [-1.25] * 3, "max": [1.25] * 3}]}
    image = draw_glyphs(blank(CUBE_SIZE), Glyphs.from_dict(data, "t"), CUBE_CAMERA, cube_depth)
    assert alpha_at(image, CUBE_CAMERA, FAR * 1.25, CUBE_SIZE, 1) == round(0.4 * 255)
    assert alpha_at(image, CUBE_CAMERA, -FAR * 1.25, CUBE_SIZE) == 255


def test_glyph_lying_on_visible_faces_is_visible(cube_depth):
    """The cube's own edges and lines drawn on its faces must not be hidden by those faces;
    the three edges at the far corner are behind them."""
    edges = glyphs("none", box=[{"min": [-1, -1, -1], "max": [1, 1, 1], "width": 3}])
    image = draw_glyphs(blank(CUBE_SIZE), edges, CUBE_CAMERA, cube_depth)
    # corner pairs that differ in one coordinate, each pair once
    edges = [(a, b) for a in CORNERS for b in CORNERS if (a < b).any() and np.abs(a - b).sum() == 2]
    assert len(edges) == 12
    behind = [(a == FAR).all() or (b == FAR).all() for a, b in edges]
    seen = [
        np.array([project(p, CUBE_CAMERA, size=CUBE_SIZE) for p in edge])
        for edge, hidden in zip(edges, behind, strict=True)
        if not hidden
    ]
    checked_hidden = 0
    for (a, b), hidden in zip(edges, behind, strict=True):
        for t in (0.2, 0.4, 0.6, 0.8):
            point = a + t * (b - a)
            if hidden:
                # where a hidden edge crosses a visible one on screen, the visible one shows
                if min(_distance(project(point, CUBE_CAMERA, size=CUBE_SIZE), s) for s in seen) < 4:
                    continue
                checked_hidden += 1
            alpha = alpha_at(image, CUBE_CAMERA, point, CUBE_SIZE)
            assert (alpha == 0) if hidden else (alpha == 255), (a, b, t, alpha)
    assert checked_hidden >= 6
    on_faces = glyphs(
        "none",
        path=[
            {"points": [[-0.8, 1, -0.8], [0.8, 1, 0.8]], "width": 3},  # on the top face
            {"points": [[-0.8, -0.5, 1], [0.8, 0.5, 1]], "width": 3},  # on the front face
        ],
    )
    image = draw_glyphs(blank(CUBE_SIZE), on_faces, CUBE_CAMERA, cube_depth)
    for t in np.linspace(0, 1, 9):
        assert alpha_at(image, CUBE_CAMERA, [-0.8 + 1.6 * t, 1, -0.8 + 1.6 * t], CUBE_SIZE) == 255
        assert alpha_at(image, CUBE_CAMERA, [-0.8 + 1.6 * t, -0.5 + t, 1], CUBE_SIZE) == 255


# -- a line behind a wall ----------------------------------------------------------------------
# The wall covers x in [-1.5, 0] at z = 0; the line runs at z = -0.5 from x = -1 to 1, so its
# left half is behind the wall. Looking straight at it, the line is one row of the image.
WALL = examples.assemble({"wall": examples.box((-1.5, -1, -0.05), (0, 1, 0.05))})
WALL_SIZE = (160, 120)
WALL_CAMERA = Camera.fit(np.array([[-1.5, -1, -1], [1.5, 1, 1]]), "front", aspect=160 / 120)
LINE = {"points": [[-1, 0, -0.5], [1, 0, -0.5]], "color": "#00ff00", "width": 3}


@pytest.fixture(scope="module")
def wall_depth(renderer):
    return front_depth(renderer, WALL, WALL_CAMERA, WALL_SIZE)


def line_row(image) -> tuple[np.ndarray, np.ndarray]:
    """Alpha along the line's row: columns behind the wall and columns in the open, each kept
    clear of the wall's outline and the line's ends."""
    _, y = project([0, 0, -0.5], WALL_CAMERA, size=WALL_SIZE)
    row = image[int(np.floor(y)), :, 3]
    x_hidden = [project([x, 0, -0.5], WALL_CAMERA, size=WALL_SIZE)[0] for x in (-0.9, -0.15)]
    x_open = [project([x, 0, -0.5], WALL_CAMERA, size=WALL_SIZE)[0] for x in (0.15, 0.9)]
    return row[int(x_hidden[0]) : int(x_hidden[1])], row[int(x_open[0]) : int(x_open[1])]


def test_line_behind_wall_is_dimmed_in_dim_mode(wall_depth):
    data = {"hidden": {"mode": "dim", "opacity": 0.35}, "path": [LINE]}
    image = draw_glyphs(blank(WALL_SIZE), Glyphs.from_dict(data, "t"), WALL_CAMERA, wall_depth)
    hidden, visible = line_row(image)
    assert len(hidden) > 20 and len(visible) > 20
    np.testing.assert_array_equal(visible, 255)
    np.testing.assert_array_equal(hidden, round(0.35 * 255))
    assert (image[..., :3][image[..., 3] > 0] == GREEN).all()


def test_line_behind_wall_is_dashed_in_dashed_mode(wall_depth):
    data = {"hidden": {"mode": "dashed", "dash": [4, 3]}, "path": [LINE]}
    image = draw_glyphs(blank(WALL_SIZE), Glyphs.from_dict(data, "t"), WALL_CAMERA, wall_depth)
    hidden, visible = line_row(image)
    np.testing.assert_array_equal(visible, 255)
    ink = hidden > 127
    dashes = np.count_nonzero(ink[1:] & ~ink[:-1]) + int(ink[0])
    # a 7-pixel period along some 50 pixels: about 7 dashes, separated by clear gaps
    assert dashes >= 5, hidden
    assert hidden.max() == 255 and hidden.min() == 0


def test_line_behind_wall_is_left_out_in_none_mode(wall_depth):
    image = draw_glyphs(blank(WALL_SIZE), glyphs("none", path=[LINE]), WALL_CAMERA, wall_depth)
    hidden, visible = line_row(image)
    np.testing.assert_array_equal(visible, 255)
    np.testing.assert_array_equal(hidden, 0)


def test_orthographic_camera_hides_the_same(renderer):
    camera = Camera.fit(np.array([[-1.5, -1, -1], [1.5, 1, 1]]), "front", ortho=True, aspect=160 / 120)
    depth = front_depth(renderer, WALL, camera, WALL_SIZE)
    data = {"hidden": {"mode": "dim", "opacity": 0.35}, "path": [LINE]}
    image = draw_glyphs(blank(WALL_SIZE), Glyphs.from_dict(data, "t"), camera, depth)
    y = int(np.floor(project([0, 0, -0.5], camera, size=WALL_SIZE)[1]))
    for x, alpha in ((-0.6, round(0.35 * 255)), (-0.3, round(0.35 * 255)), (0.3, 255), (0.6, 255)):
        assert image[y, int(project([x, 0, -0.5], camera, size=WALL_SIZE)[0]), 3] == alpha, x


def test_render_with_glyphs_peels_the_front_layer_itself(renderer, wall_depth):
    frame = renderer.render(WALL, WALL_CAMERA, size=WALL_SIZE, style="transparent")
    g = glyphs("none", path=[LINE])
    image = render_with_glyphs(renderer, WALL, WALL_CAMERA, WALL_SIZE, g, frame.image)
    expected = draw_glyphs(frame.image, g, WALL_CAMERA, wall_depth)
    np.testing.assert_array_equal(image, expected)
    assert not np.array_equal(image, frame.image)


# -- labels ------------------------------------------------------------------------------------
def test_label_draws_text_beside_its_anchor(wall_depth):
    at = [0.3, 0.3, -0.5]
    g = glyphs("none", label=[{"at": at, "text": "gear", "color": "#00ff00", "anchor": "left"}])
    image = draw_glyphs(blank(WALL_SIZE), g, WALL_CAMERA, wall_depth)
    x, y = (int(v) for v in project(at, WALL_CAMERA, size=WALL_SIZE))
    ink = image[..., 3] > 0
    assert ink[y - 10 : y + 11, x + 1 : x + 50].sum() >= 20  # text to the right of the point
    assert ink.sum() == ink[y - 10 : y + 11, x + 1 : x + 50].sum()  # and nowhere else
    assert (image[ink][:, :3] == GREEN).all()


def test_hidden_label_follows_the_hidden_mode(wall_depth):
    label = {"at": [-0.8, 0.3, -0.5], "text": "gear", "anchor": "left"}
    none = draw_glyphs(blank(WALL_SIZE), glyphs("none", label=[label]), WALL_CAMERA, wall_depth)
    assert none[..., 3].max() == 0
    dim = Glyphs.from_dict({"hidden": {"mode": "dim", "opacity": 0.5}, "label": [label]}, "t")
    dimmed = draw_glyphs(blank(WALL_SIZE), dim, WALL_CAMERA, wall_depth)
    assert 0 < dimmed[..., 3].max() <= round(0.5 * 255)


# -- drawing details ---------------------------------------------------------------------------
def test_glyphs_composite_over_the_image_and_leave_the_rest(wall_depth):
    rng = np.random.default_rng(5)
    image = rng.integers(0, 256, (WALL_SIZE[1], WALL_SIZE[0], 4), dtype=np.uint8)
    before = image.copy()
    out = draw_glyphs(image, glyphs("none", path=[LINE]), WALL_CAMERA, wall_depth)
    np.testing.assert_array_equal(image, before)  # a new image; the input is untouched
    touched = np.any(out != image, axis=-1)
    _, y = project([0, 0, -0.5], WALL_CAMERA, size=WALL_SIZE)
    rows = np.flatnonzero(touched.any(axis=1))
    assert rows.min() >= int(y) - 3 and rows.max() <= int(y) + 2
    # full coverage over any background: the glyph's colour, opaque
    x = int(project([0.5, 0, -0.5], WALL_CAMERA, size=WALL_SIZE)[0])
    assert tuple(out[int(np.floor(y)), x]) == (*GREEN, 255)
    empty = draw_glyphs(image, Glyphs(), WALL_CAMERA, wall_depth)
    np.testing.assert_array_equal(empty, image)


def test_segment_through_the_near_plane_is_cut_there():
    camera = WALL_CAMERA
    eye = np.asarray(camera.eye)
    behind = eye + (eye - np.asarray(camera.target)) + [0.3, 0, 0]
    g = glyphs("none", path=[{"points": [behind.tolist(), [0.5, 0.5, 0]], "color": "#00ff00"}])
    image = draw_glyphs(blank(WALL_SIZE), g, camera, None)
    assert alpha_at(image, camera, [0.5, 0.5, 0], WALL_SIZE, 1) > 0
    assert image[..., 3].sum() > 0


def test_line_scale_widens_lines(wall_depth):
    g = glyphs("none", path=[LINE])
    thin = draw_glyphs(blank(WALL_SIZE), g, WALL_CAMERA, wall_depth)
    thick = draw_glyphs(blank(WALL_SIZE), g, WALL_CAMERA, wall_depth, line_scale=2.0)
    ratio = thick[..., 3].sum(dtype=np.int64) / thin[..., 3].sum(dtype=np.int64)
    assert 1.8 < ratio < 2.2


def test_bad_depth_shape_is_a_programming_error():
    with pytest.raises(ValueError, match="depth"):
        draw_glyphs(blank(WALL_SIZE), Glyphs(), WALL_CAMERA, np.ones((10, 10)))


# -- files -------------------------------------------------------------------------------------
SAMPLE = {
    "hidden": {"mode": "dashed", "opacity": 0.5, "dash": [3, 2]},
    "box": [{"min": [-1.25, -1.25, -1.25], "max": [1.25, 1.25, 1.25], "color": "#ff8800", "width": 2}],
    "arrow": [{"from": [1.2, 1.2, 1.2], "to": [0, 1, 0], "head": 0.2, "label": "top"}],
    "path": [{"points": [[-1, 0, 1], [0, 0.5, 1], [1, 0, 1]], "closed": True, "dash": [6, 4]}],
    "label": [{"at": [0, -1, 1], "text": "front", "size": 12, "anchor": "top"}],
}
SAMPLE_TOML = """
[hidden]
mode = "dashed"
opacity = 0.5
dash = [3, 2]

[[box]]
min = [-1.25, -1.25, -1.25]
max = [1.25, 1.25, 1.25]
color = "#ff8800"
width = 2

[[arrow]]
from = [1.2, 1.2, 1.2]
to = [0, 1, 0]
head = 0.2
label = "top"

[[path]]
points = [[-1, 0, 1], [0, 0.5, 1], [1, 0, 1]]
closed = true
dash = [6, 4]

[[label]]
at = [0, -1, 1]
text = "front"
size = 12
anchor = "top"
"""


def test_toml_and_json_give_the_same_glyphs_and_image(tmp_path, cube_depth):
    (tmp_path / "marks.toml").write_text(SAMPLE_TOML)
    (tmp_path / "marks.json").write_text(json.dumps(SAMPLE))
    from_toml = load_glyphs(tmp_path / "marks.toml")
    from_json = load_glyphs(tmp_path / "marks.json")
    assert from_toml.source.endswith("marks.toml") and len(from_toml) == 4
    a = draw_glyphs(blank(CUBE_SIZE), from_toml, CUBE_CAMERA, cube_depth)
    b = draw_glyphs(blank(CUBE_SIZE), from_json, CUBE_CAMERA, cube_depth)
    np.testing.assert_array_equal(a, b)
    assert (a[..., 3] > 0).sum() > 500


def test_shipped_example_marks_the_gearbox(renderer):
    from blueprint import load_model
    from blueprint.examples import example_path

    marks = load_glyphs(ROOT / "examples" / "marks.toml")
    model = load_model(example_path())
    size = (256, 192)
    camera = Camera.fit(model.positions, "iso", aspect=size[0] / size[1])
    image = render_with_glyphs(renderer, model, camera, size, marks, blank(size))
    tail = marks.arrows[0].start  # outside the cover: drawn in full
    assert alpha_at(image, camera, tail, size, 1) == 255
    corner = (7, 14, 26)  # a corner of the gear's box, inside the cover and clear of the rest: dimmed
    assert 0 < alpha_at(image, camera, corner, size, 1) <= round(marks.hidden.opacity * 255) + 1


BAD = [
    (
        "[[circle]]\nat = [0, 0, 0]\n",
        "unknown entry 'circle' (allowed: arrow, box, dimension, label, path, hidden)",
    ),
    ("[box]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n", "box must be a list of tables"),
    (
        "[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n[[box]]\nmin = [0, 0, 0]\nmax = [1, 1]\n",
        "box 2: max must be 3 numbers",
    ),
    ('[[box]]\nmin = [0, 0, 0]\nmax = [1, "a", 1]\n', "box 1: max must be 3 numbers"),
    ("[[box]]\nmin = [0, 0, 0]\nmax = [1, nan, 1]\n", "box 1: max must be finite numbers"),
    ("[[box]]\nmin = [0, 0, 0]\nmax = [1, -1, 1]\n", "box 1: min must not exceed max (y"),
    ("[[box]]\nmin = [0, 0, 0]\n", "box 1: max is missing"),
    (
        "[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nlenght = 3\n",
        "box 1: unknown key 'lenght' (allowed: min, max, color, width, dash, label)",
    ),
    (
        '[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\ncolor = "#ff88"\n',
        "box 1: color '#ff88' is not of the form #rrggbb",
    ),
    ('[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\ncolor = "#gg0000"\n', "box 1: color '#gg0000'"),
    ("[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\ncolor = 255\n", "box 1: color must be a string"),
    ("[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nwidth = 0\n", "box 1: width must be in (0, 64]"),
    ('[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nwidth = "2"\n', "box 1: width must be a number"),
    ("[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nwidth = inf\n", "box 1: width must be a finite number"),
    ("[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nlabel = 3\n", "box 1: label must be a string"),
    ("[[arrow]]\nfrom = [0, 0, 0]\nto = [0, 0, 0]\n", "arrow 1: from and to are the same point"),
    ("[[arrow]]\nfrom = [0, 0, 0]\nto = [1, 0, 0]\nhead = 2\n", "arrow 1: head must be in [0, 1]"),
    ("[[arrow]]\nfrom = [0, 0, 0]\nto = [1, 0, 0]\nhead = true\n", "arrow 1: head must be a number"),
    ("[[path]]\npoints = [[0, 0, 0]]\n", "path 1: points must be a list of 2 to"),
    ("[[path]]\npoints = [[0, 0, 0], [1, 0]]\n", "path 1: point 2 must be 3 numbers"),
    ('[[path]]\npoints = [[0, 0, 0], [1, 0, 0]]\nclosed = "no"\n', "path 1: closed must be true or false"),
    ("[[path]]\npoints = [[0, 0, 0], [1, 0, 0]]\ndash = [6, 4, 2]\n", "path 1: dash must be an even count"),
    ("[[path]]\npoints = [[0, 0, 0], [1, 0, 0]]\ndash = [6, -4]\n", "path 1: dash must be an even count"),
    ('[[label]]\nat = [0, 0, 0]\ntext = ""\n', "label 1: text must not be empty"),
    ("[[label]]\nat = [0, 0, 0]\n", "label 1: text is missing"),
    (
        '[[label]]\nat = [0, 0, 0]\ntext = "a"\nanchor = "middle"\n',
        "label 1: anchor must be one of left, right, center, top, bottom, top-left",
    ),
    ('[[label]]\nat = [0, 0, 0]\ntext = "a"\nsize = 1\n', "label 1: size must be in [4, 256]"),
    ('[hidden]\nmode = "faint"\n', "hidden: mode must be one of dim, dashed, none, got 'faint'"),
    ("[hidden]\nopacity = 1.5\n", "hidden: opacity must be in [0, 1], got 1.5"),
    ("[hidden]\nstyle = 1\n", "hidden: unknown key 'style' (allowed: mode, opacity, dash)"),
    ("[[box]\nmin = 1\n", "not valid TOML"),
    ("box = [1, 2]\n", "box 1: must be a table of keys"),
]


@pytest.mark.parametrize(("text", "message"), BAD, ids=[m for _, m in BAD])
def test_bad_glyph_file_is_one_line_naming_file_and_entry(tmp_path, text, message):
    path = tmp_path / "marks.toml"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        load_glyphs(path)
    line = str(info.value)
    assert "\n" not in line
    assert line.startswith(f"{path}: "), line
    assert message in line, line


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        (
            "marks.json",
            '{"box": [{"min": [0, 0, 0], "max": [1, 1, NaN]}]}',
            "box 1: max must be finite numbers",
        ),
        ("marks.json", '{"box": [', "not valid JSON"),
        ("marks.json", "[1, 2]", "must be a table of glyph lists"),
        (
            "marks.json",
            '{"label": [{"at": [0, 0, 0], "text": "a", "size": 300}]}',
            "label 1: size must be in",
        ),
        ("marks.yaml", "box: []", "glyph file must end in .toml or .json"),
        ("marks.toml", b"\xff\xfe", "not UTF-8 text"),
    ],
)
def test_bad_json_and_files(tmp_path, name, content, message):
    path = tmp_path / name
    (path.write_bytes if isinstance(content, bytes) else path.write_text)(content)
    with pytest.raises(InputError) as info:
        load_glyphs(path)
    line = str(info.value)
    assert "\n" not in line and line.startswith(f"{path}: ") and message in line, line


def test_missing_file_and_dict_source(tmp_path):
    with pytest.raises(InputError, match=r"marks\.toml: no such file"):
        load_glyphs(tmp_path / "marks.toml")
    with pytest.raises(InputError, match=r"^scene: arrow 1: to must be 3 numbers"):
        Glyphs.from_dict({"arrow": [{"from": [0, 0, 0], "to": 5}]}, "scene")
