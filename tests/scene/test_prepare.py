"""Preparing a model for the GPU (``scene.prepare``, ``scene.normals``, ``scene.weld``) against
slow, independent computations on small meshes: corner normals from a loop over every corner
and the faces around it, the vertex split from ``np.unique`` of whole rows, the weld's
grouping with every row's hash the same; and the prepared arrays kept by content."""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest
import trimesh

from blueprint import parallel, settings
from blueprint.render.mesh import GpuMesh
from blueprint.scene import environment, normals, prepare, up, weld
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model
from blueprint.sorting import SortedKeys


def mixed_mesh() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Some 300 faces with every case of the smoothing: a noisy sphere as a triangle soup with
    faces wound the wrong way (smooth vertices, lone creases of noise, chained ones), a box
    (creases), an open fold (a border), a fan of 70 faces (a vertex beyond ``_MAX_DEGREE``), a
    pointed cone, a degenerate face and vertices a hair apart (welded). Three parts."""
    rng = np.random.default_rng(5)
    sphere = trimesh.creation.icosphere(subdivisions=2)
    v = sphere.vertices * (1 + rng.normal(0, 0.04, (len(sphere.vertices), 1)))
    f = sphere.faces.copy()
    f[::5] = f[::5, ::-1]
    soup = v[f].reshape(-1, 3) + rng.normal(0, 1e-9, (3 * len(f), 3))
    parts = [(soup, np.arange(len(soup)).reshape(-1, 3))]
    box = trimesh.creation.box(extents=(0.5, 0.5, 0.5))
    parts.append((box.vertices + (2.0, 0, 0), box.faces))
    fold = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -0.8, 0.6], [1, 1, 0.1]], float) + (0, 2.0, 0)
    parts.append((fold, np.array([[0, 1, 2], [1, 0, 3], [1, 4, 2], [2, 2, 4]])))
    ring = np.linspace(0, 2 * np.pi, 70, endpoint=False)
    fan = np.r_[[[0, 0, 0.3]], np.c_[np.cos(ring), np.sin(ring), np.zeros(70)]] + (0, -3.0, 0)
    parts.append((fan, np.c_[np.zeros(70, int), 1 + np.arange(70), 1 + (np.arange(70) + 1) % 70]))
    # a pointed apex on no crease edge whose opposite faces are 120 degrees apart: counted with
    # the sign of their cosine
    ring = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    cone = np.r_[[[0, 0, 1.7]], np.c_[np.cos(ring), np.sin(ring), np.zeros(24)]] + (3.0, 3.0, 0)
    parts.append((cone, np.c_[np.zeros(24, int), 1 + np.arange(24), 1 + (np.arange(24) + 1) % 24]))
    positions, faces, face_part, offset = [], [], [], 0
    for k, (p, fc) in enumerate(parts):
        positions.append(p)
        faces.append(fc + offset)
        face_part.append(np.full(len(fc), min(k, 2)))
        offset += len(p)
    return np.concatenate(positions), np.concatenate(faces), np.concatenate(face_part)


def reference_normals(positions: np.ndarray, faces: np.ndarray, crease_angle: float) -> np.ndarray:
    """``corner_normals`` one corner at a time, as its docstring says."""
    p = positions.astype(np.float64)
    used = np.unique(faces)
    diag = float(np.linalg.norm(p[used].max(axis=0) - p[used].min(axis=0))) or 1.0
    tol2 = (1e-6 * diag) ** 2
    root = list(range(len(p)))

    def find(i):
        while root[i] != i:
            i = root[i]
        return i

    diff = p[:, None] - p[None]
    for i, j in zip(*np.nonzero(np.triu(np.einsum("ijk,ijk->ij", diff, diff) <= tol2, 1)), strict=True):
        root[find(int(i))] = find(int(j))
    welded = [[find(int(i)) for i in face] for face in faces]

    area, unit = [], []
    for face in faces:
        a, b, c = p[face]
        u, w = b - a, c - a
        n = np.array([u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]])
        length = math.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        area.append(n)
        unit.append(n / length if length > 0 else n)

    def cos(f, g):
        return unit[f][0] * unit[g][0] + unit[f][1] * unit[g][1] + unit[f][2] * unit[g][2]

    edge_faces: dict[tuple[int, int], list[int]] = {}
    for f, w in enumerate(welded):
        for k in range(3):
            edge_faces.setdefault(tuple(sorted((w[k], w[(k + 1) % 3]))), []).append(f)
    limit = math.cos(math.radians(crease_angle)) - 1e-9
    anchored = {v for e, fs in edge_faces.items() if len(fs) != 2 for v in e}
    creases = [e for e, fs in edge_faces.items() if len(fs) == 2 and abs(cos(*fs)) < limit]
    on_creases = {}
    for e in creases:
        for v in e:
            on_creases[v] = on_creases.get(v, 0) + 1
    sharp = set(anchored)
    for e in creases:
        alone = all(on_creases[v] == 1 and v not in anchored for v in e)
        if not alone:
            sharp.update(e)

    around: dict[int, list[int]] = {}
    for f, w in enumerate(welded):
        for k in range(3):
            around.setdefault(w[k], []).append(f)  # corners in corner order
    out = np.zeros((len(faces), 3, 3), np.float32)
    for f, w in enumerate(welded):
        for k in range(3):
            total = np.zeros(3)
            if len(around[w[k]]) <= normals._MAX_DEGREE:
                for g in around[w[k]]:
                    c = cos(f, g)
                    if w[k] not in sharp or abs(c) >= limit:
                        total = total + area[g] * np.sign(c)
            length = math.sqrt(total[0] ** 2 + total[1] ** 2 + total[2] ** 2)
            out[f, k] = total / length if length > 0 else unit[f]
    return out


# The corners around vertices of one degree are compared as one table where they are few, and
# a corner at a time where they are many: either way for every test of the answers.
FORMS = {"by table": 1 << 60, "by rows": 0}


@pytest.fixture(params=sorted(FORMS))
def form(request, monkeypatch):
    monkeypatch.setattr(normals, "_ROWS_FROM", FORMS[request.param])
    monkeypatch.setattr(prepare, "_ROWS_FROM", FORMS[request.param])
    return request.param


@pytest.mark.parametrize("crease", [15.0, 30.0, 60.0])
def test_corner_normals_equal_a_loop_over_every_corner(crease, form):
    positions, faces, _ = mixed_mesh()
    np.testing.assert_allclose(
        normals.corner_normals(positions, faces, crease),
        reference_normals(positions, faces, crease),
        atol=2e-7,
    )


def test_smoothing_without_pairs_needs_every_pair_positive():
    """The vertices smoothed without comparing their faces pairwise (``_within_cone``) are ones
    where every pair of faces around them has a positive cosine."""
    positions, faces, _ = mixed_mesh()
    welded = normals.weld_ids(positions, faces)
    cross = np.cross(
        positions[faces[:, 1]] - positions[faces[:, 0]], positions[faces[:, 2]] - positions[faces[:, 0]]
    )
    length = np.linalg.norm(cross, axis=1)
    unit = cross / np.where(length > 0, length, 1)[:, None]
    vertices = welded.max() + 1
    summed = np.stack(
        [np.bincount(welded.ravel(), np.repeat(cross[:, k], 3), minlength=vertices) for k in range(3)], 1
    )
    inside = normals._within_cone(welded, unit, summed, np.linalg.norm(summed, axis=1))
    assert 0 < inside.sum() < vertices
    for v in np.flatnonzero(inside):
        around = unit[np.flatnonzero((welded == v).any(axis=1))]
        assert (around @ around.T > 0).all(), v


def reference_arrays(model: Model, crease: float) -> tuple[np.ndarray, np.ndarray]:
    """``gpu_arrays`` by ``np.unique`` of (vertex, part, quantized normal) rows, the last corner of
    each row giving its normal."""
    corner_normals = normals.corner_normals(model.positions, model.faces, crease).reshape(-1, 3)
    rows = np.column_stack(
        [
            model.faces.reshape(-1),
            np.repeat(model.face_part, 3),
            np.round(corner_normals * 32767).astype(np.int64),
        ]
    )
    unique, inverse = np.unique(rows, axis=0, return_inverse=True)
    last = np.zeros(len(unique), np.int64)
    np.maximum.at(last, inverse.reshape(-1), np.arange(len(rows)))
    vertices = np.zeros(len(unique), prepare.VERTEX)
    vertices["p"] = model.positions[unique[:, 0]]
    vertices["n"] = corner_normals[last]
    vertices["part"] = unique[:, 1]
    return vertices, inverse.reshape(-1).astype(np.uint32)


@pytest.mark.parametrize("threads", [1, 3])
@pytest.mark.parametrize("crease", [15.0, 30.0])
@pytest.mark.parametrize("shape", ["mixed", "indexed-box", "soup"])
def test_gpu_arrays_equal_unique_rows(shape, crease, threads, form, monkeypatch):
    # blocks of a few rows, so that these small meshes are split over the threads
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 8)
    positions, faces, face_part = mixed_mesh()
    if shape == "indexed-box":
        # an indexed box whose parts share vertices: corners split by part and by crease
        box = trimesh.creation.box()
        positions, faces, face_part = box.vertices, box.faces, np.arange(12) % 3
    elif shape == "soup":
        positions, faces, face_part = (
            positions[faces].reshape(-1, 3),
            np.arange(3 * len(faces)).reshape(-1, 3),
            None,
        )
    model = Model.from_arrays(positions, faces, face_part)
    vertices, indices = prepare._prepare(model, crease, None)
    expected_vertices, expected_indices = reference_arrays(model, crease)
    if shape == "soup":
        # each corner a vertex of the model: merged where they draw alike
        assert vertices[indices].tobytes() == expected_vertices[expected_indices].tobytes()
        assert len(vertices) < len(expected_vertices)
        return
    assert vertices.tobytes() == expected_vertices.tobytes()
    np.testing.assert_array_equal(indices, expected_indices)


@pytest.mark.parametrize("threads", [1, 3])
def test_split_vertices_number_the_pairs_of_vertex_and_normal(threads, form, monkeypatch):
    """``_split_vertices`` against the distinct (key, quantized normal) pairs in order, each
    with a corner of its own: keys of a few corners (compared pairwise) and of more than
    ``_TABLE_DEGREE`` (sorted), normals drawn from a few, some keys of one normal alone; the
    corners in blocks of 64 a thread."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 64)
    rng = np.random.default_rng(5)
    sizes = []  # the most corners of a key, each trial
    for _ in range(24):
        n = int(rng.integers(1, 4000))
        keys = max(1, n // int(rng.choice([2, 5, 40, 150])))
        key = rng.integers(0, keys, n) * 7 + 3
        palette = rng.normal(size=(int(rng.integers(1, 5)), 3)).astype(np.float32)
        unit = palette / np.linalg.norm(palette, axis=1, keepdims=True)
        corner_normals = unit[rng.integers(0, len(unit), n)]
        chosen, inverse = prepare._split_vertices(key, corner_normals)
        quantized = prepare._normal_key(corner_normals)
        pairs = sorted(set(zip(key.tolist(), quantized.tolist(), strict=True)))
        number = {pair: k for k, pair in enumerate(pairs)}
        expected = np.array([number[pair] for pair in zip(key.tolist(), quantized.tolist(), strict=True)])
        np.testing.assert_array_equal(inverse, expected)
        # each pair drawn from a corner of its own
        np.testing.assert_array_equal(expected[chosen], np.arange(len(pairs)))
        sizes.append(int(np.bincount(key).max()))
    assert min(sizes) <= prepare._TABLE_DEGREE < max(sizes)


@pytest.mark.parametrize("parts", [1, 2])
def test_a_smooth_soup_draws_its_corners_from_its_welded_vertices(parts):
    """A sphere's soup: one vertex a point and part, whose corners all draw alike (each the
    corner's own position, part and normal, bit for bit), as many as the indexed sphere's."""
    sphere = trimesh.creation.icosphere(subdivisions=2)
    face_part = np.arange(len(sphere.faces)) % parts
    soup = Model.from_arrays(
        sphere.vertices[sphere.faces].reshape(-1, 3),
        np.arange(3 * len(sphere.faces)).reshape(-1, 3),
        face_part,
    )
    vertices, indices = prepare._prepare(soup, 30.0, None)
    corners = soup.faces.reshape(-1)
    corner_normals = normals.corner_normals(soup.positions, soup.faces, 30.0).reshape(-1, 3)
    assert vertices["p"][indices].tobytes() == soup.positions[corners].tobytes()
    assert vertices["n"][indices].tobytes() == corner_normals.tobytes()
    np.testing.assert_array_equal(vertices["part"][indices], np.repeat(face_part, 3))
    shared = np.unique(np.column_stack([sphere.faces.reshape(-1), np.repeat(face_part, 3)]), axis=0)
    assert len(vertices) == len(shared)


def test_gpu_arrays_without_normals_share_vertices_of_one_part():
    positions, faces, face_part = mixed_mesh()
    model = Model.from_arrays(positions, faces, face_part)
    vertices, indices = prepare._prepare(model, None, None)
    assert not vertices["n"].any()
    corner_vertex = model.faces.reshape(-1)
    np.testing.assert_array_equal(vertices["p"][indices], model.positions[corner_vertex])
    np.testing.assert_array_equal(vertices["part"][indices], np.repeat(model.face_part, 3))
    assert len(vertices) == len(np.unique(corner_vertex))  # no vertex here lies in two parts


def test_weld_groups_rows_by_value_when_every_hash_collides(monkeypatch):
    rng = np.random.default_rng(2)
    points = rng.integers(0, 3, (500, 3)).astype(np.float32) * np.float32(0.5)
    points[::7] *= -1  # -0.0 and 0.0 are one position
    expected_inverse, expected_first = weld._exact_groups(points)
    monkeypatch.setattr(weld, "_BITS_HASH", np.zeros(3, np.uint64))
    inverse, first = weld._exact_groups(points)
    np.testing.assert_array_equal(inverse, expected_inverse)
    np.testing.assert_array_equal(first, expected_first)
    # numbered by first occurrence, each the lowest of its equal rows
    _, lowest, numbers = np.unique(points + np.float32(0), axis=0, return_index=True, return_inverse=True)
    assert first.tolist() == sorted(lowest.tolist())
    np.testing.assert_array_equal(first[inverse], lowest[numbers.reshape(-1)])


def test_weld_groups_rows_by_value_where_some_hashes_collide(monkeypatch):
    """A hash of the first coordinate alone: rows that share it and differ in the others
    collide, in runs among runs that do not; the groups are the true hash's."""
    rng = np.random.default_rng(5)
    points = rng.integers(0, 40, (3000, 3)).astype(np.float32)
    points[rng.random(3000) < 0.3, 1:] = 0.0  # runs of one row repeated, beside collisions
    expected_inverse, expected_first = weld._exact_groups(points)
    monkeypatch.setattr(weld, "_BITS_HASH", np.array([0x9E3779B97F4A7C15, 0, 0], np.uint64))
    inverse, first = weld._exact_groups(points)
    np.testing.assert_array_equal(inverse, expected_inverse)
    np.testing.assert_array_equal(first, expected_first)


@pytest.mark.parametrize("tol", [1e-9, 0.3, 2.0])
def test_weld_groups_of_distinct_positions_skip_the_exact_pass_alike(tol):
    """A soup's positions are distinct already (``Model.soup``): welded without the pass that
    groups equal ones, the groups are the same, -0.0 and 0.0 (one position, two bit patterns)
    and points within ``tol`` included."""
    rng = np.random.default_rng(9)
    points = rng.integers(-4, 5, (4000, 3)).astype(np.float32) * np.float32(0.25)
    points = np.unique(points, axis=0)[rng.permutation(len(np.unique(points, axis=0)))]
    zero = np.flatnonzero((points == 0).any(axis=1))[:40]
    points = np.concatenate([points, -points[zero]])  # the same positions with -0.0 for 0.0
    points = np.concatenate([points, points[:50] + np.float32(0.1)])  # close, not equal
    expected_inverse, expected_first = weld.weld_groups(points, tol)
    inverse, first = weld.weld_groups(points, tol, distinct=True)
    np.testing.assert_array_equal(inverse, expected_inverse)
    np.testing.assert_array_equal(first, expected_first)
    assert len(expected_first) < len(points)


def test_a_soup_is_welded_without_the_exact_pass(monkeypatch, tmp_path):
    """The STL reader's positions are distinct: preparing its model welds them without
    grouping equal ones again, to the same arrays."""
    trimesh.creation.icosphere(subdivisions=2).export(tmp_path / "sphere.stl")
    soup = load_model(tmp_path / "sphere.stl")
    assert soup.soup
    with monkeypatch.context() as m:  # welded as positions not known distinct are
        m.setattr(normals, "weld_groups", lambda points, tol, distinct: weld.weld_groups(points, tol))
        expected = prepare._prepare(soup, 30.0, None)
    grouped = []
    exact = weld._exact_groups
    monkeypatch.setattr(weld, "_exact_groups", lambda *a, **k: grouped.append(1) or exact(*a, **k))
    got = prepare._prepare(soup, 30.0, None)
    assert grouped == []
    for a, b in zip(got, expected, strict=True):
        assert a.tobytes() == b.tobytes()


@pytest.mark.parametrize(
    ("same", "at", "runs", "numbers"),
    [
        ([1, 0, 1, 1, 0, 0, 1], [0, 3], [0, 1, 2, 3, 4], [0, 0, 1, 1, 1]),
        ([1, 0, 1, 1, 0, 0, 1], [6], [6, 7], [0, 0]),
        ([1, 1, 1], [1], [0, 1, 2, 3], [0, 0, 0, 0]),
        ([0, 1, 0, 1], [1, 3, 3], [1, 2, 3, 4], [0, 0, 1, 1]),
    ],
)
def test_the_runs_holding_positions(same, at, runs, numbers):
    found, run = weld._runs_holding(np.array(same, bool), np.array(at))
    assert found.tolist() == runs and run.tolist() == numbers


def test_weld_groups_equal_rows_as_one_where_runs_of_collisions_lie_apart():
    """Whole numbers as float64 (their low bits zero) collide in many runs of the hash, with
    runs between them that do not: each equal row in one group, as ``np.unique`` finds them
    (sorted together across the runs, a value's rows straddled a run between and split)."""
    rng = np.random.default_rng(0)
    points = rng.integers(-15, 15, (50_000, 3)).astype(np.float64)
    inverse, first = weld._exact_groups(points)
    assert len(first) == len(np.unique(points, axis=0))
    np.testing.assert_array_equal(points[first][inverse], points)


class _Buffers:
    def __init__(self) -> None:
        self.data: list[bytes] = []

    def buffer(self, data) -> None:
        self.data.append(bytes(memoryview(data)))


def test_a_model_of_the_same_content_skips_the_sorts(monkeypatch):
    monkeypatch.setattr(prepare, "_topologies", type(prepare._topologies)())
    positions, faces, face_part = mixed_mesh()
    first = Model.from_arrays(positions, faces, face_part)
    made = prepare.gpu_arrays(first, 30.0)
    held = prepare.topology(first)
    assert held["welded"].dtype == np.int32 and held[("sharp", 30.0)].dtype == bool

    def refused(*args, **kwargs):
        raise AssertionError("sorted again")

    monkeypatch.setattr(normals, "_welded", refused)
    monkeypatch.setattr(normals, "crease_vertices", refused)
    again = prepare.gpu_arrays(Model.from_arrays(positions.copy(), faces.copy(), face_part.copy()), 30.0)
    assert again[0].tobytes() == made[0].tobytes() and again[1].tobytes() == made[1].tobytes()
    moved = positions.copy()
    moved[0, 0] += 1e-3
    with pytest.raises(AssertionError, match="sorted again"):
        prepare.gpu_arrays(Model.from_arrays(moved, faces, face_part), 30.0)
    with pytest.raises(AssertionError, match="sorted again"):
        prepare.gpu_arrays(first, 20.0)  # another crease angle: its crease vertices
    # GpuMesh uploads the arrays (and the one instance that places them, and its row of the
    # faces table)
    buffers = _Buffers()
    GpuMesh(buffers, first, 30.0)
    assert buffers.data[:2] == [made[0].tobytes(), made[1].tobytes()] and len(buffers.data) == 4


def test_a_drawing_that_keeps_no_topology_prepares_the_same(monkeypatch):
    """Within ``topologies_kept(False)`` nothing is kept, nor the content digested, and the
    arrays are those of a preparation that keeps its topology; the setting before comes back
    after the block."""
    monkeypatch.setattr(prepare, "_topologies", type(prepare._topologies)())
    positions, faces, face_part = mixed_mesh()
    once = Model.from_arrays(positions, faces, face_part)
    with prepare.topologies_kept(False):
        made = prepare.gpu_arrays(once, 30.0)
        with prepare.topologies_kept(True):
            prepare.gpu_arrays(Model.from_arrays(positions, faces, face_part), 30.0)
            assert len(prepare._topologies) == 1
        prepare._topologies.clear()
        prepare.gpu_arrays(once, 20.0)
    assert not prepare._topologies and "digest" not in once._cache
    kept = prepare.gpu_arrays(Model.from_arrays(positions, faces, face_part), 30.0)
    assert len(prepare._topologies) == 1
    assert kept[0].tobytes() == made[0].tobytes() and kept[1].tobytes() == made[1].tobytes()


@pytest.mark.parametrize("crease_angle", [30.0, 10.0, 0.0, None])
def test_a_soup_of_distinct_corners_prepares_as_its_corners_apart(monkeypatch, crease_angle):
    """A soup held as its distinct corners (``Model.soup``: a binary STL's) gives the vertex
    and index arrays of its corners each a vertex of its own, bit for bit, three parts and
    every case of the smoothing; and so does one whose faces were chosen and reordered since
    (its corners no longer numbered by first corner)."""
    monkeypatch.setattr(prepare, "_topologies", type(prepare._topologies)())
    positions, faces, face_part = mixed_mesh()
    corners = positions[faces].reshape(-1, 3).astype(np.float32)
    by_corner = np.arange(len(corners)).reshape(-1, 3)
    _, first, inverse = np.unique(
        corners.view(np.uint32).view(np.dtype((np.void, 12))).ravel(), return_index=True, return_inverse=True
    )
    number = np.empty(len(first), np.int64)
    number[np.argsort(first)] = np.arange(len(first))
    apart = Model.from_arrays(corners, by_corner, face_part)
    soup = apart.replaced(positions=corners[np.sort(first)], faces=number[inverse].reshape(-1, 3), soup=True)
    assert len(soup.positions) < len(corners) // 2

    def same(model: Model, expected: Model) -> None:
        made, wanted = prepare.gpu_arrays(model, crease_angle), prepare.gpu_arrays(expected, crease_angle)
        assert made[0].tobytes() == wanted[0].tobytes() and made[1].tobytes() == wanted[1].tobytes()

    same(soup, apart)
    chosen = np.random.default_rng(2).permutation(len(faces))[: len(faces) // 2]
    expected = Model.from_arrays(corners.reshape(-1, 3, 3)[chosen].reshape(-1, 3), by_corner[: len(chosen)])
    same(
        soup.replaced(faces=soup.faces[chosen], face_part=np.zeros(len(chosen), np.int32), part_names=("a",)),
        expected,
    )


def test_topologies_kept_are_bounded(monkeypatch):
    monkeypatch.setattr(prepare, "_topologies", type(prepare._topologies)())
    box = trimesh.creation.box()
    models = [Model.from_arrays(box.vertices + k, box.faces) for k in range(prepare._KEPT + 3)]
    for model in models:
        prepare.gpu_arrays(model, 30.0)
    assert list(prepare._topologies) == [m.content_digest() for m in models[-prepare._KEPT :]]
    monkeypatch.setattr(prepare, "_KEPT_BYTES", 10)
    prepare.gpu_arrays(models[0], 30.0)
    assert not prepare._topologies


@pytest.mark.parametrize("threads", [1, 3])
def test_up_guess_a_block_at_a_time_equals_all_at_once(monkeypatch, threads):
    """Flat faces at the bottom of every axis in several blocks (over several threads): a
    finely split box under the mixed mesh."""
    positions, faces, _ = mixed_mesh()
    box = trimesh.creation.box(extents=(2, 2, 2)).subdivide().subdivide()
    faces = np.r_[faces, box.faces + len(positions)]
    positions = np.r_[positions, box.vertices - 4.0]
    whole = [up.base_fraction(positions, faces, axis) for axis in range(3)]
    monkeypatch.setattr(up, "_BLOCK", 7)
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 20)
    assert [up.base_fraction(positions, faces, axis) for axis in range(3)] == whole
    assert all(value > 0 for value in whole)


def test_environment_of_faces_out_of_part_order():
    """A skybox and a ground plane found alike whether the faces come part by part or mixed."""
    sky = trimesh.creation.box(extents=(40, 40, 40))
    sky.invert()
    ground = trimesh.creation.box(extents=(30, 0.01, 30))
    ground.apply_translation((0, -0.6, 0))
    meshes = [trimesh.creation.box().apply_translation((k * 1.5, 0, 0)) for k in range(3)]
    meshes[1:1] = [sky, ground]
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes])
    positions = np.concatenate([m.vertices for m in meshes])
    faces = np.concatenate([m.faces + o for m, o in zip(meshes, offsets, strict=False)])
    face_part = np.concatenate([np.full(len(m.faces), k) for k, m in enumerate(meshes)])
    in_order = environment.environment_parts(Model.from_arrays(positions, faces, face_part))
    mixed = np.random.default_rng(0).permutation(len(faces))
    out_of_order = environment.environment_parts(Model.from_arrays(positions, faces[mixed], face_part[mixed]))
    assert in_order.tolist() == [False, True, True, False, False]
    assert out_of_order.tolist() == in_order.tolist()


def test_crease_vertices_of_more_welded_vertices_than_an_int32_key_holds():
    """Edge keys (lo * vertices + hi) of 60 000 vertices pass 2**31: int32 ids say the same as
    int64 ones. A strip three vertices wide, its middle row inside, its heights noisy."""
    n = 20000
    rng = np.random.default_rng(1)
    positions = np.concatenate(
        [np.c_[np.arange(n), np.full(n, row), rng.normal(0, 0.3, n)] for row in range(3)]
    )
    i = np.arange(n - 1)
    faces = np.concatenate(
        [
            np.r_[
                np.c_[i + r * n, i + 1 + r * n, i + (r + 1) * n],
                np.c_[i + 1 + r * n, i + 1 + (r + 1) * n, i + (r + 1) * n],
            ]
            for r in range(2)
        ]
    )
    welded = normals.weld_ids(positions, faces)
    unit = np.cross(
        positions[faces[:, 1]] - positions[faces[:, 0]], positions[faces[:, 2]] - positions[faces[:, 0]]
    )
    unit /= np.linalg.norm(unit, axis=1)[:, None]
    wide = normals.crease_vertices(welded, unit, 30.0, positions, faces)
    narrow = normals.crease_vertices(welded.astype(np.int32), unit, 30.0, positions, faces)
    assert welded.max() ** 2 > 2**31
    np.testing.assert_array_equal(narrow, wide)
    assert 0 < wide[n : 2 * n].sum() < n  # some of the middle row on creases, not all


@pytest.mark.parametrize("threads", [1, 3])
def test_crease_vertices_are_the_ends_of_edges_not_of_two_faces(threads, monkeypatch):
    """With no crease angle passed (180 degrees), the crease vertices are the ends of every
    border and non-manifold edge, counted edge by edge here; edges in blocks of a few, so a
    run of two keys may straddle two threads' blocks."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 8)
    sphere = trimesh.creation.icosphere(subdivisions=2)
    rng = np.random.default_rng(4)
    faces = sphere.faces[rng.random(len(sphere.faces)) > 0.15]  # holes: borders
    faces = np.concatenate([faces, faces[:6]])  # six faces twice: edges of three and four faces
    positions = sphere.vertices
    welded = normals.weld_ids(positions, faces)
    unit = np.cross(
        positions[faces[:, 1]] - positions[faces[:, 0]], positions[faces[:, 2]] - positions[faces[:, 0]]
    )
    unit /= np.linalg.norm(unit, axis=1)[:, None]
    sharp = normals.crease_vertices(welded, unit, 180.0, positions, faces)
    counts: dict = {}
    for face in welded.tolist():
        for k in range(3):
            edge = tuple(sorted((face[k], face[(k + 1) % 3])))
            counts[edge] = counts.get(edge, 0) + 1
    expected = np.zeros(len(sharp), bool)
    for edge, count in counts.items():
        if count != 2:
            expected[list(edge)] = True
    assert 0 < expected.sum() < len(expected)
    np.testing.assert_array_equal(sharp, expected)


def test_content_digest_is_the_triangles():
    box = trimesh.creation.box()
    one = Model.from_arrays(box.vertices, box.faces)
    assert Model.from_arrays(box.vertices.copy(), box.faces.copy()).content_digest() == one.content_digest()
    others = [
        Model.from_arrays(box.vertices, box.faces[::-1]),
        Model.from_arrays(box.vertices, box.faces, np.arange(12) % 2),
        Model.from_arrays(box.vertices, box.faces, part_names=["a", "b"]),
        Model.from_arrays(np.zeros((0, 3)), np.zeros((0, 3), int)),
    ]
    assert len({m.content_digest() for m in [one, *others]}) == 5


@pytest.mark.parametrize("threads", [1, 3])
@pytest.mark.parametrize("small", [True, False])
def test_content_digest_hash_by_size(monkeypatch, small, threads):
    """A mesh below ``_SMALL_DIGEST`` bytes is digested by BLAKE2b (no OpenSSL to load), a
    bigger one by SHA-256: each the hash of the arrays' types, shapes and bytes (a big one's
    as the SHA-256 digests of their blocks of ``_DIGEST_BLOCK`` bytes, in order), and the part
    count, as hashlib computes it."""
    import hashlib

    from blueprint.scene import model as model_module

    monkeypatch.setattr(settings, "THREADS", threads)
    box = trimesh.creation.box()
    m = Model.from_arrays(box.vertices, box.faces, np.arange(12) % 3)
    arrays = (m.positions, m.faces, m.face_part)
    if not small:
        monkeypatch.setattr(model_module, "_SMALL_DIGEST", sum(a.nbytes for a in arrays))
        monkeypatch.setattr(model_module, "_DIGEST_BLOCK", 40)
    expected = hashlib.blake2b() if small else hashlib.sha256()
    for a in arrays:
        expected.update(str((a.dtype.str, a.shape)).encode())
        data = a.tobytes()
        if small:
            expected.update(data)
        else:
            for start in range(0, len(data), 40):
                expected.update(hashlib.sha256(data[start : start + 40]).digest())
    expected.update(b"3")
    assert len(m.part_names) == 3
    assert m.content_digest() == expected.digest()


def _noisy_sphere(soup: bool) -> Model:
    """An icosphere of 5 120 faces, its vertices moved along their radius by noise, in three
    parts, as an indexed mesh or as a triangle soup (a third of its faces wound the other way)."""
    sphere = trimesh.creation.icosphere(subdivisions=4)
    rng = np.random.default_rng(9)
    v = sphere.vertices * (1 + rng.normal(0, 0.02, (len(sphere.vertices), 1)))
    f = sphere.faces.copy()
    f[::3] = f[::3, ::-1]
    face_part = (np.arange(len(f)) // 7) % 3
    if soup:
        return Model.from_arrays(v[f].reshape(-1, 3), np.arange(3 * len(f)).reshape(-1, 3), face_part)
    return Model.from_arrays(v, f, face_part)


@pytest.mark.parametrize("soup", [False, True])
def test_preparing_over_threads_gives_the_same_bits_as_one(soup, monkeypatch):
    model = _noisy_sphere(soup)
    made = {}
    for threads, block in ((1, parallel.MIN_BLOCK), (4, 16), (7, 1000)):
        monkeypatch.setattr(settings, "THREADS", threads)
        monkeypatch.setattr(parallel, "MIN_BLOCK", block)
        topology = {}
        made[threads] = (
            *prepare._prepare(model, 20.0, topology),
            *prepare._prepare(model, None, None),
            topology["welded"],
            topology[("sharp", 20.0)],
            normals.corner_normals(model.positions, model.faces, 20.0),
            weld.weld_groups(model.positions, 1e-3)[0],
        )
    for threads in (4, 7):
        for got, expected in zip(made[threads], made[1], strict=True):
            assert got.dtype == expected.dtype and got.tobytes() == expected.tobytes()
    # the corners draw as the reference's; some vertices lie on creases
    vertices, indices = made[1][:2]
    expected_vertices, expected_indices = reference_arrays(model, 20.0)
    assert vertices[indices].tobytes() == expected_vertices[expected_indices].tobytes()
    assert made[1][5].any()


@pytest.mark.parametrize("parts", [1, 2])
def test_a_soup_with_unused_vertices_between_its_corners_draws_them_as_its_own(parts):
    """Corners in vertex order, with vertices no face uses between them (each welded apart
    from every corner, or onto one): the welded ids of the corners are not dense."""
    sphere = trimesh.creation.icosphere(subdivisions=1)
    soup = sphere.vertices[sphere.faces].reshape(-1, 3)
    lone = np.array([[5.0, 5.0, 5.0], [-5.0, 0.0, 0.0]])
    positions = np.concatenate([soup[:30], lone[:1], soup[30:], lone[1:], soup[:1]])
    corners = np.r_[np.arange(30), 31 + np.arange(len(soup) - 30)]
    model = Model.from_arrays(positions, corners.reshape(-1, 3), np.arange(len(sphere.faces)) % parts)
    vertices, indices = prepare._prepare(model, 30.0, None)
    expected_vertices, expected_indices = reference_arrays(model, 30.0)
    assert vertices[indices].tobytes() == expected_vertices[expected_indices].tobytes()
    assert indices.max() + 1 == len(vertices) < len(corners)


@pytest.mark.parametrize("threads", [1, 2, 4, 5])
@pytest.mark.parametrize("run_corners", [1 << 18, 40, 5])
def test_the_vertex_sums_a_block_at_a_time_equal_one_bincount(threads, run_corners, monkeypatch):
    """Put in order of their vertices' ranges a block of corners a thread, then summed a range
    at a time, each vertex's area normals are those of one ``bincount`` over every corner, bit
    for bit (the same additions in the same order): every vertex one range, ranges of some
    vertices, and a vertex a range."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 6)
    monkeypatch.setattr(normals, "_SUM_CORNERS", run_corners)
    rng = np.random.default_rng(3)
    faces, vertices = 100, 40
    vertex = rng.integers(0, vertices - 3, 3 * faces).astype(np.int32)  # the last three unused
    area = rng.standard_normal((faces, 3)) * 10.0 ** rng.integers(-6, 6, (faces, 1))
    summed, degree = normals._vertex_sums(vertex, area, vertices)
    for axis in range(3):
        expected = np.bincount(vertex, np.repeat(area[:, axis], 3), minlength=vertices)
        assert summed[:, axis].tobytes() == expected.tobytes()
    np.testing.assert_array_equal(degree, np.bincount(vertex, minlength=vertices))


@pytest.mark.parametrize("threads", [1, 2])
def test_sharp_edges_a_block_at_a_time_equal_the_cosines_compared(threads, monkeypatch):
    """The crease test of the paired edges: the cosine between their faces' unit normals below
    the limit up to sign, as computed for every edge at once; the other edges never sharp."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(normals, "_ROWS", 6)
    rng = np.random.default_rng(5)
    unit = rng.standard_normal((20, 3))
    unit /= np.linalg.norm(unit, axis=1)[:, None]
    order = rng.permutation(60)
    paired = np.zeros(59, bool)
    paired[rng.choice(59, 25, replace=False)] = True
    pair = np.flatnonzero(paired)
    limit = np.cos(np.radians(30.0)) - 1e-9
    sharp = np.zeros(59, bool)
    edges = SortedKeys(np.argsort(order))  # keys whose sorted order is ``order``
    parallel.run(partial(normals._pair_sharp, unit, edges, paired, limit, sharp), 59, min_block=5)
    cos = np.einsum("ij,ij->i", unit[order[pair] // 3], unit[order[pair + 1] // 3])
    np.testing.assert_array_equal(np.flatnonzero(sharp), pair[np.abs(cos) < limit])
    assert 0 < sharp.sum() < len(pair)
