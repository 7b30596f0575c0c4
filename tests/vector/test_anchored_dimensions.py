"""A glyph file's dimensions anchored to the model's edges (vector/anchors.py): ``edge = N``
measures edge N between its ends in every view, ``edges = [N, M]`` the distance between two
edges (hand-computed cases), in SVG and PNG alike; bad edges are one-line errors."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest
import trimesh
from helpers import no_output, one_error, run_cli

import blueprint
from blueprint.compose.glyphs import Glyphs
from blueprint.errors import InputError
from blueprint.examples import gearbox
from blueprint.scene.camera import fit_camera
from blueprint.scene.dimension import GAP_MM, format_value
from blueprint.scene.model import Model
from blueprint.scene.sheet import picture_per_mm
from blueprint.vector import edge_numbers, edge_segments
from blueprint.vector.anchors import anchor_glyphs, edge_distance

SVG = "{http://www.w3.org/2000/svg}"
SIZE = (320, 240)


@pytest.fixture(scope="module")
def model():
    return gearbox()


def _box() -> Model:
    mesh = trimesh.creation.box((50.0, 20.0, 10.0))
    return Model.from_arrays(mesh.vertices, mesh.faces, part_names=["box"], up="z")


def _edge_between(model: Model, p: np.ndarray, q: np.ndarray) -> int:
    """The number of the model's edge from ``p`` to ``q`` (either way round)."""
    ends = edge_segments(model, np.arange(len(edge_numbers(model))))
    match = np.flatnonzero(
        (np.abs(ends - [p, q]).max(axis=(1, 2)) < 1e-6) | (np.abs(ends - [q, p]).max(axis=(1, 2)) < 1e-6)
    )
    assert len(match) >= 1
    return int(match[0])


def _long_face_side(model: Model, cameras) -> tuple[np.ndarray, np.ndarray]:
    """The longest side of a face of the model, read from its faces and positions, that every
    camera sees at least 40 px long."""
    faces = model.faces.astype(np.int64)
    sides = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    ends = model.positions[sides].astype(np.float64)
    length = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    seen = np.ones(len(sides), bool)
    for camera in cameras:
        px = camera.to_pixels(ends.reshape(-1, 3), SIZE).reshape(-1, 2, 2)
        seen &= np.linalg.norm(px[:, 1] - px[:, 0], axis=1) > 40
    best = int(np.argmax(np.where(seen, length, -1.0)))
    assert seen[best]
    return ends[best, 0], ends[best, 1]


def _anchors(lines: np.ndarray, per_mm: float) -> np.ndarray:
    """(2, 2) pixels a dimension's marks point at: each extension line starts ISO 129's gap
    off its point, running away from it."""
    out = []
    for start, end in lines[:2]:
        away = (end - start) / np.linalg.norm(end - start)
        out.append(start - away * GAP_MM * per_mm)
    return np.array(out)


def test_an_edge_dimension_points_at_its_edge_in_two_views(model, renderer, tmp_path):
    drawings = {
        view: blueprint.draw(model, size=SIZE, view=view, ortho=view == "front", units="mm", vector=True)
        for view in ("iso", "front")
    }
    cameras = [d.lines.camera for d in drawings.values()]
    p, q = _long_face_side(model, cameras)
    number = _edge_between(model, p, q)
    glyphs = Glyphs.from_dict({"dimension": [{"edge": number}]}, "dims.toml")
    for view in ("iso", "front"):
        drawing = blueprint.draw(
            model, size=SIZE, view=view, ortho=view == "front", units="mm", glyphs=glyphs, vector=True
        )
        vector = drawing.lines
        camera = vector.camera
        ends = camera.to_pixels(np.array([p, q]), SIZE)
        found = _anchors(vector.marks.lines, 96.0 / 25.4)
        assert np.linalg.norm(found - ends, axis=1).max() <= 1.0, view
        # the value is the side's length, from the model's own positions, in mm
        assert [t.text for t in vector.marks.texts] == [format_value(float(np.linalg.norm(q - p)))]
        path = tmp_path / f"{view}.svg"
        drawing.save(path)
        texts = [t.text for t in ET.parse(path).getroot().iter(f"{SVG}text")]
        assert texts.count(format_value(float(np.linalg.norm(q - p)))) == 1

        # the picture: its extension lines start the gap off the edge's projected ends
        options = {"size": SIZE, "view": view, "ortho": view == "front", "units": "mm"}
        frame = blueprint.draw(model, glyphs=glyphs, **options).frame
        plain = blueprint.draw(model, **options).image
        ends = frame.camera.to_pixels(np.array([p, q]), SIZE)
        ys, xs = np.nonzero(np.abs(frame.image.astype(int) - plain).max(axis=2) > 30)
        ink = np.column_stack([xs, ys]) + 0.5
        gap = GAP_MM * picture_per_mm(SIZE)
        for end in ends:
            nearest = np.linalg.norm(ink - end, axis=1).min()
            assert gap - 2.0 <= nearest <= gap + 1.0, (view, nearest, gap)


def test_two_edges_of_a_box_in_svg_and_png(renderer, tmp_path):
    """Parallel edges 50 apart (the box's ends), and two skew edges whose closest points are
    two corners 50 apart; each dimension's points on its edges' lines."""
    box = _box()
    left = _edge_between(box, np.array([-25.0, -10.0, -5.0]), np.array([-25.0, -10.0, 5.0]))
    right = _edge_between(box, np.array([25.0, -10.0, -5.0]), np.array([25.0, -10.0, 5.0]))
    across = _edge_between(box, np.array([-25.0, -10.0, -5.0]), np.array([-25.0, 10.0, -5.0]))
    glyphs = Glyphs.from_dict(
        {"dimension": [{"edges": [left, right]}, {"edges": [right, across], "offset": -4}]}, "dims.toml"
    )
    anchored = anchor_glyphs(glyphs, box)
    assert anchored.dimensions[0].start == (-25.0, -10.0, 0.0)
    assert anchored.dimensions[0].end == (25.0, -10.0, 0.0)
    assert anchored.dimensions[1].start == (25.0, -10.0, -5.0)
    assert anchored.dimensions[1].end == (-25.0, -10.0, -5.0)
    path = tmp_path / "front.svg"
    blueprint.draw(box, size=SIZE, view="front", ortho=True, units="mm", glyphs=glyphs, vector=True).save(
        path
    )
    texts = [t.text for t in ET.parse(path).getroot().iter(f"{SVG}text")]
    assert texts == ["50", "50"]
    plain = blueprint.draw(box, size=SIZE, view="front", ortho=True, units="mm").image
    drawn = blueprint.draw(box, size=SIZE, view="front", ortho=True, units="mm", glyphs=glyphs).image
    assert (np.abs(drawn.astype(int) - plain).max(axis=2) > 40).sum() > 100


@pytest.mark.parametrize(
    "a, b, start, end",
    [
        # skew: across each other's middles, one above the other
        ([[0, 0, 0], [1, 0, 0]], [[0.5, -1, 1], [0.5, 1, 1]], [0.5, 0, 0], [0.5, 0, 1]),
        # apart in a plane: the end of one and the end of the other
        ([[0, 0, 0], [1, 0, 0]], [[2, 1, 0], [3, 2, 0]], [1, 0, 0], [2, 1, 0]),
        # an end of one nearest to the inside of the other
        ([[0, 0, 0], [2, 0, 0]], [[1, 1, 0], [1, 3, 2]], [1, 0, 0], [1, 1, 0]),
        # parallel, beside each other over [2, 4]: the middle of that stretch
        ([[0, 0, 0], [4, 0, 0]], [[10, 3, 0], [2, 3, 0]], [3, 0, 0], [3, 3, 0]),
        # parallel, not beside each other: the end of a nearest to b, and its foot on b's line
        ([[0, 0, 0], [4, 0, 0]], [[6, 0, 2], [8, 0, 2]], [4, 0, 0], [4, 0, 2]),
        ([[0, 0, 0], [4, 0, 0]], [[-3, 0, 2], [-1, 0, 2]], [0, 0, 0], [0, 0, 2]),
    ],
)
def test_the_distance_between_two_edges_by_hand(a, b, start, end):
    found = edge_distance(np.array(a, float), np.array(b, float))
    assert np.allclose(found[0], start, atol=1e-12) and np.allclose(found[1], end, atol=1e-12)


def test_edges_that_meet_and_unknown_edges_are_errors():
    box = _box()
    count = len(edge_numbers(box))
    corner = np.array([-25.0, -10.0, -5.0])
    one = _edge_between(box, corner, np.array([-25.0, -10.0, 5.0]))
    two = _edge_between(box, corner, np.array([-25.0, 10.0, -5.0]))
    meeting = Glyphs.from_dict(
        {"dimension": [{"from": [0, 0, 0], "to": [1, 0, 0]}, {"edges": [one, two]}]}, "d.toml"
    )
    with pytest.raises(InputError, match=rf"^d.toml: dimension 2: edges {one} and {two} of .* meet"):
        anchor_glyphs(meeting, box)
    unknown = Glyphs.from_dict({"dimension": [{"edge": count}]}, "d.toml")
    with pytest.raises(
        InputError, match=rf"^d.toml: dimension 1: edge {count} is no edge of .* 0 to {count - 1}\)"
    ):
        anchor_glyphs(unknown, box)
    # drawn unanchored, the glyphs say what to do
    image = np.zeros((8, 8, 4), np.uint8)
    with pytest.raises(InputError, match="dimension 1 is given by edges: anchor"):
        blueprint.draw_glyphs(image, unknown, fit_camera(box, (8, 8), "front"), None)


@pytest.mark.parametrize(
    "entry, message",
    [
        ({"edge": -1}, "edge must be an edge number (a whole number from 0), got -1"),
        ({"edge": 2.5}, "edge must be an edge number (a whole number from 0), got 2.5"),
        ({"edge": True}, "edge must be an edge number (a whole number from 0), got True"),
        ({"edges": [3]}, "edges must be two edge numbers [N, M], got [3]"),
        ({"edges": [3, 3]}, "edges names edge 3 twice: a dimension measures between two"),
        (
            {"edge": 1, "from": [0, 0, 0]},
            "give from and to, edge or edges, one of them alone (got from, edge)",
        ),
        (
            {"edge": 1, "edges": [1, 2]},
            "give from and to, edge or edges, one of them alone (got edge, edges)",
        ),
        ({"text": "x"}, "give from and to (model points), edge = N or edges = [N, M] (edge numbers)"),
        ({"to": [0, 0, 0]}, "from is missing"),
    ],
)
def test_bad_edge_entries(entry, message):
    with pytest.raises(InputError) as caught:
        Glyphs.from_dict({"dimension": [{"from": [0, 0, 0], "to": [1, 0, 0]}, entry]}, "dims.toml")
    assert str(caught.value) == f"dims.toml: dimension 2: {message}"


@pytest.mark.parametrize("entry", ["edge = 18", "edges = [2, 99]"])
@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_an_unknown_edge_is_one_line(tmp_path, entry, suffix):
    """The box has 18 edges: 0 to 17."""
    model = tmp_path / "box.obj"
    trimesh.creation.box((50.0, 20.0, 10.0)).export(model)
    glyphs = tmp_path / "dims.toml"
    glyphs.write_text(f"[[dimension]]\n{entry}\n")
    folder = tmp_path / "out"
    folder.mkdir()
    proc = run_cli(
        "render", model, "-o", folder / f"x{suffix}", "--size", 64, 64, "--view", "front", "--glyphs", glyphs
    )
    edge = entry.split("=")[1].strip(" []").split(",")[-1].strip()
    one_error(proc, f"{glyphs}: dimension 1: edge {edge} is no edge of", "box.obj", "(it has 18: 0 to 17)")
    no_output(folder)
