"""Smooth contours in pictures (issue 39, point 2): ``smooth_contours=True`` (and by default a
picture of one mesh) draws the outline of smooth surfaces as lines along the contour of their
interpolated normals, each into the edge map of its occlusion level (``vector.contour_ink``,
``pipeline.contours``), and the edges pass leaves those faces' borders and jumps out. Checked
against the vector drawing's contours, which the exact hidden-line tests hold, and by the
issue's speck measure at 1024 x 1024."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from capture_helpers import one_way
from helpers import run_cli
from instanced_scenes import smooth_scene
from PIL import Image
from scan_helpers import ink, noisy_bust, noisy_sphere, specks, stanford_bunny
from scipy import ndimage

import blueprint
from blueprint import examples
from blueprint.api.options import DrawOptions
from blueprint.api.picture import smooth_contours_wanted
from blueprint.scene.camera import clip_to_pixels, fit_camera, transform
from blueprint.vector.contour_ink import DENSE, contour_ink
from blueprint.vector.linework import SILHOUETTE
from blueprint.vector.occlusion.gpu import MAX_LAYERS

SIZE = (1024, 1024)


def test_stanford_bunny_specks(renderer, shared_models):
    """The issue's target of 15 on the bunny, by default: 24 with the mesh's outline, 10 with the
    contour lines (llvmpipe), which its picture draws unasked."""
    model = stanford_bunny(shared_models)
    assert specks(np.asarray(blueprint.render(model, size=SIZE))) <= 12


@pytest.mark.parametrize(("name", "most"), [("noisy sphere", 11), ("noisy bust", 1)])
def test_generated_scan_specks(renderer, name, most):
    """The generated scans, as measured (llvmpipe): the sphere 34 with the mesh's outline, 11
    with the contour lines (by default); the bust 19 and 0."""
    model = noisy_sphere(0.006) if name == "noisy sphere" else noisy_bust()[0]
    assert specks(np.asarray(blueprint.render(model, size=SIZE))) <= most


def _visible_pixels(lines, silhouettes: bool) -> np.ndarray:
    """(K, 2) pixels (x, y from the top) along the vector drawing's visible lines (its
    silhouettes alone where ``silhouettes``), a quarter of a pixel apart."""
    points = []
    chosen = (lines.level == 0) & ((lines.kind == SILHOUETTE) | (not silhouettes))
    for i in np.flatnonzero(chosen):
        polyline = lines.points[lines.offsets[i] : lines.offsets[i + 1]]
        for a, b in zip(polyline[:-1], polyline[1:], strict=True):
            steps = max(int(np.ceil(np.linalg.norm(b - a) * 4)), 1)
            points.append(a + np.linspace(0.0, 1.0, steps, endpoint=False)[:, None] * (b - a))
    return np.concatenate(points)


@pytest.mark.parametrize("name", ["noisy sphere", "noisy bust"])
def test_outline_follows_the_vector_contours(renderer, name):
    """Every point of the vector drawing's visible contours has the picture's ink within a
    pixel, and the picture's visible lines (its strongest ink) lie within 1.5 px of the
    drawing's: the picture draws the same smooth outline, not the mesh's zigzag beside it."""
    model = noisy_sphere(0.006) if name == "noisy sphere" else noisy_bust()[0]
    image = np.asarray(blueprint.render(model, size=SIZE, smooth_contours=True))
    lines = blueprint.draw(model, size=SIZE, vector=True).lines.lines

    def spots(silhouettes):
        pixels = _visible_pixels(lines, silhouettes)
        x = np.clip(np.floor(pixels[:, 0]).astype(int), 0, SIZE[0] - 1)
        return x, np.clip(np.floor(pixels[:, 1]).astype(int), 0, SIZE[1] - 1)

    x, y = spots(True)
    near = ndimage.binary_dilation(ink(image), np.ones((3, 3), bool))
    assert near[y, x].mean() >= 0.99, near[y, x].mean()
    # the visible lines: ink as strong as layer 0's, against the faint hidden lines
    paper = image[0, 0].astype(int)
    strength = np.abs(image[..., :3].astype(int) - paper[:3]).sum(axis=-1)
    outline = strength > 0.8 * strength.max()
    drawn = np.zeros(SIZE[::-1], bool)
    x, y = spots(False)
    drawn[y, x] = True
    distance = ndimage.distance_transform_edt(~drawn)
    assert (distance[outline] <= 1.5).mean() >= 0.98, (distance[outline] <= 1.5).mean()


def test_levels_come_from_the_layers(renderer):
    """The contour lines of a smooth sphere half behind a plate (a box: two surfaces): the
    visible half at level 0, the half behind the plate at level 2, as the vector drawing has
    them, and drawn in those layers' inks."""
    sphere = noisy_sphere(0.0)
    plate = examples.box((-1.2, -1.2, 1.3), (0.0, 1.2, 1.35))
    model = examples.assemble({"sphere": (sphere.positions, sphere.faces), "plate": plate})
    camera = fit_camera(model, SIZE, "front")
    found = contour_ink(renderer, model, camera, SIZE, max_layers=4)
    assert set(found.level.tolist()) == {0, 2}
    middle = 0.5 * (found.points[:, 0].min() + found.points[:, 0].max())
    for level, side in ((0, 1), (2, -1)):
        pieces = np.flatnonzero(found.level == level)
        xs = np.concatenate([found.points[found.offsets[i] : found.offsets[i + 1], 0] for i in pieces])
        # the plate's edge runs through the middle: points further from it are on their side
        far = np.abs(xs - middle) > 10
        assert (np.sign(xs[far] - middle) == side).all(), level
    image = np.asarray(blueprint.render(model, size=SIZE, view="front", smooth_contours=True))
    paper = image[0, 0].astype(int)
    strength = np.abs(image[..., :3].astype(int) - paper[:3]).sum(axis=-1)
    centre = int(0.5 * (found.points[:, 1].min() + found.points[:, 1].max()))
    rows = np.arange(centre - 30, centre + 30)
    # along the rows through the sphere's middle, the ink across its outline (a line a pixel
    # wide, split between two pixels where it runs between them): a visible line's on the
    # right, a hidden one's on the left
    x0, x1 = int(found.points[:, 0].min()), int(found.points[:, 0].max())
    right = strength[rows, x1 - 4 : x1 + 5].sum(axis=1)
    left = strength[rows, x0 - 4 : x0 + 5].sum(axis=1)
    full = strength.max()
    assert (right > 0.8 * full).all(), right.min() / full
    assert (left < 0.6 * full).all() and (left > 0.1 * full).all(), (left.min() / full, left.max() / full)


def test_faces_without_a_smooth_surface_draw_as_before(renderer):
    """A model of flat faces alone has no contour: the option changes no pixel."""
    model = examples.assemble(
        {"a": examples.box((0, 0, 0), (2, 1, 1)), "b": examples.box((1, 0.5, 0.5), (3, 2, 2))}
    )
    camera = fit_camera(model, (256, 256), "iso")
    assert contour_ink(renderer, model, camera, (256, 256)) is None
    before = np.asarray(blueprint.render(model, size=(256, 256), smooth_contours=False))
    after = np.asarray(blueprint.render(model, size=(256, 256), smooth_contours=True))
    assert np.array_equal(before, after)


@pytest.mark.parametrize("way", ["peel", "k-buffer", "a-buffer"])
def test_every_capture_draws_them(renderer, way):
    """The peel, the k-buffer and the A-buffer draw the same picture of the noisy sphere with
    contour lines: the face IDs the edges pass reads come from each of them."""
    model = noisy_sphere(0.006)
    with one_way(renderer, "peel"):
        reference = np.asarray(
            blueprint.render(model, size=(512, 512), smooth_contours=True, renderer=renderer)
        )
    with one_way(renderer, way, abuffer=lambda row: row):
        image = np.asarray(blueprint.render(model, size=(512, 512), smooth_contours=True, renderer=renderer))
    differ = np.abs(image.astype(int) - reference.astype(int)).max(axis=-1) > 24
    assert differ.mean() < 0.002, differ.sum()
    assert specks(image) <= 8


def test_command_line_flag(tmp_path):
    """``blueprint render``: the noisy sphere's file drawn with its contour lines by default and
    with ``--smooth-contours``, the same picture, with fewer specks than with
    ``--no-smooth-contours``."""
    path = tmp_path / "scan.stl"
    model = noisy_sphere(0.006)
    trimesh.Trimesh(model.positions, model.faces, process=False).export(path)
    found = {}
    for flags in ((), ("--smooth-contours",), ("--no-smooth-contours",)):
        target = tmp_path / f"scan{len(found)}.png"
        done = run_cli("render", path, "-o", target, *flags)
        assert done.returncode == 0, done.stderr
        with Image.open(target) as picture:
            found[flags] = np.asarray(picture.convert("RGB"))
    assert np.array_equal(found[()], found[("--smooth-contours",)])
    assert specks(found[()]) < specks(found[("--no-smooth-contours",)])


def test_pictures_of_one_mesh_draw_them_by_default(renderer):
    """By default a picture of one mesh draws the contour lines, its triangles large on it
    (found on the CPU) or under a pixel (on the GPU, ``contour_ink.DENSE``); a model kept as
    instances, and a renderer's frames (streams, the bench), draw none unless asked."""
    model = noisy_sphere(0.006)
    side = int(np.ceil(np.sqrt(model.triangle_count / DENSE)))
    large, small = (2 * side, 2 * side), (side // 2, side // 2)
    for size in (large, small):
        assert smooth_contours_wanted(model, DrawOptions(size=size))
        assert not smooth_contours_wanted(model, DrawOptions(size=size, smooth_contours=False))
        options = dict(size=size, style="paper", renderer=renderer)
        drawn = blueprint.render(model, **options)
        assert np.array_equal(drawn, blueprint.render(model, smooth_contours=True, **options))
        assert not np.array_equal(drawn, blueprint.render(model, smooth_contours=False, **options))
    instanced = smooth_scene()  # kept as instances: their meshes' own outlines
    assert instanced.instances is not None
    assert not smooth_contours_wanted(instanced, DrawOptions(size=(4096, 4096)))
    options = dict(size=small, style="paper", renderer=renderer)
    camera = fit_camera(model, small)
    frame = renderer.render(model, camera, size=small, style="paper")
    unasked = blueprint.render(model, camera=camera, smooth_contours=False, **options)
    assert np.array_equal(frame.image, unasked)


def test_levels_stop_at_one_faces_pass(renderer):
    """A smooth sphere behind four plates (eight surfaces), every layer drawn: the lines'
    levels are found for the layers one pass of the faces k-buffer holds (``MAX_LAYERS``), so
    the sphere's outline, at level 8, has no line, and its layer keeps the mesh's outline:
    inked as without the option."""
    sphere = noisy_sphere(0.0, subdivisions=3)
    parts = {"sphere": (sphere.positions, sphere.faces)}
    for k in range(4):
        parts[f"plate{k}"] = examples.box((-2.0, -2.0, 1.5 + 0.3 * k), (2.0, 2.0, 1.6 + 0.3 * k))
    model = examples.assemble(parts)
    camera = fit_camera(model, (256, 256), "front")
    found = contour_ink(renderer, model, camera, (256, 256), max_layers=None)
    assert found.layers == MAX_LAYERS and len(found) == 0
    options = dict(size=(256, 256), view="front", max_layers=None, style="paper")
    plain = np.asarray(blueprint.render(model, smooth_contours=False, **options))
    lined = np.asarray(blueprint.render(model, smooth_contours=True, **options))
    # the ink within 4 px of the sphere's outline (its equator, projected)
    circle = np.stack(
        [np.cos(np.linspace(0, 2 * np.pi, 400)), np.sin(np.linspace(0, 2 * np.pi, 400)), np.zeros(400)], 1
    )
    view, projection = np.asarray(camera.view_matrix()), np.asarray(camera.projection_matrix())
    rim = np.zeros((256, 256), bool)
    xy = np.floor(clip_to_pixels(transform(circle, projection @ view), (256, 256))).astype(int)
    rim[xy[:, 1], xy[:, 0]] = True
    near = ndimage.binary_dilation(rim, iterations=4)

    def strength(image):
        return np.abs(image[..., :3].astype(int) - image[0, 0, :3].astype(int)).sum(axis=-1)[near].sum()

    assert strength(plain) > 0 and strength(lined) > 0.9 * strength(plain), (strength(lined), strength(plain))


def test_both_forms_of_the_edges_draw_them(renderer, monkeypatch):
    """The edge maps as fragment passes' targets, and as the compute form's arrays (a GPU's, where
    each level's lines are drawn into a map of their own and merged into its slice): the same
    picture of the sphere half behind a plate with its contour lines, within the two forms'
    own rounding, and the lines change it in both."""
    if renderer.ctx.version_code < 430:
        pytest.skip("the compute form needs OpenGL 4.3")
    sphere = noisy_sphere(0.0)
    plate = examples.box((-1.2, -1.2, 1.3), (0.0, 1.2, 1.35))
    model = examples.assemble({"sphere": (sphere.positions, sphere.faces), "plate": plate})
    pictures = {}
    for compute in (False, True):
        monkeypatch.setattr(renderer, "use_compute", compute)
        for lines in (False, True):
            options = dict(size=(512, 512), view="front", smooth_contours=lines, renderer=renderer)
            pictures[compute, lines] = np.asarray(blueprint.render(model, **options)).astype(int)
    apart = np.abs(pictures[False, True] - pictures[True, True]).max(axis=-1)
    assert apart.max() <= 24, apart.max()
    for compute in (False, True):
        changed = np.abs(pictures[compute, True] - pictures[compute, False]).max(axis=-1) > 24
        assert changed.sum() > 200, (compute, changed.sum())


def test_every_face_contoured_reads_no_table(renderer, monkeypatch):
    """Where the contour lines stand for the outline of every face (a scan: all smooth), the
    edges read no table of contoured faces: the same picture, to the bit, as with the table
    read for each sample, by the fragment passes and (OpenGL 4.3) the compute form; where the
    lines' levels count every layer the frame may draw, the edges are built to find part
    boundaries alone (none in a mesh of one part), the same picture again; and a mesh with
    faces of its own outline still reads the table."""
    from blueprint.pipeline import executor

    every_face = executor.every_face

    def no_face(contoured):  # the table read, whatever the faces
        return False

    sphere = noisy_sphere(0.006)
    # two spheres, one half in front of the other: part boundaries where they overlap
    far = sphere.positions * 0.8 + (0.9, 0.3, -1.5)
    pair = examples.assemble({"near": (sphere.positions, sphere.faces), "far": (far, sphere.faces)})
    options = dict(size=(256, 256), view="front", smooth_contours=True, renderer=renderer)
    for compute in (False, True) if renderer.ctx.version_code >= 430 else (False,):
        monkeypatch.setattr(renderer, "use_compute", compute)
        # 2 layers: the lines' levels count all the frame draws, and the edges are built to
        # draw part boundaries alone (CONTOURS_EVERY_LAYER), none at all for one part
        for model, layers in ((sphere, 2), (pair, 2), (sphere, None)):
            pictures = []
            for table in (False, True):
                monkeypatch.setattr(executor, "every_face", no_face if table else every_face)
                pictures.append(np.asarray(blueprint.render(model, max_layers=layers, **options)))
                run = renderer.executor.last_run
                assert (run.contoured is None) == (not table)
                edges = run.pl.bound.passes["edges"]
                defines = executor._defines(edges, run)
                assert defines.get("CONTOURS_EVERY_LAYER", False) == (layers is not None and not table)
                assert defines.get("ONE_PART", False) == (model is sphere and not table)
            assert np.array_equal(*pictures), (compute, layers, model is sphere)
    monkeypatch.undo()
    plate = examples.box((-1.2, -1.2, 1.3), (0.0, 1.2, 1.35))
    both = examples.assemble({"sphere": (sphere.positions, sphere.faces), "plate": plate})
    blueprint.render(both, **options)
    assert renderer.executor.last_run.contoured is not None
