"""Smooth contours found on the GPU (``vector.contour_gpu``, issue 39 point 2): for a mesh of
more triangles than a pixel holds, the contour segments, the faces they outline and the
occlusion tables come from one compute pass over the mesh as drawn, checked here against the
CPU's lines (``lines.smooth_contour_segments``, which the exact hidden-line tests hold), its
face planes (``levels.face_planes``) and grazing band (``lines.grazing_band``)."""

from __future__ import annotations

import numpy as np
import pytest
from capture_helpers import one_way
from scan_helpers import noisy_bust, noisy_sphere
from scipy.spatial import cKDTree

import blueprint
from blueprint import examples
from blueprint.gpu.tables import TABLE_WIDTH
from blueprint.render import budget
from blueprint.scene.camera import clip_to_pixels, fit_camera, transform
from blueprint.scene.prepare import feature_faces
from blueprint.silhouette.edges import feature_vertices
from blueprint.vector import contour_ink as ink_module
from blueprint.vector.contour_gpu import gpu_contours
from blueprint.vector.contour_ink import contour_ink
from blueprint.vector.lines import GRAZING_REACH, adjacency, grazing_band, smooth_contour_segments
from blueprint.vector.occlusion.levels import face_planes

SIZE = (512, 512)
MODELS = {"noisy sphere": lambda: noisy_sphere(0.006), "noisy bust": lambda: noisy_bust()[0]}


def _found(renderer, model, view="iso", size=SIZE):
    camera = fit_camera(model, size, view)
    view_m = np.asarray(camera.view_matrix(), np.float64)
    projection = np.asarray(camera.projection_matrix(), np.float64)
    return camera, view_m, projection, gpu_contours(renderer, model, view_m, projection, size, 30.0, 8)


def _pixels(points, view, projection, size=SIZE):
    return clip_to_pixels(transform(points.reshape(-1, 3), projection @ view), size)


def _read_table(texture, rows, columns):
    return np.frombuffer(texture.read(), np.float32).reshape(-1, columns)[:rows]


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("view", ["iso", "front"])
def test_segments_are_the_cpu_contours(renderer, name, view):
    """The GPU's segments lie on the CPU's smooth contours (its bridges to mesh silhouettes
    aside): every end within a tenth of a pixel of the CPU's, both ways, in the same faces; and
    the faces they outline are the CPU's."""
    model = MODELS[name]()
    camera, view_m, projection, found = _found(renderer, model, view)
    try:
        segments, contoured = smooth_contour_segments(model, view_m, projection, SIZE)
        lines = found.lines
        assert len(lines.points) > 100
        gpu = _pixels(lines.points, view_m, projection)
        # the CPU's contours, bridges (which follow them, each in the face of a contour's end)
        # aside: a face holds one contour segment
        first = np.unique(segments.faces[:, 0], return_index=True)[1]
        cpu = _pixels(segments.points[first], view_m, projection)
        ours_to_cpu = cKDTree(cpu).query(gpu)[0]
        assert ours_to_cpu.max() < 0.1, ours_to_cpu.max()
        shared = np.isin(segments.faces[first, 0], lines.faces[:, 0])
        assert shared.mean() > 0.99, shared.mean()
        cpu_to_ours = cKDTree(gpu).query(cpu.reshape(-1, 2, 2)[shared].reshape(-1, 2))[0]
        assert cpu_to_ours.max() < 0.1, cpu_to_ours.max()
        assert (found.contoured == contoured).mean() > 0.999
        assert found.contoured.sum() > 0.5 * model.triangle_count
    finally:
        found.tables.release()


@pytest.mark.parametrize("name", sorted(MODELS))
def test_tables_are_the_cpu_planes_and_band(renderer, name):
    """The occlusion tables the pass writes: each face's eye-space plane as ``face_planes``
    makes it (float32 rounding apart), zero in the rows past the last face; the grazing band's
    reach as ``grazing_band`` times ``GRAZING_REACH``, but for faces whose vertex normals (the
    preparation's, rounded to 16 bits, against the CPU's smooth surface's) lie on the band's
    edge."""
    model = MODELS[name]()
    camera, view_m, projection, found = _found(renderer, model)
    try:
        faces = model.triangle_count
        rows = found.tables.rows
        assert rows == faces + 1
        planes = np.frombuffer(found.tables.planes.read(), np.float32).reshape(-1, 4)
        assert len(planes) % TABLE_WIDTH == 0 and not planes[faces:].any()
        expected = face_planes(model, view_m)[:faces]
        scale = np.abs(expected[:, 3]).max()
        assert np.abs(planes[:faces, :3] - expected[:, :3]).max() < 1e-4
        assert np.abs(planes[:faces, 3] - expected[:, 3]).max() < 1e-4 * scale
        reach = np.frombuffer(found.tables.reach.read(), np.float32)
        assert not reach[faces:].any()
        band = grazing_band(model, view_m, projection) * GRAZING_REACH
        both = (reach[:faces] > 0) & (band[:faces] > 0)
        assert np.allclose(reach[:faces][both], band[:faces][both], rtol=1e-5)
        apart = (reach[:faces] > 0) != (band[:faces] > 0)
        assert both.sum() > 50 and apart.sum() <= 0.02 * both.sum(), (both.sum(), apart.sum())
    finally:
        found.tables.release()


def test_feature_faces_are_the_surfaces_features(renderer):
    """The faces its preparation marks (a vertex on a crease, a border or a non-manifold edge)
    are those with a feature vertex of the vector lines' adjacency: the bust's ridge, and the
    border of a sphere with a cap cut off."""
    bust = noisy_bust()[0]
    sphere = noisy_sphere(0.0)
    cut = sphere.positions[sphere.faces].mean(axis=1)[:, 2] < 0.8
    open_sphere = blueprint.Model.from_arrays(sphere.positions, sphere.faces[cut])
    for model in (bust, open_sphere):
        renderer.capturer.mesh(model, 30.0)
        marked = feature_faces(model, 30.0)
        adj = adjacency(model)
        expected = feature_vertices(adj, 30.0)[adj.faces].any(axis=1)
        assert marked is not None and marked.any()
        assert np.array_equal(marked, expected)
    assert feature_faces(bust, 10.0) is None  # not prepared at that angle


def test_levels_come_from_the_layers(renderer, monkeypatch):
    """A smooth sphere half behind a plate, its lines found on the GPU: the visible half at
    level 0, the half behind the plate (two surfaces) at level 2, as on the CPU."""
    sphere = noisy_sphere(0.0)
    plate = examples.box((-1.2, -1.2, 1.3), (0.0, 1.2, 1.35))
    model = examples.assemble({"sphere": (sphere.positions, sphere.faces), "plate": plate})
    camera = fit_camera(model, SIZE, "front")
    found = {}
    for dense in (0.0, 1e9):
        monkeypatch.setattr(ink_module, "DENSE", dense)
        found[dense] = contour_ink(renderer, model, camera, SIZE, max_layers=4)
    gpu, cpu = found[0.0], found[1e9]
    assert set(gpu.level.tolist()) == {0, 2}
    for level in (0, 2):
        ours = np.concatenate(
            [gpu.points[gpu.offsets[i] : gpu.offsets[i + 1]] for i in np.flatnonzero(gpu.level == level)]
        )
        theirs = np.concatenate(
            [cpu.points[cpu.offsets[i] : cpu.offsets[i + 1]] for i in np.flatnonzero(cpu.level == level)]
        )
        assert cKDTree(theirs).query(ours)[0].max() < 1.0, level
        assert cKDTree(ours).query(theirs)[0].max() < 1.0, level


def test_dense_pictures_match_the_cpu_lines(renderer, monkeypatch):
    """The noisy bust at 256 x 256 (more than half a triangle a pixel) with its contour lines:
    the GPU's picture is the CPU's but for a few pixels (the bridges, the pieces' ends)."""
    model = noisy_bust()[0]
    size = (256, 256)
    assert model.triangle_count > ink_module.DENSE * size[0] * size[1]
    pictures = {}
    for dense in (ink_module.DENSE, 1e9):
        monkeypatch.setattr(ink_module, "DENSE", dense)
        pictures[dense] = np.asarray(blueprint.render(model, size=size, smooth_contours=True)).astype(int)
    gpu, cpu = pictures.values()
    differ = np.abs(gpu - cpu).max(axis=-1) > 24
    assert differ.mean() < 0.002, differ.sum()
    plain = np.asarray(blueprint.render(model, size=size, smooth_contours=False)).astype(int)
    assert (np.abs(gpu - plain).max(axis=-1) > 24).sum() > 10 * differ.sum()


def test_where_the_gpu_cannot(renderer, monkeypatch):
    """No GPU contours for a model kept as instances, flat normals (no smooth face) or a mesh
    drawn in chunks; a dense mesh's picture then keeps its outline, as without the option."""
    model = noisy_sphere(0.006)
    camera = fit_camera(model, (64, 64), "iso")
    view = np.asarray(camera.view_matrix(), np.float64)
    projection = np.asarray(camera.projection_matrix(), np.float64)
    assert gpu_contours(renderer, model, view, projection, (64, 64), 0.0, 8) is None
    from instanced_scenes import smooth_scene

    instanced = smooth_scene()
    assert gpu_contours(renderer, instanced, view, projection, (64, 64), 30.0, 8) is None
    # memory for a third of the mesh beside the frame: it would be drawn in chunks; the frame's
    # own plan is left to the frame (``fits_whole`` plans nothing)
    renderer.forget(model)
    need = budget.frame_bytes(model.triangle_count, 64 * 64, 8, None)
    monkeypatch.setenv(budget.GPU_MEMORY_ENV, str(sum(need.values()) - 2 * need["mesh"] // 3))
    checked = renderer.capturer._checked
    assert gpu_contours(renderer, model, view, projection, (64, 64), 30.0, 8) is None
    assert renderer.capturer._checked is checked
    monkeypatch.delenv(budget.GPU_MEMORY_ENV)
    monkeypatch.setattr(renderer.capturer, "chunk_faces", 1024)
    assert gpu_contours(renderer, model, view, projection, (64, 64), 30.0, 8) is None
    assert contour_ink(renderer, model, camera, (64, 64)) is None
    options = dict(size=(64, 64), style="paper")
    assert np.array_equal(
        blueprint.render(model, smooth_contours=True, **options),
        blueprint.render(model, smooth_contours=False, **options),
    )


def test_no_pass_where_no_face_is_smooth(renderer, monkeypatch):
    """Boxes (a building's elements, a plant's): every vertex is on a crease, so no face is
    smooth and none has a contour; no pass over the faces runs, and the dense picture is the
    one drawn without contours."""
    from blueprint.vector import contour_gpu

    positions, faces, parts = [], [], []
    for k in range(300):
        v, f = examples.box(
            (k % 10, (k // 10) % 10, k // 100), (k % 10 + 0.6, (k // 10) % 10 + 0.5, k // 100 + 0.4)
        )
        faces.append(f + 8 * k)
        positions.append(v)
        parts.append(np.full(12, k))
    model = blueprint.Model.from_arrays(np.vstack(positions), np.vstack(faces), np.concatenate(parts))
    size = (48, 48)
    assert model.triangle_count > ink_module.DENSE * size[0] * size[1]
    passes = []
    monkeypatch.setattr(contour_gpu, "run_over", lambda *args: passes.append(args))
    renderer.mesh(model, 30.0)
    assert feature_faces(model, 30.0).all()
    camera, view, projection, found = _found(renderer, model, size=size)
    assert found is None and not passes
    assert contour_ink(renderer, model, camera, size) is None
    options = dict(size=size, style="paper")
    assert np.array_equal(
        blueprint.render(model, smooth_contours=True, **options),
        blueprint.render(model, smooth_contours=False, **options),
    )


@pytest.mark.parametrize("way", ["k-buffer", "peel"])
def test_the_same_lines_every_time_and_from_the_faces_near_them(renderer, monkeypatch, way):
    """The bust's contour lines twice, bit for bit (the pass appends its segments in whatever
    order its invocations run); and from the faces near the lines' samples alone (a fraction of
    them: what the faces k-buffer, or the peel in its place, draws for their levels) the same
    lines, levels and picture as from every face, by either way of capturing them."""
    from blueprint.vector import contour_gpu

    model = noisy_bust()[0]
    camera = fit_camera(model, SIZE, "front")
    monkeypatch.setattr(ink_module, "DENSE", 0.0)
    with one_way(renderer, way):
        found = [contour_ink(renderer, model, camera, SIZE) for _ in range(2)]
        kept = []
        near = contour_gpu.near_faces

        def counted(*args):
            subset = near(*args)
            kept.append(None if subset is None else sum(group[3] for group in subset[0].groups) // 3)
            return subset

        monkeypatch.setattr(contour_gpu, "near_faces", counted)
        found.append(contour_ink(renderer, model, camera, SIZE))
        monkeypatch.setattr(contour_gpu, "near_faces", lambda *args: None)
        found.append(contour_ink(renderer, model, camera, SIZE))
        # and the picture with them is the one with the levels from every face
        options = dict(size=SIZE, view="front", smooth_contours=True, style="paper")
        every = np.asarray(blueprint.render(model, **options))
        monkeypatch.setattr(contour_gpu, "near_faces", near)
        assert np.array_equal(np.asarray(blueprint.render(model, **options)), every)
    assert len(found[0]) >= 5 and len(set(found[0].level.tolist())) > 1
    for other in found[1:]:
        for field in ("points", "offsets", "level", "contoured"):
            assert np.array_equal(getattr(found[0], field), getattr(other, field)), field
    assert 0 < kept[0] < 0.5 * model.triangle_count, kept
