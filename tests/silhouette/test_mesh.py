"""Welding, connectivity and orientation on tiny hand-checked meshes."""

import itertools

import numpy as np
import pytest

from blueprint.silhouette import build_adjacency, weld

# Unit cube [0, 1]^3: corner index = 4x + 2y + z; two outward-wound triangles per side.
CUBE_CORNERS = np.array(list(itertools.product((0.0, 1.0), repeat=3)))
CUBE_FACES = np.array(
    [
        [0, 1, 3], [0, 3, 2],  # x = 0
        [4, 6, 7], [4, 7, 5],  # x = 1
        [0, 4, 5], [0, 5, 1],  # y = 0
        [2, 3, 7], [2, 7, 6],  # y = 1
        [0, 2, 6], [0, 6, 4],  # z = 0
        [1, 5, 7], [1, 7, 3],  # z = 1
    ]
)  # fmt: skip


def directed_edges(faces):
    """All (start, end) half-edges of a face array, as a list of tuples."""
    return [(int(a), int(b)) for f in faces for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))]


def test_cube_faces_are_outward_and_closed():
    # Guards the fixture itself: every half-edge appears once and its reverse once.
    half = directed_edges(CUBE_FACES)
    assert len(set(half)) == 36
    assert all((b, a) in half for a, b in half)
    centre = CUBE_CORNERS[CUBE_FACES].mean(axis=1) - 0.5
    n = np.cross(*(CUBE_CORNERS[CUBE_FACES][:, 1:] - CUBE_CORNERS[CUBE_FACES][:, :1]).swapaxes(0, 1))
    assert (np.einsum("ij,ij->i", n, centre) > 0).all()


def test_weld_triangle_soup_cube_to_eight_vertices():
    soup = CUBE_CORNERS[CUBE_FACES].reshape(-1, 3)
    positions, faces = weld(soup, np.arange(36).reshape(12, 3))
    assert positions.shape == (8, 3) and positions.dtype == np.float64
    assert faces.shape == (12, 3) and faces.dtype == np.int64
    # Every welded face names the same corners as the original one.
    np.testing.assert_array_equal(positions[faces], CUBE_CORNERS[CUBE_FACES])


def test_weld_near_duplicates_within_tol_merge_beyond_do_not():
    base = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]])
    near = base[0] + [4e-3, 0.0, 0.0]
    far = base[0] + [0.0, 2e-2, 0.0]
    positions = np.vstack([base, near, far])
    welded, faces = weld(positions, np.array([[0, 1, 2], [3, 1, 4]]), tol=1e-2)
    assert len(welded) == 4
    np.testing.assert_array_equal(faces, [[0, 1, 2], [0, 1, 3]])
    np.testing.assert_array_equal(welded[0], base[0])


def test_weld_merges_across_grid_cell_boundary():
    # The origin pins the grid: with tol = 0.1 the cell boundary nearest 1.0 lies within
    # 1e-8 of it, between 0.999 and 1.001. One pair straddles it on all three axes (a
    # diagonal neighbour cell), the other on x only.
    positions = np.array(
        [[0, 0, 0], [0.999, 0.999, 0.999], [1.001, 1.001, 1.001], [0.999, 3, 3], [1.001, 3, 3],
         [5, 5, 5]]
    )  # fmt: skip
    welded, faces = weld(positions, np.array([[0, 1, 3], [2, 4, 5]]), tol=0.1)
    assert len(welded) == 4
    np.testing.assert_array_equal(faces, [[0, 1, 2], [1, 2, 3]])


def test_weld_default_tol_is_relative_to_bbox_diagonal():
    d = np.sqrt(3.0) * 1000.0  # diagonal of the points below
    positions = np.array([[0.0, 0, 0], [1000.0, 1000, 1000], [0.5e-6 * d, 0, 0], [2e-6 * d, 0, 0]])
    welded, faces = weld(positions, np.array([[0, 1, 2], [0, 1, 3]]))
    np.testing.assert_array_equal(faces, [[0, 1, 0], [0, 1, 2]])
    assert len(welded) == 3


def test_weld_chain_is_transitive_and_zero_tol_is_exact():
    positions = np.array([[0.0, 0, 0], [0.8, 0, 0], [1.6, 0, 0], [-0.0, 0, 0]])
    _, faces = weld(positions, np.array([[0, 1, 2], [3, 1, 2]]), tol=1.0)
    np.testing.assert_array_equal(faces, [[0, 0, 0], [0, 0, 0]])
    welded, faces = weld(positions, np.array([[0, 1, 2], [3, 1, 2]]), tol=0.0)
    assert len(welded) == 3
    np.testing.assert_array_equal(faces, [[0, 1, 2], [0, 1, 2]])


@pytest.mark.parametrize(
    ("positions", "faces", "tol"),
    [
        (np.zeros((3, 2)), np.array([[0, 1, 2]]), None),
        (np.zeros((3, 3)), np.array([[0, 1, 3]]), None),
        (np.zeros((3, 3)), np.array([[0.0, 1.0, 2.0]]), None),
        (np.zeros((3, 3)), np.array([[0, 1, 2]]), -1.0),
        (np.array([[0, 0, 0], [np.nan, 0, 0], [1, 1, 1]]), np.array([[0, 1, 2]]), None),
    ],
)
def test_weld_rejects_bad_arguments(positions, faces, tol):
    with pytest.raises(ValueError):
        weld(positions, faces, tol)


def test_cube_adjacency_has_18_two_face_edges():
    adj = build_adjacency(CUBE_CORNERS[CUBE_FACES].reshape(-1, 3), np.arange(36).reshape(12, 3))
    assert adj.edges.shape == (18, 2) and adj.edges.dtype == np.int64
    assert (adj.edges[:, 0] < adj.edges[:, 1]).all()
    np.testing.assert_array_equal(np.bincount(adj.edge_faces[:, 0]), np.full(18, 2))
    lengths = np.linalg.norm(np.diff(adj.positions[adj.edges], axis=1)[:, 0], axis=1)
    np.testing.assert_allclose(np.sort(lengths), [1.0] * 12 + [np.sqrt(2.0)] * 6)
    assert not adj.flipped.any()
    np.testing.assert_array_equal(adj.component, np.zeros(12))
    # Outward winding is kept, so the normals are the outward axis directions.
    expected = np.repeat(np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1],
                                   [0, 0, 1]]), 2, axis=0)  # fmt: skip
    np.testing.assert_allclose(adj.face_normals, expected, atol=1e-15)


def test_book_of_four_pages_has_one_edge_with_four_faces():
    # Spine from (0,0,0) to (0,0,1); four pages fanning out around it.
    positions = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 0.5], [0, 1, 0.5], [-1, 0, 0.5], [0, -1, 0.5]], float)
    faces = np.array([[0, 1, 2], [0, 1, 3], [1, 0, 4], [0, 1, 5]])
    adj = build_adjacency(positions, faces)
    spine = np.flatnonzero((adj.edges == [0, 1]).all(axis=1))
    assert spine.size == 1
    np.testing.assert_array_equal(
        adj.edge_faces[adj.edge_faces[:, 0] == spine[0]], [[spine[0], f] for f in range(4)]
    )
    assert len(adj.edges) == 9
    np.testing.assert_array_equal(np.sort(np.bincount(adj.edge_faces[:, 0])), [1] * 8 + [4])
    # The spine is not crossed when orienting: every page is its own component, none flipped.
    assert len(np.unique(adj.component)) == 4
    assert not adj.flipped.any()


def test_open_square_has_four_border_edges():
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    adj = build_adjacency(positions, np.array([[0, 1, 2], [0, 2, 3]]))
    count = np.bincount(adj.edge_faces[:, 0])
    np.testing.assert_array_equal(adj.edges[count == 1], [[0, 1], [0, 3], [1, 2], [2, 3]])
    np.testing.assert_array_equal(adj.edges[count == 2], [[0, 2]])


def test_cube_with_flipped_faces_is_made_consistent():
    flip = np.zeros(12, dtype=bool)
    flip[[1, 2, 5, 7, 8, 11]] = True
    faces = np.where(flip[:, None], CUBE_FACES[:, ::-1], CUBE_FACES)
    adj = build_adjacency(CUBE_CORNERS, faces)
    np.testing.assert_array_equal(adj.flipped, flip)
    half = directed_edges(adj.faces)
    assert len(set(half)) == 36
    assert all((b, a) in half for a, b in half)
    # Face 0 seeds the search and is outward, so all normals end up outward.
    centre = adj.positions[adj.faces].mean(axis=1) - 0.5
    assert (np.einsum("ij,ij->i", adj.face_normals, centre) > 0).all()
    # Same vertex sets as the input, original face order.
    np.testing.assert_array_equal(np.sort(adj.faces, axis=1), np.sort(faces, axis=1))


def test_two_components_are_oriented_independently():
    faces = np.vstack([CUBE_FACES, CUBE_FACES[:, ::-1] + 8])
    positions = np.vstack([CUBE_CORNERS, CUBE_CORNERS + 5.0])
    adj = build_adjacency(positions, faces)
    np.testing.assert_array_equal(adj.component, [0] * 12 + [1] * 12)
    assert not adj.flipped.any()


def test_mobius_strip_does_not_crash():
    n = 12
    angle = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    twist = angle / 2.0
    ring = np.stack([np.cos(angle), np.sin(angle), np.zeros(n)], axis=1)
    offset = 0.3 * np.stack(
        [np.cos(twist) * np.cos(angle), np.cos(twist) * np.sin(angle), np.sin(twist)], axis=1
    )
    positions = np.vstack([ring - offset, ring + offset])  # i: inner, n + i: outer
    quads = []
    for i in range(n - 1):
        quads.append([i, i + 1, n + i + 1, n + i])
    quads.append([n - 1, n, 0, 2 * n - 1])  # the half twist swaps the two rims
    faces = np.array([[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads])
    adj = build_adjacency(positions, faces)
    np.testing.assert_array_equal(adj.component, np.zeros(2 * n))
    # n rungs and n diagonals inside, and a single boundary loop of 2n edges.
    np.testing.assert_array_equal(np.bincount(np.bincount(adj.edge_faces[:, 0])), [0, 2 * n, 2 * n])
    # A non-orientable surface leaves exactly one interior edge traversed the same way twice
    # (the BFS tree edges are all consistent; the twist shows up on one non-tree edge).
    half = directed_edges(adj.faces)
    assert sum(half.count(h) == 2 for h in set(half)) == 1


def test_merged_winding_is_the_searched_one_where_one_exists():
    from blueprint.silhouette.mesh import _orient, _orient_merged, _orient_searched

    rng = np.random.default_rng(7)
    for trial in range(400):
        n = int(rng.integers(1, 40))
        a, b = rng.integers(0, n, (2, int(rng.integers(0, 3 * n))))
        pairs = np.stack([a[a != b], b[a != b]], axis=1)
        if trial % 2:  # parities of some winding: one can be found
            wound = rng.random(n) < 0.5
            parity = wound[pairs[:, 0]] ^ wound[pairs[:, 1]]
        else:
            parity = rng.random(len(pairs)) < 0.5
        searched = _orient_searched(n, pairs, parity)
        merged = _orient_merged(n, pairs, parity)
        consistent = not np.any(searched[0][pairs[:, 0]] ^ searched[0][pairs[:, 1]] ^ parity)
        assert (merged is not None) == consistent
        for got, expected in zip(_orient(n, pairs, parity), searched, strict=True):
            np.testing.assert_array_equal(got, expected)
            assert got.dtype == expected.dtype


def test_a_drawing_of_a_plain_file_does_not_load_scipy(tmp_path):
    """Its import costs a vector drawing's process 0.4 s of CPU time: orienting the faces of
    an orientable mesh does without it."""
    import subprocess
    import sys

    model = tmp_path / "cube.obj"
    model.write_text(
        "".join(f"v {x:g} {y:g} {z:g}\n" for x, y, z in CUBE_CORNERS)
        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in CUBE_FACES)
    )
    script = (
        "import sys; from blueprint.api.files import render_vector_file; "
        f"render_vector_file({str(model)!r}, {str(tmp_path / 'cube.svg')!r}, size=(64, 64)); "
        "print(sorted(m for m in sys.modules if m.startswith('scipy')))"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_degenerate_faces_get_zero_normals_and_no_edges():
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], float)
    adj = build_adjacency(positions, np.array([[0, 1, 2], [0, 0, 1], [0, 1, 3]]))
    np.testing.assert_array_equal(adj.face_normals, [[0, 0, 1], [0, 0, 0], [0, 0, 0]])
    assert 1 not in adj.edge_faces[:, 1]


def test_empty_mesh():
    adj = build_adjacency(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    assert adj.edges.shape == (0, 2) and adj.faces.shape == (0, 3)


@pytest.mark.parametrize("levels", [4096, 3], ids=["level-by-level", "strip-too-deep"])
def test_breadth_first_distances_equal_scipys_shortest_paths(monkeypatch, levels):
    """The winding search's distances (one breadth-first search, a level at a time, or
    scipy's shortest paths past ``_MAX_LEVELS``) on a random graph with unreachable nodes."""
    from scipy import sparse
    from scipy.sparse import csgraph

    from blueprint.silhouette import mesh

    monkeypatch.setattr(mesh, "_MAX_LEVELS", levels)
    rng = np.random.default_rng(7)
    n = 3000
    source, target = rng.integers(0, n - 100, (2, 4000))  # the last 100 nodes unreachable
    reach = sparse.csr_matrix(
        (np.ones(8000, np.int8), (np.r_[source, target], np.r_[target, source])), shape=(n, n)
    )
    expected = csgraph.shortest_path(reach, method="D", unweighted=True, indices=0)
    assert np.isinf(expected).any() and expected[np.isfinite(expected)].max() > 3
    np.testing.assert_array_equal(mesh._distances(reach, 0), expected)
