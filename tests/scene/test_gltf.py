"""The NumPy GLB reader (``blueprint.scene.formats.gltf``) against trimesh, which it stands in for: the
same instances joined into the same arrays and part names where it reads a file, None (trimesh
then reads it, or refuses it in one line) for anything else."""

from __future__ import annotations

import json
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import SHARED_MODELS, loaded_in_a_process

import blueprint
from blueprint import examples
from blueprint.errors import InputError
from blueprint.scene import loader
from blueprint.scene.formats.gltf import read_glb

GEARBOX = Path(blueprint.__file__).parent / "data" / "gearbox.glb"
SHARED = [
    "glTF-Sample-Models/2CylinderEngine.glb",
    "glTF-Sample-Models/CesiumMilkTruck.glb",
    "trimesh/converted/FM1_satellite.glb",
    "trimesh/converted/cycloidal.glb",
    "trimesh/converted/rod.glb",
    "trimesh/no_indices_3storybuilding.glb",
]


def ours(path: Path):
    instances = read_glb(path.read_bytes())
    assert instances is not None, "left to trimesh"
    return loader._joined(instances, path.stem, str(path))


def theirs(path: Path):
    return loader._flatten(loader._load_scene(path, "glb"), path.stem, str(path))


def assert_same(path: Path, names: bool = True) -> None:
    mine, trimeshs = ours(path), theirs(path)
    for a, b in zip(mine[:3], trimeshs[:3], strict=True):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)
    if names:
        assert mine[3] == trimeshs[3]


# -- a GLB written by hand --------------------------------------------------------------------------
TRIANGLE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
QUAD = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
SOUP = QUAD[[0, 1, 2, 0, 2, 3]]  # two triangles, no indices


class Glb:
    """A GLB file built one array at a time: ``accessor`` appends an array to the binary chunk
    with its view and accessor; the document's other fields are set directly."""

    def __init__(self, **doc) -> None:
        self.binary = b""
        self.doc = {"asset": {"version": "2.0"}, "bufferViews": [], "accessors": [], **doc}

    def accessor(self, array: np.ndarray, kind: int, shape: str, stride: int | None = None) -> int:
        data = np.ascontiguousarray(array)
        rows = data.reshape(len(data), -1)
        if stride is not None:  # rows spread apart, zeros between them
            padded = np.zeros((len(rows), stride), np.uint8)
            padded[:, : rows.strides[0]] = rows.view(np.uint8).reshape(len(rows), -1)
            raw = padded.tobytes()
        else:
            raw = rows.tobytes()
        view = {"buffer": 0, "byteOffset": len(self.binary), "byteLength": len(raw)}
        if stride is not None:
            view["byteStride"] = stride
        self.binary += raw + b"\0" * (-len(raw) % 4)
        self.doc["bufferViews"].append(view)
        self.doc["accessors"].append(
            {
                "bufferView": len(self.doc["bufferViews"]) - 1,
                "componentType": kind,
                "count": len(rows),
                "type": shape,
            }
        )
        return len(self.doc["accessors"]) - 1

    def primitive(self, vertices=TRIANGLE, faces=(0, 1, 2), index_type: int = 5125, **extra) -> dict:
        primitive = {"attributes": {"POSITION": self.accessor(vertices, 5126, "VEC3")}, **extra}
        if faces is not None:
            dtype = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32}[index_type]
            primitive["indices"] = self.accessor(np.asarray(faces, dtype), index_type, "SCALAR")
        return primitive

    def bytes(self) -> bytes:
        doc = {"buffers": [{"byteLength": len(self.binary)}], **self.doc} if self.binary else self.doc
        text = json.dumps(doc).encode()
        text += b" " * (-len(text) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text
        if self.binary:
            body += struct.pack("<II", len(self.binary), 0x004E4942) + self.binary
        return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body

    def write(self, path: Path) -> Path:
        path.write_bytes(self.bytes())
        return path


def assembly() -> Glb:
    """Three meshes, two named alike, placed by matrices and T, R, S under nested nodes."""
    glb = Glb(scene=0)
    glb.doc["meshes"] = [
        {"name": "bolt", "primitives": [glb.primitive()]},
        {"name": "bolt", "primitives": [glb.primitive(QUAD, (0, 1, 2, 0, 2, 3), 5123)]},
        {"primitives": [glb.primitive(SOUP, None)]},
    ]
    glb.accessor(QUAD, 5126, "VEC3")  # an accessor nothing uses
    matrix = np.eye(4)
    matrix[:3, 3] = [5, 6, 7]
    matrix[0, 1] = 0.5
    glb.doc["nodes"] = [
        {"name": "frame", "children": [1, 2, 4], "translation": [1, 2, 3], "rotation": [0.1, 0.7, 0.1, 0.7]},
        {"name": "bolt-left", "mesh": 0, "scale": [2, 2, 2]},
        {"name": "bolt", "mesh": 0, "matrix": matrix.T.ravel().tolist(), "children": [3]},
        {"mesh": 1, "translation": [0, 0, 4], "rotation": [0, 0, 0, 0]},
        {"name": "frame", "mesh": 2, "rotation": [0.0, 0.0, 0.3826834, 0.9238795]},
        {"name": "loose", "mesh": 1},
    ]
    glb.doc["scenes"] = [{"nodes": [0]}]
    return glb


def test_an_assembly_reads_as_trimesh_reads_it(tmp_path):
    path = assembly().write(tmp_path / "assembly.glb")
    assert_same(path)
    # trimesh's walk takes a node's last child first
    assert ours(path)[3] == ["GLTF", "bolt", "bolt_1", "bolt-left"]


def test_many_nodes_placed_in_bulk_read_as_trimesh_reads_them(tmp_path):
    """Node transforms composed in bulk (a level of the tree a matrix product) give trimesh's
    arrays to the bit: 400 nodes four levels deep, by translation, rotation (zero and
    unnormalised quaternions among them), scale, matrix, and matrix with TRS together."""
    rng = np.random.default_rng(5)
    glb = Glb(scene=0)
    glb.doc["meshes"] = [
        {
            "name": "a",
            "primitives": [glb.primitive(rng.normal(size=(5, 3)).astype(np.float32), (0, 1, 2, 2, 3, 4))],
        },
        {"name": "b", "primitives": [glb.primitive(), glb.primitive(QUAD, (0, 1, 2, 0, 2, 3), 5123)]},
    ]
    nodes = []
    for k in range(400):
        node = {"mesh": int(rng.integers(0, 2))}
        kind = k % 6
        if kind in (0, 3, 5):
            node["translation"] = rng.normal(size=3).tolist()
        if kind in (1, 3, 5):
            node["rotation"] = [0, 0, 0, 0] if k % 50 == 1 else (rng.normal(size=4) * 3).tolist()
        if kind in (2, 3):
            node["scale"] = rng.uniform(0.5, 2, 3).tolist()
        if kind in (4, 5):
            node["matrix"] = np.r_[rng.normal(size=12), [0, 0, 0, 1]].reshape(4, 4).T.ravel().tolist()
        nodes.append(node)
    # four levels: nodes 0-3 roots, each of the rest under an earlier node of the level above
    for k in range(4, 400):
        level_start = 4 if k < 40 else (40 if k < 150 else 150)
        parent = int(rng.integers(0 if level_start == 4 else {40: 4, 150: 40}[level_start], level_start))
        nodes[parent].setdefault("children", []).append(k)
    glb.doc["nodes"] = nodes
    glb.doc["scenes"] = [{"nodes": [0, 1, 2, 3]}]
    path = glb.write(tmp_path / "many.glb")
    positions, faces, parts, names = ours(path)
    trimeshs = theirs(path)
    assert len(names) > 400
    np.testing.assert_array_equal(faces, trimeshs[1])
    np.testing.assert_array_equal(parts, trimeshs[2])
    # trimesh multiplies a deep chain in another order: the last bits of a float64 differ
    np.testing.assert_allclose(positions, trimeshs[0], rtol=0, atol=1e-12)
    # to the bit, the transforms of one node at a time, composed down the tree as read
    world = {}
    stack = [(None, root) for root in glb.doc["scenes"][0]["nodes"]]
    placed = []
    while stack:
        parent, index = stack.pop()
        node = nodes[index]
        stack.extend((index, child) for child in node.get("children", []))
        local = one_node_matrix(node)
        world[index] = local if parent is None else world[parent] @ local
        mesh = glb.doc["meshes"][node["mesh"]]
        placed += [world[index] if len(mesh["primitives"]) == 1 else world[index] @ np.eye(4)] * len(
            mesh["primitives"]
        )
    read = read_glb(path.read_bytes())
    assert read.moved.all()
    for transform, expected in zip(read.transform, placed, strict=True):
        np.testing.assert_array_equal(transform, expected)


def quaternion_matrix(q) -> np.ndarray:
    """trimesh.transformations.quaternion_matrix of one (w, x, y, z) quaternion, its squared
    norm summed by ``np.dot`` (trimesh's ``diagonal_dot`` sums it in another order)."""
    q = np.array(q, float)
    n = np.dot(q, q)
    if not n < np.finfo(float).eps * 4:
        q = q * np.sqrt(2.0 / n)
    q = np.outer(q, q)
    return np.array(
        [
            [1.0 - q[2, 2] - q[3, 3], q[1, 2] - q[3, 0], q[1, 3] + q[2, 0], 0.0],
            [q[1, 2] + q[3, 0], 1.0 - q[1, 1] - q[3, 3], q[2, 3] - q[1, 0], 0.0],
            [q[1, 3] - q[2, 0], q[2, 3] + q[1, 0], 1.0 - q[1, 1] - q[2, 2], 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def one_node_matrix(node: dict) -> np.ndarray:
    """A node's transform as trimesh composes it, one matrix product a field: matrix, then
    translation, rotation and scale."""
    matrix = np.eye(4) if "matrix" not in node else np.array(node["matrix"], float).reshape(4, 4).T
    if "translation" in node:
        translation = np.eye(4)
        translation[:3, 3] = node["translation"]
        matrix = np.dot(matrix, translation)
    if "rotation" in node:
        matrix = np.dot(matrix, quaternion_matrix(np.roll(node["rotation"], 1)))
    if "scale" in node:
        matrix = np.dot(matrix, np.diag([*node["scale"], 1.0]))
    return matrix


def test_trimesh_exports_read_as_trimesh_reads_them(tmp_path):
    scene = trimesh.Scene()
    box = trimesh.Trimesh(*examples.box((0, 0, 0), (1, 2, 3)), process=False)
    for k in range(4):
        transform = trimesh.transformations.rotation_matrix(0.3 * k, [0, 1, 1], [k, 0, 0])
        scene.add_geometry(box, node_name=f"box{k}", geom_name="box", transform=transform)
    scene.add_geometry(trimesh.creation.icosphere(2), node_name="ball", transform=np.diag([2.0, 1, 1, 1]))
    scene.add_geometry(trimesh.creation.cylinder(1, 3), parent_node_name="box2", geom_name="pin")
    path = tmp_path / "export.glb"
    path.write_bytes(scene.export(file_type="glb"))
    assert_same(path)
    one = tmp_path / "one.glb"
    one.write_bytes(box.export(file_type="glb"))
    assert_same(one)
    assert ours(one)[3] == ["one"]


@pytest.mark.parametrize(
    "change",
    [
        "strided positions",
        "byte and short indices",
        "a second scene chosen",
        "a node named world",
        "names left empty",
        "a camera node",
        "a camera without its fields",
        "unreachable nodes",
        "a flat scene",
        "a flat scene with a node named world",
        "nodes named after their meshes",
    ],
)
def test_variants_read_as_trimesh_reads_them(tmp_path, change):
    glb = assembly()
    doc = glb.doc
    if change == "strided positions":
        doc["meshes"][0]["primitives"] = [
            {**glb.primitive(), "attributes": {"POSITION": glb.accessor(TRIANGLE, 5126, "VEC3", 16)}}
        ]
    elif change == "byte and short indices":
        doc["meshes"][0]["primitives"] = [glb.primitive(faces=(2, 1, 0), index_type=5121)]
        doc["meshes"][1]["primitives"] = [glb.primitive(QUAD, (0, 1, 2, 0, 2, 3), 5123)]
    elif change == "a second scene chosen":
        doc["scenes"] = [{"nodes": [0]}, {"nodes": [5]}]
        doc["scene"] = 1
    elif change == "a node named world":
        doc["nodes"][1]["name"] = "world"
        doc["nodes"][5]["name"] = "world_1"
    elif change == "names left empty":
        doc["meshes"][0]["name"] = ""
        doc["nodes"][1]["name"] = ""
    elif change in ("a camera node", "a camera without its fields"):
        fields = {"yfov": 0.7, "znear": 0.1}
        if change == "a camera node":
            fields["aspectRatio"] = 1.5
        doc["cameras"] = [{"type": "perspective", "perspective": fields}]
        # camera nodes leave trimesh's graph, subtree and all, until one makes a camera
        doc["nodes"][2]["camera"] = 0
        doc["nodes"][4]["camera"] = 0
        doc["nodes"][1]["camera"] = 0
    elif change == "unreachable nodes":
        doc["nodes"][5]["children"] = [6]
        doc["nodes"].append({"name": "bolt-left", "mesh": 0})
    elif change.startswith("a flat scene"):
        # every node a root, every mesh's and node's name its own: the readers' quick paths
        doc["meshes"][1]["name"] = "nut"
        doc["nodes"][0]["name"] = "frame-0"
        for node in doc["nodes"]:
            node.pop("children", None)
        doc["scenes"] = [{"nodes": [3, 0, 5, 1, 4, 2]}]
        if change.endswith("world"):
            # named after its mesh, so that the part takes the node's name
            doc["meshes"][1]["name"] = doc["nodes"][5]["name"] = "world"
    elif change == "nodes named after their meshes":
        # every part named after its node (the second "bolt" mesh is bolt_1 to trimesh)
        names = {0: "bolt", 1: "bolt_1", 2: "GLTF"}
        for k, node in enumerate(doc["nodes"]):
            if "mesh" in node:
                node["name"] = f"{names[node['mesh']]}-{k}"
    path = glb.write(tmp_path / "variant.glb")
    assert_same(path)
    if change == "nodes named after their meshes":
        # in trimesh's order (a node's last child first)
        assert ours(path)[3] == ["GLTF-4", "bolt-2", "bolt_1-3", "bolt-1"]


def test_a_mesh_of_several_primitives_names_its_parts_after_the_mesh(tmp_path):
    """trimesh names the frames of each primitive with a random suffix; the arrays are its own."""
    glb = Glb(scene=0, scenes=[{"nodes": [0, 1]}])
    glb.doc["meshes"] = [
        {"name": "body", "primitives": [glb.primitive(), glb.primitive(QUAD, (0, 1, 2, 0, 2, 3))]}
    ]
    glb.doc["nodes"] = [{"name": "body-7", "mesh": 0}, {"name": "body", "mesh": 0, "translation": [3, 0, 0]}]
    path = glb.write(tmp_path / "primitives.glb")
    assert_same(path, names=False)
    assert ours(path)[3] == ["body", "body_1", "body[2]", "body_1[2]"]


def test_the_collector_is_paused_while_a_document_is_read_and_left_as_it_was(tmp_path, monkeypatch):
    """A GLB is parsed and read with Python's cyclic collector off, and left on or off as the
    caller had it, also where the file is refused."""
    import gc

    from blueprint.scene.formats import gltf

    seen = []
    real = gltf.read_glb
    monkeypatch.setattr(gltf, "read_glb", lambda *a: seen.append(gc.isenabled()) or real(*a))
    path = assembly().write(tmp_path / "assembly.glb")
    bad = tmp_path / "bad.glb"
    bad.write_bytes(_lie(_simple().bytes(), "a mesh that does not exist"))
    was = gc.isenabled()
    try:
        for enabled in (True, False):
            gc.enable() if enabled else gc.disable()
            assert gltf.read_data(path, path.read_bytes()) is not None
            with pytest.raises(InputError):
                gltf.read_data(bad, bad.read_bytes())
            assert gc.isenabled() == enabled
    finally:
        gc.enable() if was else gc.disable()
    assert seen == [False, False]


def test_many_meshes_read_in_blocks_as_trimesh_reads_them(tmp_path, monkeypatch):
    """The accessors are read a block of them at a time, by one gather each: blocks of a few
    rows over 60 meshes of one to three primitives (byte, short and int indices, none, spread
    out rows), placed once, twice or four times, flattened and kept as instances, give
    trimesh's arrays."""
    from blueprint.scene.formats import gltf

    rng = np.random.default_rng(11)
    glb = Glb(scene=0)
    meshes = []
    for k in range(60):
        primitives = []
        for _ in range(k % 3 + 1):
            count = int(rng.integers(3, 9))
            vertices = rng.normal(size=(count, 3)).astype(np.float32)
            faces = rng.integers(0, count, size=3 * int(rng.integers(1, 5)))
            kind = (5121, 5123, 5125, None)[int(rng.integers(0, 4))]
            if kind is None:  # its vertices three by three
                vertices = vertices[: count - count % 3]
                primitive = glb.primitive(vertices, None)
            else:
                primitive = glb.primitive(vertices, faces, kind)
            if k % 5 == 0:
                primitive["attributes"]["POSITION"] = glb.accessor(vertices, 5126, "VEC3", 20)
            primitives.append(primitive)
        meshes.append({"name": f"m{k % 40}", "primitives": primitives})
    glb.doc["meshes"] = meshes
    monkeypatch.setattr(gltf, "_BLOCK_ROWS", 7)
    # 90 nodes: 30 meshes placed twice, 30 once, flattened
    for count in (90, 240):
        nodes = [{"name": f"n{k}", "mesh": k % 60, "translation": [float(k), 0.0, 0.0]} for k in range(count)]
        glb.doc["nodes"] = nodes
        glb.doc["scenes"] = [{"nodes": list(range(count))}]
        path = glb.write(tmp_path / f"blocks-{count}.glb")
        assert_same(path)
    # 240: each mesh four times, kept as instances
    kept = loader._joined(read_glb(path.read_bytes()), path.stem, str(path), instanced=True)[0]
    scene = loader._load_scene(path, "glb")
    theirs_kept = loader._flatten(scene, path.stem, str(path), instanced=True)[0]
    for field in ("positions", "faces", "vertex_start", "face_start", "mesh", "transform", "part"):
        np.testing.assert_array_equal(getattr(kept, field), getattr(theirs_kept, field))


def test_accessors_laid_end_to_end_read_as_trimesh_reads_them(tmp_path, monkeypatch):
    """Packed accessors one after another in one view each of positions and indices (as most
    writers lay them) are read a block at a time by one copy; a block that holds a gap (an
    accessor moved on by a row) is gathered instead. Blocks of a few rows over 40 meshes give
    trimesh's arrays either way."""
    from blueprint.scene.formats import gltf

    rng = np.random.default_rng(5)
    glb = Glb(scene=0)
    positions, indices, index_at, vertex_at = [], [], 0, 0
    glb.doc["meshes"], glb.doc["accessors"] = [], []
    for k in range(40):
        count = int(rng.integers(3, 9))
        gap = 12 if k == 17 else 0
        positions.append(
            np.zeros(gap, np.uint8).tobytes() + rng.normal(size=(count, 3)).astype("<f4").tobytes()
        )
        faces = rng.integers(0, count, size=3 * int(rng.integers(1, 5))).astype("<u2")
        indices.append(faces.tobytes())
        glb.doc["accessors"] += [
            {
                "bufferView": 0,
                "byteOffset": vertex_at + gap,
                "componentType": 5126,
                "count": count,
                "type": "VEC3",
            },
            {
                "bufferView": 1,
                "byteOffset": index_at,
                "componentType": 5123,
                "count": len(faces),
                "type": "SCALAR",
            },
        ]
        vertex_at += len(positions[-1])
        index_at += len(indices[-1])
        primitive = {"attributes": {"POSITION": 2 * k}, "indices": 2 * k + 1}
        glb.doc["meshes"].append({"name": f"m{k}", "primitives": [primitive]})
    vertex_bytes, index_bytes = b"".join(positions), b"".join(indices)
    index_bytes += b"\0" * (-len(index_bytes) % 4)
    glb.binary = vertex_bytes + index_bytes
    glb.doc["bufferViews"] = [
        {"buffer": 0, "byteOffset": 0, "byteLength": len(vertex_bytes)},
        {"buffer": 0, "byteOffset": len(vertex_bytes), "byteLength": len(index_bytes)},
    ]
    glb.doc["nodes"] = [{"name": f"n{k}", "mesh": k, "translation": [float(k), 0.0, 0.0]} for k in range(40)]
    glb.doc["scenes"] = [{"nodes": list(range(40))}]
    path = glb.write(tmp_path / "end-to-end.glb")
    # blocks of one accessor (each one copy), of a few (the gap's gathered), of all of them
    # (the indices one copy; the positions, across the gap, gathered)
    for block_rows in (1, 7, 40, 1 << 16):
        monkeypatch.setattr(gltf, "_BLOCK_ROWS", block_rows)
        assert_same(path)


@pytest.mark.parametrize("name", [GEARBOX.name, *SHARED])
def test_shipped_and_shared_models_read_as_trimesh_reads_them(name):
    path = GEARBOX if name == GEARBOX.name else SHARED_MODELS / name
    if not path.exists():
        pytest.skip(f"{path} not found (see ../shared/models/README.md)")
    assert_same(path)


def test_loader_model_is_the_trimesh_model():
    """The whole load (up axis, degenerate faces, parts) through either reader."""
    fast = loader.load_model(GEARBOX)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = trimesh.load_scene(GEARBOX, process=False)
    slow = loader.model_from_object(scene, name=str(GEARBOX))
    np.testing.assert_array_equal(fast.positions, slow.positions)
    np.testing.assert_array_equal(fast.faces, slow.faces)
    np.testing.assert_array_equal(fast.face_part, slow.face_part)
    assert fast.part_names == slow.part_names and fast.up == slow.up == "y"


def test_a_glb_loads_without_trimesh():
    """trimesh (with scipy and networkx) takes longer to import than most drawings take."""
    assert loaded_in_a_process(GEARBOX, "len(m.part_names)") == ["13", "False"]


# -- left to trimesh ---------------------------------------------------------------------------------
def _left(glb: Glb, change: str) -> None:
    doc = glb.doc
    primitive = doc["meshes"][0]["primitives"][0]
    if change == "buffer by uri":
        doc["buffers"] = [{"byteLength": 4, "uri": "data:application/octet-stream;base64,AAAAAA=="}]
    elif change == "draco":
        primitive["extensions"] = {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {}}}
    elif change == "meshopt":
        doc["bufferViews"][0]["extensions"] = {"EXT_meshopt_compression": {}}
    elif change == "sparse accessor":
        doc["accessors"][0]["sparse"] = {"count": 1}
    elif change == "bufferless accessor":
        del doc["accessors"][0]["bufferView"]
    elif change in ("lines", "strips", "points"):
        primitive["mode"] = {"lines": 1, "strips": 5, "points": 0}[change]
    elif change == "a mode that is a list":  # unhashable: the reader compares, never hashes
        primitive["mode"] = [4]
    elif change == "a component type that is a list":
        glb.doc["accessors"][0]["componentType"] = [5126]
    elif change == "quantised positions":
        doc["accessors"][0]["componentType"] = 5123
    elif change == "float indices":
        doc["accessors"][1]["componentType"] = 5126
    elif change == "indices not in threes":
        doc["accessors"][1]["count"] = 2
    elif change == "a node placed twice":
        doc["nodes"][0]["children"] = [1, 1]
    elif change == "a node name not a string":
        doc["nodes"][1]["name"] = 7
    elif change == "no scenes":
        del doc["scenes"]
    elif change == "a matrix of 15 numbers":
        doc["nodes"][1]["matrix"] = [1.0] * 15
    elif change == "a camera it cannot follow":
        doc["nodes"][1]["camera"] = 3
        doc["cameras"] = []


LEFT = [
    "buffer by uri",
    "draco",
    "meshopt",
    "sparse accessor",
    "bufferless accessor",
    "lines",
    "strips",
    "points",
    "a mode that is a list",
    "a component type that is a list",
    "quantised positions",
    "float indices",
    "indices not in threes",
    "a node placed twice",
    "a node name not a string",
    "no scenes",
    "a matrix of 15 numbers",
    "a camera it cannot follow",
]


def _simple() -> Glb:
    glb = Glb(scene=0, scenes=[{"nodes": [0]}])
    glb.doc["meshes"] = [{"primitives": [glb.primitive()]}]
    glb.doc["nodes"] = [{"children": [1]}, {"mesh": 0}]
    return glb


@pytest.mark.parametrize("change", LEFT)
def test_anything_else_is_left_to_trimesh(change):
    glb = _simple()
    assert read_glb(glb.bytes()) is not None
    _left(glb, change)
    assert read_glb(glb.bytes()) is None


# -- lies and damage: refused in one line, as before -------------------------------------------------
def _lie(data: bytes, change: str) -> bytes:
    head, json_length = data[:12], int.from_bytes(data[12:16], "little")
    doc = json.loads(data[20 : 20 + json_length])
    if change == "an accessor counts 10^12 rows":
        doc["accessors"][0]["count"] = 10**12
    elif change == "a view of 2^62 bytes":
        doc["bufferViews"][0]["byteLength"] = 2**62
    elif change == "a view past the buffer":
        doc["bufferViews"][1]["byteOffset"] = 10**9
    elif change == "a stride of 2^40":
        doc["bufferViews"][0]["byteStride"] = 2**40
    elif change == "a mesh that does not exist":
        doc["nodes"][1]["mesh"] = 9
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + json_length :]
    if change == "a file shorter than its header says":
        rest = rest[:-8]
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + rest
    return head[:8] + struct.pack("<I", 12 + len(body)) + body


@pytest.mark.parametrize(
    "change",
    [
        "an accessor counts 10^12 rows",
        "a view of 2^62 bytes",
        "a view past the buffer",
        "a stride of 2^40",
        "a file shorter than its header says",
    ],
)
def test_lying_sizes_are_refused_in_one_line(tmp_path, change):
    data = _lie(_simple().bytes(), change)
    assert read_glb(data) is None
    path = tmp_path / "lies.glb"
    path.write_bytes(data)
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: cannot read as GLB (the file is damaged or not in that format)"


def test_a_mesh_that_does_not_exist_is_refused(tmp_path):
    """trimesh would leave such a node (and its subtree) out of its graph, and draw the rest
    as if the file were whole."""
    path = tmp_path / "nomesh.glb"
    path.write_bytes(_lie(_simple().bytes(), "a mesh that does not exist"))
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: nodes[1].mesh refers to mesh 9, which does not exist"


@pytest.mark.parametrize("index", [3, 5, 2**31 - 2, 2**32 - 1])
@pytest.mark.parametrize("used", [(0, 1, 2), (2, 1, 0)])
def test_an_index_past_its_own_mesh_is_refused(tmp_path, index, used):
    """An index past its mesh's vertices would name those of the mesh placed next to it, or,
    joined into 32-bit faces, wrap into range: the file is refused, not drawn wrong, whether
    the meshes are placed in the file's order (their faces read as they lie) or not."""
    glb = Glb(scene=0, scenes=[{"nodes": [0, 1, 2]}])
    past = glb.primitive(faces=(0, 1, index))
    glb.doc["meshes"] = [
        {"primitives": [glb.primitive()]},
        {"primitives": [past]},
        {"primitives": [glb.primitive()]},
    ]
    glb.doc["nodes"] = [{"mesh": m, "translation": [2.0 * k, 0, 0]} for k, m in enumerate(used)]
    path = glb.write(tmp_path / "past.glb")
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: faces refer to vertices that do not exist"


def test_a_million_deep_node_chain_is_refused(tmp_path):
    glb = _simple()
    depth = 10**6
    glb.doc["nodes"] = [{"children": [i + 1]} for i in range(depth)] + [{"mesh": 0}]
    path = glb.write(tmp_path / "deep.glb")
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: its nodes nest more than 64 deep (the limit)"
