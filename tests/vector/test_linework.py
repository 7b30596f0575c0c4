"""Lines that know where they come from (vector/linework.py): every line's source edges lie
under it, its kind agrees with the geometry of its edges, an edge keeps its number in every view
and run, and the SVG, DXF and PDF read back give the same parts, kinds, levels and edges."""

import subprocess
import sys
from collections import Counter
from dataclasses import replace

import numpy as np
import pytest
from vector_helpers import parse_path, point_segment_distance, svg_edges, svg_line_paths

from blueprint.errors import InputError
from blueprint.examples import assemble, box, example_path, gearbox
from blueprint.scene.camera import clip_to_pixels, fit_camera, transform
from blueprint.scene.loader import load_model
from blueprint.scene.weld import weld
from blueprint.vector import (
    KINDS,
    Lines,
    draw_vector,
    edge_numbers,
    edge_segments,
    load_vector_style,
    save_drawing,
)
from blueprint.vector.dxf import layer_name
from blueprint.vector.lines import _welded_adjacency, adjacency
from blueprint.vector.linework import BORDER, BOUNDARY, CREASE, INTERSECTION, SILHOUETTE
from blueprint.vector.svg import path_data, svg_bytes

SIZE = (240, 180)


@pytest.fixture(scope="module")
def model():
    return gearbox()


@pytest.fixture(scope="module")
def views(model, renderer):
    """The gearbox from two views, with their cameras."""
    drawn = {}
    for view in ("iso", "front"):
        camera = fit_camera(model, SIZE, view)
        drawn[view] = (camera, draw_vector(model, camera, SIZE, renderer=renderer))
    return drawn


def _projected(model, camera, edges) -> np.ndarray:
    """(N, 2, 2) pixels of the model's edges ``edges`` seen by ``camera``."""
    ends = edge_segments(model, edges).reshape(-1, 3)
    clip = transform(ends, camera.projection_matrix() @ camera.view_matrix())
    return clip_to_pixels(clip, SIZE).reshape(-1, 2, 2)


def _samples(points: np.ndarray, step: float = 0.25) -> np.ndarray:
    """Points every ``step`` pixels along a 2D polyline."""
    out = [points[:1]]
    for a, b in zip(points[:-1], points[1:], strict=True):
        n = max(int(np.ceil(np.linalg.norm(b - a) / step)), 1)
        out.append(a + (b - a) * (np.arange(1, n + 1) / n)[:, None])
    return np.concatenate(out)


def test_the_numbering_is_the_sorted_pairs_of_the_welded_model(model):
    """Recomputed from the model: each part welded on its own, its faces' edges as (low, high)
    vertex pairs, the parts' vertices numbered one after the other; the pairs, by their ends'
    positions, are the numbered edges' (every edge once)."""
    numbered = edge_segments(model, np.arange(len(edge_numbers(model))))
    keys = {tuple(np.round(np.sort(e, axis=0), 9).reshape(-1)) for e in numbered}
    assert len(keys) == len(numbered) - _shared_between_parts(model)
    found = set()
    for part in range(len(model.part_names)):
        faces = model.faces[model.face_part == part]
        positions, welded = weld(model.positions.astype(np.float64), faces)
        pairs = np.sort(np.concatenate([welded[:, [0, 1]], welded[:, [1, 2]], welded[:, [2, 0]]]), axis=1)
        pairs = np.unique(pairs[pairs[:, 0] != pairs[:, 1]], axis=0)
        found |= {tuple(np.round(np.sort(positions[p], axis=0), 9).reshape(-1)) for p in pairs}
    assert found == keys
    edges = edge_numbers(model)
    assert (edges[:, 0] < edges[:, 1]).all()
    assert (np.diff(edges[:, 0] * (edges.max() + 1) + edges[:, 1]) > 0).all()


def _shared_between_parts(model) -> int:
    """Edges that two parts both have (each keeps its own): counted once by position."""
    ends = edge_segments(model, np.arange(len(edge_numbers(model))))
    keys = Counter(tuple(np.round(np.sort(e, axis=0), 9).reshape(-1)) for e in ends)
    return sum(n - 1 for n in keys.values())


def test_every_line_lies_on_its_source_edges_within_a_pixel(model, views):
    for camera, drawing in views.values():
        lines = drawing.lines
        with_edges = 0
        for i in range(len(lines)):
            edges = lines.edges_of(i)
            if len(edges) == 0:
                assert lines.kind[i] == INTERSECTION
                continue
            with_edges += 1
            segments = _projected(model, camera, edges)
            points = _samples(lines.polyline(i))
            # every point of the line on one of its edges, every edge under the line
            assert point_segment_distance(points, segments).min(axis=1).max() <= 1.0, i
            assert point_segment_distance(points, segments).min(axis=0).max() <= 1.0, i
        assert with_edges > 100


def test_kinds_agree_with_the_geometry_of_their_edges(model, views):
    """A crease's edge has two faces meeting at more than the crease angle; a silhouette's one
    facing the camera and one facing away (or seen edge-on); a border's one face; a part
    boundary's one face, with another part's border on it; intersections have no edge."""
    adj = adjacency(model)
    count = np.bincount(adj.edge_faces[:, 0], minlength=len(adj.edges))
    start = np.cumsum(count) - count
    first = adj.edge_faces[start, 1]
    second = adj.edge_faces[np.minimum(start + 1, len(adj.edge_faces) - 1), 1]
    seen = set()
    for camera, drawing in views.values():
        lines = drawing.lines
        owner = np.repeat(np.arange(len(lines)), np.diff(lines.edge_offsets))
        kind = lines.kind[owner]
        edges = lines.edges
        seen |= set(kind.tolist())
        normals = adj.face_normals
        eye = np.linalg.inv(camera.view_matrix())[:3, 3]
        facing = np.einsum("ij,ij->i", normals, eye - adj.positions[adj.faces[:, 0]])
        facing /= np.linalg.norm(eye - adj.positions[adj.faces[:, 0]], axis=1)

        crease = edges[kind == CREASE]
        assert (count[crease] == 2).all()
        cos = np.einsum("ij,ij->i", normals[first[crease]], normals[second[crease]])
        assert (cos < np.cos(np.radians(30.0))).all()

        # of all its faces (an edge of three or more too), one faces the camera, one not
        toward = facing[adj.edge_faces[:, 1]]
        most, least = np.maximum.reduceat(toward, start), np.minimum.reduceat(toward, start)
        silhouette = edges[kind == SILHOUETTE]
        assert ((most[silhouette] > 0) & (least[silhouette] < 1e-6)).all()

        for code in (BORDER, BOUNDARY):
            assert (count[edges[kind == code]] == 1).all()
        boundary = edge_segments(model, edges[kind == BOUNDARY])
        borders = edge_segments(model, np.flatnonzero(count == 1))
        part_of = model.face_part[first]
        for edge, ends in zip(edges[kind == BOUNDARY].tolist(), boundary, strict=True):
            same = np.all(np.isclose(np.sort(borders, axis=1), np.sort(ends, axis=0), atol=1e-6), axis=(1, 2))
            assert len(set(part_of[np.flatnonzero(count == 1)[same]].tolist()) - {part_of[edge]}) >= 1
    assert {SILHOUETTE, CREASE} <= seen


def test_an_edge_drawn_in_two_views_has_one_number(model, views):
    """The edges both views draw, each projected in each view, lie under a line of that view
    that lists them: one number, one edge of the model."""
    (iso_camera, iso), (front_camera, front) = views["iso"], views["front"]
    common = np.intersect1d(iso.lines.edges, front.lines.edges)
    assert len(common) > 20
    for camera, drawing in ((iso_camera, iso), (front_camera, front)):
        lines = drawing.lines
        owner = np.repeat(np.arange(len(lines)), np.diff(lines.edge_offsets))
        for edge in common[:: max(len(common) // 25, 1)].tolist():
            segment = _projected(model, camera, [edge])
            near = [
                point_segment_distance(_samples(lines.polyline(i)), segment).min()
                for i in np.unique(owner[lines.edges == edge]).tolist()
            ]
            assert min(near) <= 1.0


def test_a_file_gives_the_same_numbers_in_another_run(tmp_path):
    """A second process loading the same file numbers its edges alike, and so does a weld of a
    second load made afresh (not the cache)."""
    source = example_path()
    here = edge_numbers(load_model(source))
    code = (
        "import sys, numpy as np\n"
        "from blueprint.scene.loader import load_model\n"
        "from blueprint.vector import edge_numbers\n"
        f"np.save(sys.argv[1], edge_numbers(load_model({str(source)!r})))\n"
    )
    out = tmp_path / "edges.npy"
    done = subprocess.run([sys.executable, "-c", code, out], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    np.testing.assert_array_equal(np.load(out), here)
    np.testing.assert_array_equal(_welded_adjacency(load_model(source)).edges, here)


def test_an_unknown_edge_is_named_in_one_line(model):
    with pytest.raises(InputError, match=r"edge 999999 is no edge of the model"):
        edge_segments(model, [0, 999999])


def _drawn(drawing) -> Counter:
    """(part, kind name, level, edges ascending) of every line a writer draws."""
    lines = drawing.lines
    return Counter(
        (int(lines.part[i]), KINDS[lines.kind[i]], int(lines.level[i]), tuple(np.unique(lines.edges_of(i))))
        for i in range(len(lines))
        if np.ptp(np.round(lines.polyline(i), 1), axis=0).any()
    )


def test_the_svg_reads_back_to_the_lines_parts_kinds_levels_and_edges(views, tmp_path):
    drawing = views["iso"][1]
    path = save_drawing(tmp_path / "g.svg", drawing)
    read = Counter()
    for part, level, element, _ in svg_line_paths(path):
        subpaths = parse_path(element.get("d"))
        edges = svg_edges(element.get("data-edges"))
        if not edges:
            edges = [np.zeros(0, np.int64)] * len(subpaths)
        assert len(edges) == len(subpaths)
        key = (int(part.get("data-part")), element.get("data-kind"), int(level.get("data-level")))
        read.update((*key, tuple(e.tolist())) for e in edges)
    assert read == _drawn(drawing)


def test_the_dxf_reads_back_to_the_lines_parts_kinds_levels_and_edges(views, tmp_path):
    import ezdxf

    drawing = views["iso"][1]
    doc = ezdxf.readfile(save_drawing(tmp_path / "g.dxf", drawing))
    names = {}
    for part, kind, level, _ in drawing.groups():
        names[layer_name(drawing.part_names[part], level, KINDS[kind])] = (part, KINDS[kind], level)
    read = Counter()
    for entity in doc.modelspace().query("LWPOLYLINE CIRCLE ARC"):
        part, kind, level = names[entity.dxf.layer]
        tags = entity.get_xdata("BLUEPRINT")
        assert tags[0] == (1000, kind)
        read[(part, kind, level, tuple(sorted({value for _, value in tags[1:]})))] += 1
    assert read == _drawn(drawing)


def test_the_pdf_has_a_layer_per_kind_and_marks_each_group_with_it(views, tmp_path):
    import re

    import pypdf

    drawing = views["iso"][1]
    reader = pypdf.PdfReader(save_drawing(tmp_path / "g.pdf", drawing))
    page = reader.pages[0]
    keys = page["/Resources"]["/Properties"]
    content = page.get_contents().get_data().decode("latin-1")
    marked = re.findall(r"/OC /P(\d+) BDC\n/OC /K(\d+) BDC\n/OC /L(\d+) BDC\n", content)
    assert [(int(p), int(k), int(lv)) for p, k, lv in marked] == [g[:3] for g in drawing.groups()]
    kinds = {str(keys[f"/K{k}"].get_object()["/Name"]) for _, k, _ in marked}
    assert kinds == set(drawing.lines_per_kind())


def test_intersections_are_a_kind_with_a_style_of_their_own(renderer, tmp_path):
    """Two boxes pushed into each other: where they cut, lines of kind intersection, drawn in
    the width a line style file gives that kind."""
    model = assemble({"a": box((0, 0, 0), (2, 2, 2)), "b": box((1, 1, 1), (3, 3, 3))})
    style = tmp_path / "s.toml"
    style.write_text('[kinds.intersection]\nwidth = 3.0\ncolor = "#ff0000"\n')
    drawing = draw_vector(model, size=(160, 160), style=str(style), renderer=renderer)
    cut = drawing.lines.where(kind="intersection")
    assert len(cut) >= 1 and len(cut.edges) == 0
    # the cut lies where the faces of the two boxes meet: x, y or z at 1 or 2 on both
    path = save_drawing(tmp_path / "cut.svg", drawing)
    found = [
        (level, element)
        for _, level, element, _ in svg_line_paths(path)
        if element.get("data-kind") == "intersection"
    ]
    assert found
    for level, element in found:
        # the level's stroke is its outlines' (ISO 128: twice the level's width), the cut's three times
        ratio = float(element.get("stroke-width")) / float(level.get("stroke-width"))
        assert ratio == pytest.approx(1.5, rel=1e-3)
        assert element.get("stroke") == "#ff0000"


def test_lines_filter_by_kind_part_and_level():
    lines = Lines(
        np.arange(12.0).reshape(6, 2),
        np.array([0, 2, 4, 6]),
        np.array([0, 1, 1], np.int32),
        np.array([SILHOUETTE, CREASE, INTERSECTION], np.uint8),
        np.array([0, 1, 0], np.int32),
        np.array([7, 8, 9]),
        np.array([0, 1, 3, 3]),
        np.zeros(3, bool),
    )
    creases = lines.where(kind="crease")
    assert len(creases) == 1 and creases.edges.tolist() == [8, 9]
    np.testing.assert_array_equal(creases.polyline(0), [[4.0, 5.0], [6.0, 7.0]])
    assert lines.where(part=1, level=0).kind.tolist() == [INTERSECTION]
    assert lines.where(kind=["silhouette", INTERSECTION]).edges.tolist() == [7]
    both = Lines.concatenate([lines, lines.shifted((1, 0))])
    assert both.edge_offsets.tolist() == [0, 1, 3, 3, 4, 6, 6]
    assert both.polyline(3)[0].tolist() == [1.0, 1.0]
    with pytest.raises(InputError, match="unknown kind of line 'edge'"):
        lines.where(kind="edge")


def test_a_kind_left_out_by_the_style_file_is_drawn_by_no_writer(model, views, tmp_path):
    import ezdxf

    style = tmp_path / "s.toml"
    style.write_text("[kinds.crease]\nshow = false\n")
    drawing = replace(views["iso"][1], style=load_vector_style(style))
    assert drawing.lines_per_kind()["crease"] > 0
    kinds = {
        element.get("data-kind")
        for _, _, element, _ in svg_line_paths(save_drawing(tmp_path / "s.svg", drawing))
    }
    assert "crease" not in kinds and "silhouette" in kinds
    layers = {e.dxf.layer for e in ezdxf.readfile(save_drawing(tmp_path / "s.dxf", drawing)).modelspace()}
    assert not any("-crease-" in name for name in layers) and any("-silhouette-" in name for name in layers)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[kinds.edge]\nwidth = 2\n", "kinds: unknown kind 'edge'"),
        ("[kinds.crease]\nshow = 1\n", "kinds.crease: show must be true or false"),
        ("[kinds.crease]\nstyle = 1\n", "kinds.crease: unknown key 'style'"),
        ("[[kinds.crease.levels]]\nwidth = 0\n", "kinds.crease: levels 0: width must be in (0, 16]"),
    ],
)
def test_bad_kind_entries_name_the_file_and_the_entry(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(InputError) as caught:
        load_vector_style(path)
    assert str(caught.value).startswith(str(path)) and message in str(caught.value)
    assert "\n" not in str(caught.value)


def test_kind_styles_take_the_level_and_override_it_per_level(tmp_path):
    path = tmp_path / "k.toml"
    path.write_text(
        '[kinds.silhouette]\ncolor = "#ff0000"\n'
        "[[kinds.crease.levels]]\nwidth = 3\n[[kinds.crease.levels]]\ndash = []\n"
    )
    style = load_vector_style(path)
    # ISO 128: outlines twice their level's width, where the file leaves the width out
    assert style.line("silhouette", 0).width == pytest.approx(2 * style.level(0).width)
    assert style.line("silhouette", 1).color == (1.0, 0.0, 0.0)
    assert style.line("silhouette", 1).dash == style.level(1).dash
    assert style.line("crease", 0).width == pytest.approx(2 * 3 * style.level(0).width)
    assert style.line("crease", 1).dash == () and style.line("crease", 4).dash == ()
    assert style.line("smooth", 0).width == pytest.approx(style.level(0).width)


def test_the_engine_svg_grows_by_at_most_30_percent_over_lines_without_kinds_or_edges(
    renderer, shared_models, tmp_path
):
    """The same lines written as before lines had kinds and edges (a path a part and level, its
    stroke on it, every polyline a subpath from an absolute move on the 0.1 px grid): the SVG
    with a path a kind, the lines' edges and the grid in a scaled group is at most 30 % larger."""
    drawing = draw_vector(
        load_model(shared_models / "glTF-Sample-Models" / "2CylinderEngine.glb"),
        size=(1024, 1024),
        renderer=renderer,
    )
    new = len(svg_bytes(drawing))
    lines = drawing.lines
    old = len(svg_bytes(replace(drawing, lines=Lines.empty())))
    order = np.lexsort((-lines.level, lines.part))
    key = lines.part[order].astype(np.int64) * 1024 + lines.level[order]
    for group in np.split(order, np.flatnonzero(np.diff(key)) + 1):
        sizes = np.diff(lines.offsets)[group]
        rows = np.concatenate([np.arange(lines.offsets[i], lines.offsets[i + 1]) for i in group])
        d = path_data(lines.points[rows], np.r_[0, np.cumsum(sizes)], 1.0, 1)
        level = int(lines.level[group[0]])
        stroke = drawing.style.level(level)
        attrs = (
            f'stroke="{stroke.hex}" stroke-width="{stroke.width:.4g}" stroke-opacity="{stroke.opacity:.3g}"'
        )
        old += len(f'<path class="level-{level}" {attrs} stroke-dasharray="1.5 3" d="{d}"/>\n')
    parts = len(np.unique(lines.part))
    old += parts * len('<g id="" inkscape:groupmode="layer" inkscape:label="" data-part="">\n</g>\n')
    assert len(drawing) > 5000
    assert new <= 1.3 * old, f"{new} bytes against {old}: {new / old - 1:.0%} more"


def _edged_lines(sizes: np.ndarray, edges: np.ndarray):
    """``len(sizes)`` two-point lines of part, kind and level 0, line ``i`` with the next
    ``sizes[i]`` of ``edges`` as its source edges."""
    n = len(sizes)
    zeros = np.zeros(n, np.int64)
    return Lines(
        np.zeros((2 * n, 2)),
        np.arange(0, 2 * n + 1, 2),
        zeros,
        zeros.astype(np.uint8),
        zeros,
        edges,
        np.r_[0, np.cumsum(sizes)],
        zeros.astype(bool),
    )


def test_the_edge_lists_of_many_paths_read_back_to_each_lines_edges():
    """``svg.edge_texts`` formats the ``data-edges`` of many paths in one pass: lines without
    edges, repeated edges, differences below zero and numbers of many digits read back, path by
    path, to each line's distinct edges ascending; a path of lines without edges writes none."""
    from blueprint.vector.svg import edge_text, edge_texts

    rng = np.random.default_rng(3)
    n = 400
    sizes = rng.integers(0, 4, n) * (rng.random(n) < 0.7)
    edges = rng.integers(0, 10**9, sizes.sum()) // rng.choice([1, 10**7], sizes.sum())
    lines = _edged_lines(sizes, edges)
    index = rng.permutation(n)[:350]
    bare = index[sizes[index] == 0][:3]
    index = np.r_[bare, index[sizes[index] > 0]]
    cuts = np.r_[
        0, len(bare), np.sort(rng.choice(np.arange(len(bare) + 1, len(index)), 40, replace=False)), len(index)
    ]
    texts = edge_texts(lines, index, cuts)
    assert texts[0] == ""  # the lines without edges
    for g in range(1, len(cuts) - 1):
        own = index[cuts[g] : cuts[g + 1]]
        assert texts[g] == edge_text(lines, own)
        got = svg_edges(texts[g])
        want = [np.unique(edges[lines.edge_offsets[i] : lines.edge_offsets[i + 1]]) for i in own]
        assert len(got) == len(want)
        for a, b in zip(got, want, strict=True):
            np.testing.assert_array_equal(a, b)


def test_the_lines_of_many_paths_ordered_by_lowest_edge_in_one_pass():
    """``svg._by_lowest_edge`` orders the lines of every path at once: each path's lines by
    their lowest source edge (ties and lines without edges in their given order, the latter
    first), path after path, as a sort of each path alone does."""
    from blueprint.vector.svg import _by_lowest_edge

    rng = np.random.default_rng(5)
    n = 500
    sizes = rng.integers(0, 4, n) * (rng.random(n) < 0.8)
    edges = rng.integers(0, 60, sizes.sum())  # few values: many ties
    lines = _edged_lines(sizes, edges)
    order = rng.permutation(n)
    cuts = np.r_[0, np.sort(rng.choice(np.arange(1, n), 30, replace=False)), n]
    groups = [order[a:b] for a, b in zip(cuts[:-1], cuts[1:], strict=True)]
    want = []
    for group in groups:
        lowest = [
            min(edges[lines.edge_offsets[i] : lines.edge_offsets[i + 1]], default=-1) for i in group.tolist()
        ]
        want += [int(group[j]) for j in sorted(range(len(group)), key=lambda j: lowest[j])]
    assert _by_lowest_edge(lines, groups).tolist() == want
