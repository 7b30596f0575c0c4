"""``connect`` (edges from one sort of packed keys, winding by merging trees a round of roots at
a time, normals a block of faces at a time, over threads) against a plain reference: NumPy's
``unique`` and ``lexsort`` for the edges, a breadth-first search in Python for the winding,
``np.cross`` for the normals. Every array equal, bit for bit, on meshes with what real files
have: duplicate vertices, non-manifold edges, several parts, degenerate faces, flipped faces."""

import collections

import numpy as np
import pytest

from blueprint import parallel, settings
from blueprint.columns import row_norm
from blueprint.silhouette import build_adjacency, weld
from blueprint.silhouette import edges as edges_module
from blueprint.silhouette import mesh as mesh_module
from blueprint.silhouette.mesh import _orient_searched, connect
from blueprint.sorting import SortedKeys

FIELDS = ("positions", "faces", "flipped", "edges", "edge_faces", "component", "face_normals")


def reference_connect(positions, faces):
    """The arrays of ``connect``, made the plain way."""
    positions = np.asarray(positions, np.float64)
    faces = np.asarray(faces, np.int64).reshape(-1, 3)
    num_faces = len(faces)
    proper = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
    half = np.arange(3 * num_faces)[np.repeat(proper, 3)]
    start = faces.reshape(-1)[half]
    end = faces[:, [1, 2, 0]].reshape(-1)[half]
    pair = np.stack([np.minimum(start, end), np.maximum(start, end)], axis=1)
    edges, edge_of = np.unique(pair.reshape(-1, 2), axis=0, return_inverse=True)
    edge_of = edge_of.reshape(-1)
    order = np.lexsort((half, edge_of))
    edge_faces = np.stack([edge_of[order], half[order] // 3], axis=1)

    pairs, parity = manifold_pairs(faces)
    flipped, component = _python_winding(num_faces, pairs, parity)
    if flipped is None:  # no consistent winding: the search's
        flipped, component = _orient_searched(num_faces, pairs, parity)
    oriented = np.where(flipped[:, None], faces[:, [0, 2, 1]], faces)

    corners = positions[oriented]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    area2 = row_norm(cross)
    longest2 = np.zeros(num_faces)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        d = corners[:, b] - corners[:, a]
        longest2 = np.maximum(longest2, (d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2])
    good = area2 > 1e-12 * longest2
    normals = np.zeros((num_faces, 3))
    normals[good] = cross[good] / area2[good, None]
    return {
        "positions": positions,
        "faces": oriented,
        "flipped": flipped,
        "edges": edges.astype(np.int64).reshape(-1, 2),
        "edge_faces": edge_faces.astype(np.int64).reshape(-1, 2),
        "component": component,
        "face_normals": normals,
    }


def manifold_pairs(faces):
    """(M, 2) the two faces of each edge with two, in the order of the edges, and (M,) True
    where both traverse it the same way: the pairs of ``connect``, found with a dictionary."""
    incidences = collections.defaultdict(list)
    for f, face in enumerate(faces.tolist()):
        if len(set(face)) < 3:
            continue
        for k in range(3):
            a, b = face[k], face[(k + 1) % 3]
            incidences[(min(a, b), max(a, b))].append((f, a))
    manifold = [incidences[e] for e in sorted(incidences) if len(incidences[e]) == 2]
    pairs = np.array([[f for f, _ in m] for m in manifold], np.int64).reshape(-1, 2)
    parity = np.array([m[0][1] == m[1][1] for m in manifold], bool)
    return pairs, parity


def _python_winding(num_faces, pairs, parity):
    """Flips relative to each component's lowest face, found by a breadth-first search from it,
    and components numbered by their lowest faces; (None, None) where a pair's parity
    contradicts the flips found."""
    neighbours = collections.defaultdict(list)
    for (a, b), p in zip(pairs.tolist(), parity.tolist(), strict=True):
        neighbours[a].append((b, p))
        neighbours[b].append((a, p))
    flipped = np.zeros(num_faces, bool)
    component = np.full(num_faces, -1, np.int64)
    count = 0
    for seed in range(num_faces):
        if component[seed] >= 0:
            continue
        component[seed] = count
        queue = collections.deque([seed])
        while queue:
            f = queue.popleft()
            for g, p in neighbours[f]:
                if component[g] < 0:
                    component[g] = count
                    flipped[g] = flipped[f] ^ p
                    queue.append(g)
                elif flipped[g] != flipped[f] ^ p:
                    return None, None
        count += 1
    return flipped, component


def assert_same(adj, expected):
    for name, value in expected.items():
        got = getattr(adj, name)
        assert got.dtype == value.dtype, name
        assert got.shape == value.shape, name
        # bit for bit: -0.0 and 0.0 apart, NaN equal to itself
        assert got.tobytes() == value.tobytes(), name


def torus(rows, columns, rng):
    """A closed torus of ``2 * rows * columns`` faces with its vertices and faces shuffled."""
    i, j = np.meshgrid(np.arange(rows), np.arange(columns), indexing="ij")
    u, v = 2 * np.pi * i.ravel() / rows, 2 * np.pi * j.ravel() / columns
    positions = np.stack([(2 + np.cos(v)) * np.cos(u), (2 + np.cos(v)) * np.sin(u), np.sin(v)], axis=1)
    a = (i * columns + j).ravel()
    b = (((i + 1) % rows) * columns + j).ravel()
    c = (((i + 1) % rows) * columns + (j + 1) % columns).ravel()
    d = (i * columns + (j + 1) % columns).ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    relabel = rng.permutation(len(positions))
    shuffled = np.empty_like(positions)
    shuffled[relabel] = positions
    return shuffled, relabel[faces][rng.permutation(len(faces))]


def flip_some(faces, rng, fraction=0.3):
    faces = faces.copy()
    turned = rng.random(len(faces)) < fraction
    faces[turned] = faces[turned][:, [0, 2, 1]]
    return faces


@pytest.fixture(params=[(1, None, None), (3, 7, 5)], ids=["one-thread", "blocks-over-threads"])
def blocks(request, monkeypatch):
    """Run with one thread, or with tiny blocks over three threads: the same results."""
    threads, block, min_block = request.param
    monkeypatch.setattr(settings, "THREADS", threads)
    if block is not None:
        monkeypatch.setattr(mesh_module, "_BLOCK", block)
        monkeypatch.setattr(mesh_module, "_ROWS", block)
        monkeypatch.setattr(edges_module, "_DOT_ROWS", block)
        monkeypatch.setattr(parallel, "MIN_BLOCK", min_block)


@pytest.mark.parametrize("seed", range(6))
def test_random_soups_with_duplicates_and_non_manifold_edges(blocks, seed):
    rng = np.random.default_rng(seed)
    # vertices on a coarse grid: many coincide, and weld into one
    positions = rng.integers(0, 3, (int(rng.integers(4, 40)), 3)).astype(np.float64)
    faces = rng.integers(0, len(positions), (int(rng.integers(1, 120)), 3))
    adj = build_adjacency(positions, faces)
    assert_same(adj, reference_connect(*weld(positions, faces)))
    counts = np.bincount(adj.edge_faces[:, 0], minlength=len(adj.edges))
    if seed == 0:
        assert counts.max() > 2  # non-manifold edges are among them


@pytest.mark.parametrize("seed", range(4))
def test_parts_degenerate_faces_and_flips(blocks, seed):
    """Several tori, some faces flipped, faces with a repeated index, zero-area and sliver
    faces: orientable, so the winding is the one consistent winding."""
    rng = np.random.default_rng(100 + seed)
    parts_positions, parts_faces, offset = [], [], 0
    for part in range(3):
        positions, faces = torus(int(rng.integers(3, 9)), int(rng.integers(3, 9)), rng)
        parts_positions.append(positions + [10.0 * part, 0, 0])
        parts_faces.append(flip_some(faces, rng) + offset)
        offset += len(positions)
    positions = np.concatenate(parts_positions)
    faces = np.concatenate(parts_faces)
    # a face with a repeated index, a zero-area face on three collinear vertices, a sliver
    n = len(positions)
    positions = np.concatenate([positions, [[0, 0, 9], [1, 0, 9], [2, 0, 9], [0, 1e-9, 9]]])
    extra = [[0, 0, 1], [n, n + 1, n + 2], [n, n + 2, n + 3], [5, 5, 5]]
    faces = np.concatenate([faces, extra])
    faces = faces[rng.permutation(len(faces))]
    adj = connect(positions, faces)
    expected = reference_connect(positions, faces)
    assert_same(adj, expected)
    assert expected["flipped"].any() and (expected["face_normals"] == 0).all(axis=1).sum() >= 3
    assert expected["component"].max() >= 3


def test_non_orientable_surface_takes_the_searched_winding(blocks):
    """A Möbius strip has no consistent winding: the breadth-first search's."""
    n = 9
    angle = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rim = []
    for w in (-0.3, 0.3):
        rim.append(
            np.stack(
                [
                    (1 + w * np.cos(angle / 2)) * np.cos(angle),
                    (1 + w * np.cos(angle / 2)) * np.sin(angle),
                    w * np.sin(angle / 2),
                ],
                axis=1,
            )
        )
    positions = np.concatenate(rim)
    quads = [[k, k + 1, n + k + 1, n + k] for k in range(n - 1)] + [[n - 1, n, 0, 2 * n - 1]]
    faces = np.array([[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads])
    assert _python_winding(len(faces), *manifold_pairs(faces))[0] is None
    assert_same(connect(positions, faces), reference_connect(positions, faces))


class UnpackedKeys(SortedKeys):
    """``SortedKeys`` as it holds keys too wide to pack with their positions: the keys and
    their stable order."""

    def __init__(self, key):
        self.length = len(key)
        self._packed = None
        self._key, self._order = key, np.argsort(key, kind="stable")


@pytest.mark.parametrize("packed", [True, False], ids=["packed-keys", "keys-and-order"])
def test_a_mesh_over_many_blocks(blocks, monkeypatch, packed):
    """A torus of 20 000 faces, shuffled, with flips: the blocks' and rounds' bookkeeping at a
    size where the merging takes several rounds; and with the sorted keys held as keys and
    order, as those of a mesh too big to pack them are."""
    if not packed:
        monkeypatch.setattr(mesh_module, "SortedKeys", UnpackedKeys)
    rng = np.random.default_rng(5)
    positions, faces = torus(100, 100, rng)
    faces = flip_some(faces, rng, 0.5)
    faces[::97, 2] = faces[::97, 1]  # faces with a repeated index, their keys past every edge's
    assert_same(connect(positions, faces), reference_connect(positions, faces))


def test_the_callers_faces_are_not_changed():
    rng = np.random.default_rng(9)
    positions, faces = torus(4, 5, rng)
    faces = flip_some(faces, rng, 0.5)
    held = faces.copy()
    adj = connect(positions, faces)
    np.testing.assert_array_equal(faces, held)
    assert adj.flipped.any() and not np.shares_memory(adj.faces, faces)


def test_row_dots_are_einsums_of_the_rows_taken(blocks):
    """The blocked dot products of rows are NumPy's einsum of the whole arrays, bit for bit."""
    rng = np.random.default_rng(3)
    a, b = rng.standard_normal((50, 3)), rng.standard_normal((70, 3))
    at_a, at_b = rng.integers(0, 50, 101), rng.integers(0, 70, 101)
    expected = np.einsum("ij,ij->i", a[at_a], b[at_b])
    assert edges_module._row_dots(a, at_a, b, at_b).tobytes() == expected.tobytes()
    own = np.einsum("ij,ij->i", a[:40], b[at_b[:40]])
    assert edges_module._row_dots(a, None, b, at_b[:40]).tobytes() == own.tobytes()


@pytest.mark.parametrize("parts", [1, 2], ids=["one-part", "two-parts-as-one"])
def test_a_models_adjacency_is_that_of_its_float64_copies(parts):
    """A one-part model is welded from its float32 positions and int32 faces as they are: the
    same arrays as from float64 and int64 copies, with near and exact duplicate vertices,
    -0.0 beside 0.0, an unused vertex and faces flipped. Two parts whose faces all name the
    first are one part."""
    from blueprint.scene.model import Model
    from blueprint.vector.lines import _welded_adjacency

    rng = np.random.default_rng(11)
    positions, faces = torus(6, 7, rng)
    positions = positions.astype(np.float32)
    n = len(positions)
    # an exact duplicate, a near one (within the weld's tolerance), a -0.0 copy, an unused one
    zeros = np.array([[0.0, 2.0, 0.0], [-0.0, 2.0, -0.0]], np.float32)
    extra = np.concatenate([positions[:2], positions[2:3] + np.float32(1e-6), zeros, [[9, 9, 9]]])
    positions = np.concatenate([positions, extra.astype(np.float32)])
    faces = flip_some(faces, rng, 0.4)
    faces[:2, 0] = [n, n + 1]  # corners moved onto the duplicates of vertices 0 and 1
    faces[2, 0] = n + 2
    faces = np.concatenate([faces, [[n + 3, n + 4, 0]]]).astype(np.int32)
    model = Model(positions, faces, np.zeros(len(faces), np.int32), tuple(f"p{k}" for k in range(parts)))
    expected = build_adjacency(positions.astype(np.float64), faces.astype(np.int64))
    assert_same(_welded_adjacency(model), {name: getattr(expected, name) for name in FIELDS})
    assert len(expected.positions) == n + 2  # the duplicates and the zeros welded, one left
