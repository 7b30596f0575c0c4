"""The OBJ reader (``blueprint.scene.formats.obj``) against trimesh, which it stands in for: the
same vertices and faces, in the same order, where it reads a file, None (trimesh then reads it)
for anything else; and a small file against arrays written by hand."""

from __future__ import annotations

import io
import warnings

import numpy as np
import pytest
import trimesh
from helpers import SHARED_MODELS, loaded_in_a_process

from blueprint.scene import loader
from blueprint.scene.formats.obj import obj_arrays


def trimesh_arrays(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = trimesh.load_scene(io.BytesIO(data), file_type="obj", process=False)
    (mesh,) = scene.geometry.values()
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


READ = {
    "triangle": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "crlf, no last newline": b"v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3",
    "comments, tabs, unused vertex": b"# c\n\nv 0\t0 0\nv 1 0 0 \nv 0 1e1 0\nv 5 5 5\nf 1 2 3\n",
    "signs and bare points": b"v .5 -.5 +1.\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "faces first": b"f 3 1 2\nf 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n",
    "interleaved": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 0 0 1\nf 1 2 4\n# end\n",
    "negative index": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -1\n",
    "quads": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\nf 4 3 1 2\n",
    "pentagons": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\nf 1 2 3 4 5\nf 5 4 3 2 1\n",
    "mixed polygons": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\n"
    b"f 1 2 3\nf 1 2 4 3\nf 1 2 3 4 5\nf 1 2\n",
    "normals": b"vn 0 0 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n",
    "normals not given": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n",
    "vertex colour": b"v 0 0 0 1 0 0\nv 1 0 0 1 0 0\nv 0 1 0 1 0 0\nf 1 2 3\n",
    "texture": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
    b"f 1/1 2/2 3/3\nf 2/1 4/2 3/3\nf 1/3 2/2 3/1\n",
    "objects, groups, texture and normals": b"o thing\ng part\ns 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
    b"vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/1/1\ng other\nf 2/1/1 4/2/1 3/3/1 1/2/1\n",
    "mixed polygons, texture, negative": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 3 3 3\nvt 0 0\nvt 1 0\n"
    b"f 1/1 2/2 3/1\nf 1/2 -4/1 3/2 4/1\nf 1/1 2/2 3/1 4/2 -1/1\n",
}

LEFT_TO_TRIMESH = {
    "index out of range": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
    "nan": b"v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n",
    "not a number": b"v 0 0 0\nv 1-0 0\nv 0 1 0\nf 1 2 3\n",
    "material": b"usemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "no faces": b"v 0 0 0\n",
    "empty": b"",
    "line continuation": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n3\n",
    "corners of two forms": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2 3\n",
    "rows of two lengths": b"v 0 0 0\nv 1 0 0 1\nv 0 1 0\nf 1 2 3\n",
    "another keyword": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nf 1 2 3\n",
    "faces of two corners": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
}


@pytest.mark.parametrize("name", READ)
def test_reads_as_trimesh_does(name):
    found = obj_arrays(READ[name])
    assert found is not None
    positions, faces = trimesh_arrays(READ[name])
    np.testing.assert_array_equal(found[0], positions)
    np.testing.assert_array_equal(found[1], faces)
    assert found[0].dtype == np.float64 and found[1].dtype == np.int64


def random_obj(seed: int) -> bytes:
    """An OBJ of random faces of 3 to 6 corners (or all of one count), of one corner form
    (v, v/vt, v//vn, v/vt/vn), with negative indices among them."""
    rng = np.random.default_rng(seed)
    nv, nt, nn = (int(n) for n in rng.integers((4, 1, 1), (40, 10, 5)))
    lines = [f"v {x:.5f} {y:.5f} {z:.5f}" for x, y, z in rng.normal(size=(nv, 3))]
    lines += [f"vt {a:.3f} {b:.3f}" for a, b in rng.random((nt, 2))] + ["vn 0 0 1"] * nn
    form = seed % 4
    for _ in range(int(rng.integers(1, 30))):
        k = 3 + seed % 4 if seed % 3 == 0 else int(rng.integers(3, 7))
        refs = []
        for _ in range(k):
            v = int(rng.integers(1, nv + 1))
            v = v if rng.random() < 0.8 else v - nv - 1
            t, n = int(rng.integers(1, nt + 1)), int(rng.integers(1, nn + 1))
            refs.append([f"{v}", f"{v}/{t}", f"{v}//{n}", f"{v}/{t}/{n}"][form])
        lines.append("f " + " ".join(refs))
    return ("\n".join(lines) + "\n").encode()


@pytest.mark.parametrize("seed", range(24))
def test_random_files_read_as_trimesh_does(seed):
    data = random_obj(seed)
    found = obj_arrays(data)
    assert found is not None
    positions, faces = trimesh_arrays(data)
    np.testing.assert_array_equal(found[0], positions)
    np.testing.assert_array_equal(found[1], faces)


@pytest.mark.parametrize("name", LEFT_TO_TRIMESH)
def test_anything_else_is_left_to_trimesh(name):
    assert obj_arrays(LEFT_TO_TRIMESH[name]) is None


def test_a_file_written_by_hand_reads_as_written():
    """Quads and a pentagon with texture indices: a vertex for each (vertex, texture) pair,
    quads made two triangles each, the pentagon a fan, in trimesh's order (worked out by hand)."""
    data = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nf 1/1 2/1 3/1 4/1\nf 1/2 2/1 3/1\n"
    positions, faces = obj_arrays(data)
    # corners (vertex, texture) 1/1 2/1 3/1 4/1 1/2 2/1 3/1; distinct: (1,1) (1,2) (2,1) (3,1) (4,1)
    np.testing.assert_array_equal(positions, [[0, 0, 0], [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    # lines of two corner counts: each face triangulated as read, the quad as (0 1 2) (2 3 0)
    np.testing.assert_array_equal(faces, [[0, 2, 3], [3, 4, 0], [1, 2, 3]])


@pytest.mark.parametrize("name", ["stanford-bunny.obj", "fandisk.obj", "teapot.obj", "spot.obj"])
def test_real_scans_read_as_trimesh_does(name):
    path = SHARED_MODELS / "common-3d-test-models" / name
    if not path.exists():
        pytest.skip(f"{path} not found (see ../shared/models/README.md)")
    data = path.read_bytes()
    found = obj_arrays(data)
    assert found is not None
    positions, faces = trimesh_arrays(data)
    np.testing.assert_array_equal(found[0], positions)
    np.testing.assert_array_equal(found[1], faces)


def test_loader_model_is_the_trimesh_model(tmp_path):
    """load_model through the plain reader gives the model trimesh's path gave: same arrays,
    part, name and up axis."""
    data = b"v 0 0 0\nv 2 0 0\nv 0 1 0\nv 0 0 1\nv 9 9 9\nf 1 2 3\nf 1 3 4\nf 1 4 2\n"
    path = tmp_path / "tetra.obj"
    path.write_bytes(data)
    fast = loader.load_model(path)
    positions, faces = trimesh_arrays(data)
    np.testing.assert_array_equal(fast.positions, positions.astype(np.float32))
    np.testing.assert_array_equal(fast.faces, faces.astype(np.int32))
    assert fast.part_names == ("tetra",)
    assert (fast.up, fast.up_reason) == (
        loader.up_of(None, "y", True, positions, faces).axis,
        loader.up_of(None, "y", True, positions, faces).reason,
    )


def test_obj_loads_without_trimesh(tmp_path):
    """trimesh (with scipy and networkx) takes longer to import than a scan takes to read."""
    path = tmp_path / "triangle.obj"
    path.write_bytes(READ["objects, groups, texture and normals"])
    assert loaded_in_a_process(path, "len(m.faces)") == ["4", "False"]
