"""GPU silhouettes (edge lines and triangle IDs) against the CPU object-space method, and their robustness."""

import functools

import numpy as np
import pytest
import trimesh
from helpers import project
from scipy import ndimage

from blueprint import InputError, Model, ShaderError, load_model
from blueprint.examples import box, gearbox, prism
from blueprint.gpu.shaders import build_program
from blueprint.gpu_silhouettes import GpuSilhouettes, composite, render_silhouettes
from blueprint.gpu_silhouettes.lines import LINES_FRAG, LINES_VERT
from blueprint.scene.camera import fit_camera
from blueprint.silhouette import BORDER, SILHOUETTE, build_adjacency, classify_edges, draw_segments
from blueprint.silhouette.edgerecords import edge_records
from blueprint.silhouette.idlist import build_id_lists, id_lists_from_topology

SIZE = (384, 288)
# Shared scans have triangles a few pixels across: at smaller sizes the strips seen edge-on
# near their outline fall below a pixel, where the ID test (by design) marks neighbouring
# pixels whose triangles are two apart (see the closing notes of issue 4).
SCAN_SIZE = (512, 384)


def cube() -> Model:
    return Model.from_arrays(*box((-1, -1, -1), (1, 1, 1)))


def cylinder(segments: int = 48) -> Model:
    return Model.from_arrays(*prism([1.0], 2.0, segments), up="z")


def sphere() -> Model:
    mesh = trimesh.creation.icosphere(subdivisions=3)
    return Model.from_arrays(mesh.vertices, mesh.faces)


def open_gearbox() -> Model:
    """The gearbox without its cover. The cover is five boxes touching along coplanar faces
    with coincident corners: the object-space method draws each box's own silhouette along
    those seams although the surface runs on flat, while the ID test sees triangles sharing
    vertices there and draws nothing, so the seams would measure the cover's construction,
    not the method. Everything else (parts resting on and passing through others) stays."""
    g = gearbox()
    keep = g.face_part != g.part_names.index("cover")
    used = np.unique(g.faces[keep])
    remap = np.full(len(g.positions), -1)
    remap[used] = np.arange(len(used))
    return Model.from_arrays(g.positions[used], remap[g.faces[keep]], g.face_part[keep])


def soup_of(model: Model, seed: int = 0) -> Model:
    """Every triangle with its own three vertices, the winding of a random half reversed."""
    faces = model.faces.copy()
    flip = np.random.default_rng(seed).random(len(faces)) < 0.5
    faces[flip] = faces[flip][:, ::-1]
    corners = model.positions[faces].reshape(-1, 3)
    return Model.from_arrays(corners, np.arange(len(corners)).reshape(-1, 3), model.face_part, up=model.up)


@pytest.fixture(scope="module")
def sil(renderer):
    with GpuSilhouettes(renderer) as s:
        yield s


# -- comparison with the object-space method ------------------------------------------------------
def visible_cpu_pixels(model: Model, camera, size, depth0: np.ndarray) -> np.ndarray:
    """Pixels crossed by the visible parts of the CPU method's silhouette and border edges.

    What is fair: the CPU method has no visibility, it returns every silhouette edge, hidden or
    not, while layer 0 of the GPU method holds only what is seen. So the CPU edges are sampled
    every quarter pixel and a sample is kept where it is not behind the layer-0 surface: its eye
    depth is at most the farthest layer-0 depth in the 3x3 pixels around it (background counts
    as infinitely far), plus 0.5 % of the model's size. The maximum, not the pixel's own depth,
    because a silhouette sample lies on the boundary where the surface bends away: the pixels
    on the far side see past it, the near side sees the surface in front of the edge's depth.
    A hidden edge is kept only within a pixel of an occluder's outline, where lines meet.
    """
    w, h = size
    edges = classify_edges(
        build_adjacency(model.positions, model.faces), camera.view_matrix(), camera.projection_matrix(), w, h
    )
    keep = np.isin(edges.kind, (SILHOUETTE, BORDER))
    ends3, ends2 = edges.segments3d[keep], edges.segments2d[keep]
    count = np.ceil(np.linalg.norm(ends2[:, 1] - ends2[:, 0], axis=1) / 0.25).astype(int) + 2
    owner = np.repeat(np.arange(len(ends3)), count)
    t = (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)) / np.repeat(count - 1, count)
    points = ends3[owner, 0] + t[:, None] * (ends3[owner, 1] - ends3[owner, 0])
    x, y = np.floor(project(points, camera, size=size)).astype(int).T
    eye = -(points @ camera.view_matrix()[2, :3] + camera.view_matrix()[2, 3])
    inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
    x, y, eye = x[inside], y[inside], eye[inside]
    near, far = camera.near, camera.far
    z = depth0.astype(np.float64)
    linear = near + z * (far - near) if camera.ortho else near * far / (far - z * (far - near))
    surface = np.where(z < 1.0, linear, np.inf)
    behind = ndimage.maximum_filter(surface, size=3, mode="nearest")
    visible = eye <= behind[y, x] + 5e-3 * np.linalg.norm(np.ptp(model.positions, axis=0))
    image = np.zeros((h, w), bool)
    image[y[visible], x[visible]] = True
    return image


def part_boundaries(part0: np.ndarray) -> np.ndarray:
    """Pixels next to a pixel of another part (both covered). Where parts pass through each
    other the ID method draws their intersection lines, which the object-space method (edges
    of each part's own mesh) has no notion of; those pixels are not held against it."""
    out = np.zeros(part0.shape, bool)
    for axis in (0, 1):
        a, b = np.moveaxis(part0, axis, 0)[:-1], np.moveaxis(part0, axis, 0)[1:]
        differ = (a != b) & (a >= 0) & (b >= 0)
        np.moveaxis(out, axis, 0)[:-1] |= differ
        np.moveaxis(out, axis, 0)[1:] |= differ
    return out


def agreement(sil, renderer, model: Model, size, view="iso", method="vertex") -> tuple[float, float]:
    """(share of visible CPU edge pixels within 1 px of a GPU pixel, share of GPU pixels within
    1 px of a visible CPU edge pixel)."""
    camera = fit_camera(model, size, view)
    gpu = sil.render(model, camera, size, method=method)[0] > 0
    layer0 = renderer.peel(model, camera, size=size, max_layers=1)
    cpu = visible_cpu_pixels(model, camera, size, layer0.depth[0])
    near = np.ones((3, 3), bool)
    judged = gpu & ~part_boundaries(layer0.part[0])
    assert cpu.sum() > 50 and judged.sum() > 50
    recall = ndimage.binary_dilation(gpu, near)[cpu].mean()
    precision = ndimage.binary_dilation(cpu, near)[judged].mean()
    return float(recall), float(precision)


@pytest.mark.parametrize(
    ("make", "view"),
    [(cube, "iso"), (cylinder, "iso"), (cylinder, "front"), (sphere, "iso"), (open_gearbox, "iso")],
    ids=["cube", "cylinder-iso", "cylinder-front", "sphere", "gearbox"],
)
def test_matches_cpu_method_on_generated_shapes(sil, renderer, make, view):
    recall, precision = agreement(sil, renderer, make(), SIZE, view)
    assert recall >= 0.95 and precision >= 0.95, (recall, precision)


@pytest.mark.parametrize(
    "path", ["common-3d-test-models/cow.obj", "libigl-tutorial-data/bunny.off"], ids=["cow", "bunny"]
)
def test_matches_cpu_method_on_shared_models(sil, renderer, shared_models, path):
    recall, precision = agreement(sil, renderer, load_model(shared_models / path), SCAN_SIZE)
    assert recall >= 0.95 and precision >= 0.95, (recall, precision)


# -- robustness -----------------------------------------------------------------------------------
@pytest.mark.parametrize("make", [sphere, cylinder, cube], ids=["sphere", "cylinder", "cube"])
@pytest.mark.parametrize("method", ["vertex", "idlist"])
def test_soup_with_mixed_winding_changes_nothing(sil, renderer, make, method):
    model = make()
    camera = fit_camera(model, SIZE)
    welded = sil.render(model, camera, SIZE, layers=3, method=method)
    soup = sil.render(soup_of(model), camera, SIZE, layers=3, method=method)
    assert welded[0].sum() > 100
    np.testing.assert_array_equal(soup, welded)


def test_soup_with_mixed_winding_changes_nothing_visible_on_an_assembly(sil, renderer):
    """Layer 0 only: behind it, solids that touch have coincident faces, and the renderer
    breaks their depth ties by winding (front faces win), so reversing windings may swap which
    face of a touching pair a deeper layer shows."""
    model = gearbox()
    camera = fit_camera(model, SIZE)
    for method in ("vertex", "idlist"):
        welded = sil.render(model, camera, SIZE, method=method)
        np.testing.assert_array_equal(sil.render(soup_of(model, 1), camera, SIZE, method=method), welded)


def finned_cylinder(segments: int = 32):
    """A closed cylinder with internal fins from its axis to every other rim line: the axis
    (cap centre to cap centre) is one edge of 16 fin triangles, each rim line it reaches is
    shared by two wall triangles and a fin, and the cap centres carry lists of 64 and 48
    triangles."""
    vertices, faces = prism([1.0], 2.0, segments)
    n = segments
    k = np.arange(0, n, 2)
    axis0, axis1 = np.full(len(k), 2 * n), np.full(len(k), 2 * n + 1)
    fins = np.concatenate([np.stack([axis0, axis1, n + k], 1), np.stack([axis0, n + k, k], 1)])
    plain = Model.from_arrays(vertices, faces, up="z")
    return plain, Model.from_arrays(vertices, np.concatenate([faces, fins]), up="z")


@pytest.mark.parametrize("view", ["iso", "top"])
def test_non_manifold_axis_gives_the_cylinder_outline(sil, renderer, view):
    """The paper's Figure 2. From outside only the cylinder is seen: its silhouette must be the
    plain cylinder's, pixel for pixel, with either method (the fins share the axis and rim
    vertices with everything around them, and the ID lists of the cap centres are long).
    The CPU method is no reference here: it counts a rim line as a silhouette wherever the fin
    on it faces away, though the wall runs on smoothly over it."""
    plain, finned = finned_cylinder()
    assert np.bincount(build_adjacency(finned.positions, finned.faces).edge_faces[:, 0]).max() == 16
    assert sorted(sil.id_lists(finned).pointers[:, 1])[-2:] == [48, 64]
    camera = fit_camera(plain, SIZE, view)
    expected = sil.render(plain, camera, SIZE)[0]
    assert expected.sum() > 500
    for method in ("vertex", "idlist"):
        np.testing.assert_array_equal(sil.render(finned, camera, SIZE, method=method)[0], expected)
    recall, precision = agreement(sil, renderer, plain, SIZE, view)
    assert recall >= 0.95 and precision >= 0.95


@pytest.mark.parametrize("make", [sphere, cylinder, open_gearbox], ids=["sphere", "cylinder", "gearbox"])
def test_vertex_storage_equals_id_lists(sil, renderer, make):
    model = make()
    camera = fit_camera(model, SIZE, "front")
    vertex = sil.render(model, camera, SIZE, layers=4, method="vertex")
    assert vertex[1].sum() > 100
    np.testing.assert_array_equal(sil.render(model, camera, SIZE, layers=4, method="idlist"), vertex)


def test_vertex_storage_equals_id_lists_on_a_shared_model(sil, renderer, shared_models):
    model = load_model(shared_models / "common-3d-test-models/cow.obj")
    camera = fit_camera(model, SIZE)
    vertex = sil.render(model, camera, SIZE, layers=2, method="vertex")
    np.testing.assert_array_equal(sil.render(model, camera, SIZE, layers=2, method="idlist"), vertex)


def test_compute_pass_equals_fragment_pass(renderer):
    model, camera = open_gearbox(), None
    camera = fit_camera(model, SIZE)
    with GpuSilhouettes(renderer, compute=False) as frag, GpuSilhouettes(renderer, compute=True) as comp:
        for method in ("vertex", "idlist"):
            expected = frag.render(model, camera, SIZE, layers=3, method=method)
            np.testing.assert_array_equal(comp.render(model, camera, SIZE, layers=3, method=method), expected)


# -- exact values on tiny cases -------------------------------------------------------------------
def coverage_outline(triangle0: np.ndarray) -> np.ndarray:
    """Pixels whose coverage differs from one of their 4 neighbours' (outside the image counts
    as the same): the outline against the background, both sides."""
    covered = triangle0 >= 0
    padded = np.pad(covered, 1, mode="edge")
    shifted = [padded[1:-1, :-2], padded[1:-1, 2:], padded[:-2, 1:-1], padded[2:, 1:-1]]
    return np.any([s != covered for s in shifted], axis=0)


@pytest.mark.parametrize("method", ["vertex", "idlist"])
def test_fan_around_one_vertex_draws_only_its_outline(sil, renderer, method):
    """The paper's Figure 1: near a vertex, a pixel's neighbours show triangles that touch its
    own only at that vertex. A cylinder from straight above shows its cap, a fan of 48
    triangles around its centre: exactly the outline is drawn, no dots at the centre."""
    model = cylinder()
    camera = fit_camera(model, (96, 96), "top")
    edges = sil.render(model, camera, (96, 96), method=method)[0]
    layer = renderer.peel(model, camera, size=(96, 96), max_layers=1)
    assert len(np.unique(layer.triangle[0])) > 40
    np.testing.assert_array_equal(edges > 0, coverage_outline(layer.triangle[0]))


def test_bow_tie_touching_at_a_vertex(sil, renderer):
    """Two triangles seen face-on touching at one vertex: where their pixels meet nothing is
    drawn, only the outline against the background."""
    positions = np.array([[0, 0, 0], [-1, -1, 0], [-1, 1, 0], [1, 1, 0], [1, -1, 0]], float)
    model = Model.from_arrays(positions, [[0, 2, 1], [0, 4, 3]])
    camera = fit_camera(model, (64, 64), "front")
    edges = sil.render(model, camera, (64, 64))[0]
    layer = renderer.peel(model, camera, size=(64, 64), max_layers=1)
    np.testing.assert_array_equal(edges > 0, coverage_outline(layer.triangle[0]))


def test_id_lists_of_a_tiny_mesh():
    # two triangles sharing edge 1-2, a third sharing only vertex 3... as a soup with repeats
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 2, 0], [1, 1, 0]], float)
    faces = np.array([[0, 1, 2], [1, 3, 2], [5, 4, 4]])
    lists = build_id_lists(positions, faces)
    # vertex 5 welds onto 3; face 2 repeats vertex 4 and is listed once for it
    np.testing.assert_array_equal(lists.face_vertices, [[0, 1, 2], [1, 3, 2], [3, 4, 4]])
    np.testing.assert_array_equal(lists.pointers, [[0, 1], [1, 2], [3, 2], [5, 2], [7, 1]])
    np.testing.assert_array_equal(lists.lists, [0, 0, 1, 0, 1, 1, 2, 2])
    assert lists.adjacent(0, 1) and lists.adjacent(1, 2) and not lists.adjacent(0, 2)
    same = id_lists_from_topology(lists.face_vertices)
    np.testing.assert_array_equal(same.lists, lists.lists)


def test_layers_past_the_last_surface_are_empty(sil, renderer):
    model = cube()
    edges = sil.render(model, size=(96, 64), layers=4)
    assert edges.shape == (4, 64, 96) and edges.dtype == np.float32
    assert edges[0].sum() > 0 and edges[1].sum() > 0 and edges[2:].sum() == 0


def test_still_picture_api(renderer):
    model = cylinder()
    gpu = render_silhouettes(model, size=(96, 64), layers=2, renderer=renderer)
    cpu = render_silhouettes(model, size=(96, 64), method="cpu", renderer=renderer)
    assert gpu.shape == cpu.shape == (64, 96, 3) and gpu.dtype == np.uint8
    paper = composite(np.zeros((1, 2, 2)))[0, 0]
    assert (gpu != paper).any(axis=2).sum() > 100 and (cpu != paper).any(axis=2).sum() > 100


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"method": "zbuffer"}, "unknown silhouette method"),
        ({"layers": 0}, "layers must be"),
        ({"layers": 2.5}, "layers must be"),
        ({"size": (0, 10)}, "size must be at least"),
    ],
)
def test_bad_arguments_are_input_errors(sil, kwargs, message):
    with pytest.raises(InputError, match=message):
        sil.render(cube(), **kwargs)


def test_bad_soup_is_an_input_error(sil):
    with pytest.raises(InputError, match="corners must have shape"):
        sil.soup(np.zeros((4, 3)))
    soup = sil.soup(np.random.default_rng(0).random((4, 3, 3)))
    try:
        with pytest.raises(InputError, match="expected corners of 4 triangles"):
            soup.update(np.zeros((5, 3, 3)))
    finally:
        soup.release()


# -- the line method: the CPU method's edges, classified and drawn on the GPU ---------------------
@functools.cache
def shared_model(path) -> Model:
    """A shared model loaded once for the module (an OBJ scan takes seconds to parse)."""
    return load_model(path)


def cpu_coverage(model: Model, camera, size, keep=None) -> np.ndarray:
    """The CPU method's silhouette and border lines, hidden ones included, as coverage: the
    picture ``--method cpu`` draws (`keep`, (F,) bool, limits it to some faces' edges)."""
    edges = classify_edges(
        build_adjacency(model.positions, model.faces), camera.view_matrix(), camera.projection_matrix(), *size
    )
    chosen = np.isin(edges.kind, (SILHOUETTE, BORDER))
    if keep is not None:
        chosen &= keep[edges.faces[:, 0]]
    return draw_segments(edges.segments2d[chosen], *size)


def both_ways(gpu: np.ndarray, cpu: np.ndarray) -> tuple[float, float]:
    """(share of CPU ink pixels within 1 px of GPU ink, share of GPU ink within 1 px of CPU ink)."""
    near = np.ones((3, 3), bool)
    assert cpu.sum() > 50 and gpu.sum() > 50
    return (
        float(ndimage.binary_dilation(gpu, near)[cpu].mean()),
        float(ndimage.binary_dilation(cpu, near)[gpu].mean()),
    )


def lines_against_cpu(
    sil, renderer, model: Model, size, view="iso", ortho=False
) -> dict[str, tuple[float, float]]:
    """Agreement of the line method with the CPU method: its visible layer against the visible
    CPU edges (``visible_cpu_pixels``), and both layers, hidden included, against everything the
    CPU method draws. Ink is coverage of at least one half."""
    camera = fit_camera(model, size, view, ortho=ortho)
    lines = sil.render(model, camera, size, layers=2, method="edges")
    layer0 = renderer.peel(model, camera, size=size, max_layers=1)
    visible = visible_cpu_pixels(model, camera, size, layer0.depth[0])
    return {
        "visible": both_ways(lines[0] >= 0.5, visible),
        "all": both_ways(lines.max(axis=0) >= 0.5, cpu_coverage(model, camera, size) >= 0.5),
    }


@pytest.mark.parametrize(
    ("make", "view", "ortho"),
    [
        (cube, "iso", False),
        (cube, "top", True),
        (cylinder, "iso", False),
        (cylinder, "iso", True),
        (cylinder, "front", False),
        (sphere, "iso", False),
        (gearbox, "iso", False),
    ],
    ids=["cube", "cube-top", "cylinder-iso", "cylinder-iso-ortho", "cylinder-front", "sphere", "gearbox"],
)
def test_lines_match_cpu_method_on_generated_shapes(sil, renderer, make, view, ortho):
    """The whole gearbox, cover included: the line method draws the CPU method's edges, so the
    cover's seams that the ID test cannot see are the CPU method's lines here too. Seen from the
    top, orthographic, a cube's walls are exactly edge-on: back-facing to both methods, so the
    top face's rim is a silhouette (a GPU facing test that made them neither drew nothing)."""
    for name, (recall, precision) in lines_against_cpu(sil, renderer, make(), SIZE, view, ortho).items():
        assert recall >= 0.95 and precision >= 0.95, (name, recall, precision)


@pytest.mark.parametrize(
    ("path", "view", "ortho"),
    [
        ("common-3d-test-models/stanford-bunny.obj", "iso", False),
        ("common-3d-test-models/stanford-bunny.obj", "top", True),
        ("libigl-tutorial-data/bunny.off", "iso", False),
        ("libigl-tutorial-data/armadillo.obj", "iso", False),
        ("trimesh/featuretype.STL", "iso", False),
        ("trimesh/featuretype.STL", "top", True),
        ("common-3d-test-models/fandisk.obj", "iso", False),
    ],
    ids=[
        "stanford-bunny",
        "stanford-bunny-top-ortho",
        "bunny",
        "armadillo",
        "featuretype",
        "featuretype-top-ortho",
        "fandisk",
    ],
)
def test_lines_match_cpu_method_on_scans_and_cad_parts(sil, renderer, shared_models, path, view, ortho):
    """Scans whose triangles fall under a pixel and CAD parts with chamfers and fans of long thin
    triangles (featuretype is an unwelded STL soup): where the triangle-ID test covers 43 to 68 %
    of what the CPU method draws, the line method agrees with it on 95 % or more both ways,
    visible lines and all lines alike."""
    model = shared_model(shared_models / path)
    for name, (recall, precision) in lines_against_cpu(sil, renderer, model, (800, 600), view, ortho).items():
        assert recall >= 0.95 and precision >= 0.95, (name, recall, precision)


def test_lines_are_the_cpu_method_s_anti_aliased_lines(sil, renderer):
    """A cube from the iso view: its six outline edges, all visible, drawn with the coverage
    ``draw_segments`` gives them (distance to the segment, one pixel wide), to the r8 target's
    precision; half the ink pixels are partly covered, as an anti-aliased line's are."""
    model = cube()
    camera = fit_camera(model, SIZE)
    lines = sil.render(model, camera, SIZE, layers=2, method="edges")
    expected = cpu_coverage(model, camera, SIZE)
    np.testing.assert_allclose(lines[0], expected, atol=0.01)
    assert lines[1].max() == 0.0
    ink = lines[0] > 0
    assert ((lines[0][ink] < 0.99).mean()) > 0.3


def test_hidden_silhouettes_go_to_the_second_layer(sil, renderer):
    """A small box behind a large one, seen from the front: the small box's outline is hidden
    all along and is drawn in layer 1 exactly as the CPU method draws it, the large box's in
    layer 0; nothing is lost and nothing drawn twice."""
    big, small = box((-1, -1, -1), (1, 1, 1)), box((-0.5, -0.5, -3.0), (0.5, 0.5, -2.0))
    positions = np.concatenate([big[0], small[0]])
    faces = np.concatenate([big[1], small[1] + len(big[0])])
    model = Model.from_arrays(positions, faces)
    camera = fit_camera(model, SIZE, "front")
    lines = sil.render(model, camera, SIZE, layers=2, method="edges")
    of_big = np.arange(len(faces)) < len(big[1])
    np.testing.assert_allclose(lines[0], cpu_coverage(model, camera, SIZE, of_big), atol=0.01)
    np.testing.assert_allclose(lines[1], cpu_coverage(model, camera, SIZE, ~of_big), atol=0.01)
    assert lines[1].sum() > 100


@pytest.mark.parametrize("layers", [3, 4])
def test_deeper_layers_sort_hidden_lines_by_the_surfaces_in_front(sil, renderer, layers):
    """Three boxes one behind the other, seen from the front: the large box's outline is
    visible, the middle one's lies behind the large box's front and back (two surfaces), the
    small one's behind four. Layer k holds the lines behind k surfaces, the last layer all those
    behind the layer before: with 4 layers the small box's outline is alone in layer 3, with 3 it
    joins the middle one's in layer 2; layer 1 (the large box's back) has none."""
    parts = [box((-1, -1, -1), (1, 1, 1)), box((-0.6, -0.6, -3.0), (0.6, 0.6, -2.0))]
    parts.append(box((-0.3, -0.3, -5.0), (0.3, 0.3, -4.0)))
    offsets = np.cumsum([0] + [len(p[0]) for p in parts])
    positions = np.concatenate([p[0] for p in parts])
    faces = np.concatenate([p[1] + o for p, o in zip(parts, offsets[:-1], strict=True)])
    model = Model.from_arrays(positions, faces)
    owner = np.repeat(np.arange(3), [len(p[1]) for p in parts])
    camera = fit_camera(model, SIZE, "front")
    lines = sil.render(model, camera, SIZE, layers=layers, method="edges")
    expected = [owner == 0, np.zeros(len(owner), bool), owner == 1, owner == 2]
    if layers == 3:
        expected = [*expected[:2], expected[2] | expected[3]]
    for k, keep in enumerate(expected):
        np.testing.assert_allclose(lines[k], cpu_coverage(model, camera, SIZE, keep), atol=0.01)
    assert all(lines[k].sum() > 100 for k in range(layers) if k != 1)


@pytest.mark.parametrize("make", [sphere, cylinder, gearbox], ids=["sphere", "cylinder", "gearbox"])
def test_lines_of_a_soup_with_mixed_winding_change_nothing(sil, renderer, make):
    """Edges are welded and oriented once (as the CPU method does), so reversing the winding of
    any faces of an unwelded soup draws the same lines."""
    model = make()
    camera = fit_camera(model, SIZE)
    welded = sil.render(model, camera, SIZE, layers=2, method="edges")
    assert welded[0].sum() > 100
    np.testing.assert_array_equal(sil.render(soup_of(model), camera, SIZE, layers=2, method="edges"), welded)


def test_deforming_soup_draws_the_lines_of_the_same_static_model(sil, renderer):
    """A soup whose corners move draws, frame by frame, the lines of a model uploaded from
    scratch in that pose: the faces' facing is decided from the positions on the GPU."""
    model = sphere()
    camera = fit_camera(model, SIZE)
    soup = sil.soup(model.positions[model.faces], topology=(model.faces, len(model.positions)))
    try:
        for k in range(3):
            moved = model.positions * np.array([1.0 + 0.3 * k, 1.0, 1.0 - 0.2 * k])
            soup.update(moved[model.faces])
            fresh = Model.from_arrays(moved, model.faces)
            expected = sil.render(fresh, camera, SIZE, layers=2, method="edges")
            np.testing.assert_array_equal(sil.render(soup, camera, SIZE, layers=2, method="edges"), expected)
            sil.forget(fresh)
    finally:
        soup.release()


def test_lines_of_scans_are_continuous(sil, renderer, shared_models):
    """Specks (8-connected ink of at most 12 pixels) on the stanford bunny: the line method draws
    no more than the CPU method's own, while the triangle-ID test draws several times as many."""
    model = shared_model(shared_models / "common-3d-test-models/stanford-bunny.obj")
    camera = fit_camera(model, (800, 600))

    def specks(ink: np.ndarray) -> int:
        labels, _ = ndimage.label(ink, np.ones((3, 3)))
        return int((np.bincount(labels.ravel())[1:] <= 12).sum())

    lines = sil.render(model, camera, (800, 600), layers=2, method="edges").max(axis=0) >= 0.5
    ids = sil.render(model, camera, (800, 600), method="vertex")[0] > 0
    cpu = specks(cpu_coverage(model, camera, (800, 600)) >= 0.5)
    assert specks(lines) <= cpu and specks(ids) >= 3 * max(cpu, 1)


def test_edge_records_of_a_soup_reoriented():
    """Two triangles of an unwelded soup sharing edge 1-2 but both running 1 -> 2 along it: the
    second is the one reoriented, so its records carry it as -2; borders have face 0; corners
    are 3 * face + k of the first face of the record, as the soup stores them."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    corners = positions[[0, 1, 2, 1, 2, 3]]
    adjacency = build_adjacency(corners, np.arange(6).reshape(2, 3))
    np.testing.assert_array_equal(adjacency.flipped, [False, True])
    np.testing.assert_array_equal(
        edge_records(adjacency), [[0, 1, 1, 0], [0, 2, 1, 0], [1, 2, 1, -2], [3, 5, -2, 0], [4, 5, -2, 0]]
    )


def test_edge_records_chain_the_faces_of_a_non_manifold_edge():
    """Edge 1-2 with three faces gives two records, face 1 with 2 and face 2 with 3 (signed
    index + 1): some pair of the chain faces opposite ways exactly when the edge has both a
    front and a back face."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1]], float)
    adjacency = build_adjacency(positions, np.array([[0, 1, 2], [2, 1, 3], [1, 2, 4]]))
    np.testing.assert_array_equal(
        edge_records(adjacency),
        [[0, 1, 1, 0], [0, 2, 1, 0], [1, 2, 1, 2]]
        + [[4, 5, 2, 0], [3, 5, 2, 0], [4, 3, 2, 3]]
        + [[6, 8, 3, 0], [7, 8, 3, 0]],
    )


def test_a_geometry_shader_error_names_its_file_and_line(renderer, tmp_path):
    """The line program is the package's one with a geometry shader: its compile errors name that
    file and line, as vertex and fragment errors do."""
    broken = tmp_path / "broken.geom"
    lines = ["layout(points) in;", "layout(points, max_vertices = 1) out;", "void main() { nowhere(); }"]
    broken.write_text("\n".join(lines) + "\n")
    with pytest.raises(ShaderError) as info:
        build_program(renderer.ctx, LINES_VERT, LINES_FRAG, geometry=broken)
    assert f"{broken}:3: " in str(info.value), str(info.value)
