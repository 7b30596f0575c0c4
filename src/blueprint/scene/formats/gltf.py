"""glTF 2.0, binary (GLB) and JSON: Y-up and in metres by its specification.

GLB files are read with NumPy alone, as trimesh loads it: importing trimesh (with the
scipy and networkx it loads) took a CPU second of every glTF drawing's process, more than most
drawings themselves.

The common file is read here: indexed or plain triangles, float positions, node matrices or
translation, rotation and scale, one scene's graph, the names trimesh gives meshes and nodes,
all in trimesh's order (``blueprint.scene.loader`` joins the instances as it joins trimesh's).
Anything else answers None and is left to trimesh, which gives it its meaning or its error:
buffers by URI, compressed or quantised meshes (Draco, meshopt, extensions on primitives or
buffer views), sparse or bufferless accessors, points, lines and strips, a node placed twice,
declared sizes the data cannot hold. Materials, textures and normals are not read: a drawing
has no use for them.

One difference: trimesh names the frames of a mesh of several primitives with random suffixes,
so their parts are named after their meshes here whatever the node's name.
"""

from __future__ import annotations

import itertools
import json
import math
import struct
from pathlib import Path

import numpy as np

from blueprint import parallel, settings
from blueprint.columns import ranges, runs
from blueprint.scene.formats.base import Placed
from blueprint.scene.headers import (
    all_of,
    check_gltf_document,
    check_gltf_graph,
    collection_paused,
    gltf_document,
)
from blueprint.settings import read_file

__all__ = ["Placed", "check_glb", "check_gltf", "read", "read_data", "read_glb"]

_GLB, _JSON, _BIN = 0x46546C67, 0x4E4F534A, 0x004E4942
_TRIANGLES = 4
_DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_INDEX_TYPES = (5121, 5123, 5125)
# rows of accessors read by one gather (``_Accessors.rows``): its indices take 8 bytes a number
_BLOCK_ROWS = 1 << 16
# trimesh's name of the root frame, which a node of the same name is renamed around
_BASE_FRAME = "world"
# trimesh.transformations' threshold of a zero quaternion
_EPS = np.finfo(float).eps * 4.0


class _Leave(Exception):
    """The file is not the common case: trimesh reads it."""


def read_glb(data: bytes, doc: dict | None = None) -> Placed | None:
    """The meshes of a GLB file's scene and their instances in trimesh's order, or None to
    leave the file to trimesh (see the module's docstring). ``doc``: its JSON document, where
    it has been parsed already."""
    try:
        return _read(data, doc)
    except _Leave:
        return None


def _read(data: bytes, doc: dict | None) -> Placed:
    doc, binary = _chunks(data, doc)
    meshes = _meshes(doc, _Accessors(doc, binary))
    nodes = _list(doc.get("nodes", []))
    names = _node_names(nodes)
    roots = _scene_roots(doc, len(nodes))
    visited, parents = _walk(doc, nodes, roots, _children(nodes, roots))
    world = _world(nodes, visited, parents)
    # the visited nodes that place a mesh, and each one's primitives: an instance each
    have = [k for k, index in enumerate(visited) if "mesh" in nodes[index]]
    mesh = _whole([nodes[visited[k]]["mesh"] for k in have])
    first = meshes.first
    if len(mesh) and mesh.max() >= len(first) - 1:
        raise _Leave
    owner = np.array(have, np.int64)
    several = first[mesh + 1] - first[mesh]
    row = np.repeat(np.arange(len(have)), several)
    transform = world[owner[row]]
    # trimesh hangs the primitives of a mesh of several under the node, each by an identity edge
    below = several[row] > 1
    transform[below] = transform[below] @ np.eye(4)
    primitive = ranges(first[mesh], several)
    node = [names[visited[k]] for k in owner[row].tolist()]
    for k in np.flatnonzero(below).tolist():
        node[k] = None
    return Placed(
        meshes.vertices,
        meshes.faces,
        meshes.vertex_start,
        meshes.face_start,
        primitive,
        transform,
        np.ones(len(primitive), bool),
        node,
        [meshes.names[p] for p in primitive.tolist()],
    )


def _walk(doc: dict, nodes: list, roots: list[int], children: list[list[int]]) -> tuple[list[int], list[int]]:
    """The nodes of the scene in trimesh's order (a stack of (parent, child) edges, the last
    pushed taken first), without the camera nodes trimesh takes out of its graph (and what
    hangs below them), and each one's parent's place in that order (-1 for a root)."""
    if not any(children) and not any("camera" in nodes[root] for root in roots):
        # a scene of roots alone, none a camera: the last pushed taken first
        return roots[::-1], [-1] * len(roots)
    cameras = doc.get("cameras")
    camera_taken = False
    placed: dict[int, int] = {}
    visited, parents = [], []
    stack = [(None, root) for root in roots]
    while stack:
        parent, index = stack.pop()
        node = nodes[index]
        stack.extend((index, child) for child in children[index])
        if "camera" in node and not camera_taken:
            # trimesh takes camera nodes (and so their subtrees) out of its graph until one
            # makes a camera
            _check_transform(node)
            camera_taken = _is_camera(cameras, node["camera"])
            continue
        if parent is not None and parent not in placed:
            _check_transform(node)
            continue  # below the camera taken out
        placed[index] = len(visited)
        visited.append(index)
        parents.append(-1 if parent is None else placed[parent])
    return visited, parents


def _world(nodes: list, visited: list[int], parents: list[int]) -> np.ndarray:
    """(N, 4, 4) float64: the transforms from the visited nodes to the scene, as trimesh
    composes them: a root's own, else its parent's times its own, a level of the tree at a
    time (one matrix product a level)."""
    local = _local_matrices([nodes[i] for i in visited])
    parent = np.array(parents, np.int64)
    depth = _depths(parent)
    world = local.copy()
    for level in range(1, int(depth.max(initial=0)) + 1):
        chosen = np.flatnonzero(depth == level)
        world[chosen] = np.matmul(world[parent[chosen]], local[chosen])
    return world


def _depths(parent: np.ndarray) -> np.ndarray:
    """(N,) int64: how many levels each node lies below its root (``parent``: each node's, -1
    for a root), a level at a time (the header's check bounds the levels)."""
    depth = np.zeros(len(parent), np.int64)
    below = np.flatnonzero(parent >= 0)
    while len(below):
        depth[below] = depth[parent[below]] + 1
        # one more than its parent's: final; the rest move down with their parents
        below = below[depth[below] != depth[parent[below]] + 1]
    return depth


def _chunks(data: bytes, doc: dict | None = None) -> tuple[dict, memoryview | None]:
    """The JSON document (``doc`` where parsed already) and the BIN chunk of a GLB file laid
    out as the format asks."""
    if len(data) < 20:
        raise _Leave
    magic, version, length, json_length, kind = struct.unpack_from("<5I", data)
    if magic != _GLB or version != 2 or length != len(data) or kind != _JSON or json_length > length - 20:
        raise _Leave
    if doc is None:
        try:
            doc = json.loads(data[20 : 20 + json_length].decode("utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError):
            raise _Leave from None
    if not isinstance(doc, dict):
        raise _Leave
    # views, not copies: the binary chunk is most of the file
    rest = memoryview(data)[20 + json_length :]
    binary = None
    if rest:
        if len(rest) < 8:
            raise _Leave
        size, kind = struct.unpack_from("<2I", rest)
        if kind != _BIN or 8 + size != len(rest):
            raise _Leave
        binary = rest[8:]
    buffers = _list(doc.get("buffers", []))
    if any(not isinstance(b, dict) or "uri" in b for b in buffers):
        raise _Leave
    return doc, binary


class _Accessors:
    """Every accessor of the document checked against the bytes it reads (as trimesh reads
    them all, a broken one anywhere fails its load), as columns: where each one's rows start in
    the binary chunk and how far apart they lie, in bytes, how many it has, its component type
    and its type."""

    def __init__(self, doc: dict, binary: memoryview | None) -> None:
        self.binary = memoryview(b"") if binary is None else binary
        views = _list(doc.get("bufferViews"))
        if not all_of(views, dict) or any("extensions" in view for view in views):
            raise _Leave
        if views and (binary is None or set(_whole([view.get("buffer") for view in views]).tolist()) != {0}):
            raise _Leave
        size = len(self.binary)
        view_start = _whole([view.get("byteOffset", 0) for view in views])
        view_length = _whole([view.get("byteLength") for view in views])
        strides = [view.get("byteStride") for view in views]
        strided = [k for k, stride in enumerate(strides) if stride is not None]
        view_stride = np.zeros(len(views), np.int64)
        view_stride[strided] = _whole([strides[k] for k in strided])
        if len(views) and ((view_start > size).any() or (view_length > size - view_start).any()):
            raise _Leave
        if (view_stride[strided] == 0).any():
            raise _Leave
        accessors = _list(doc.get("accessors"))
        if not all_of(accessors, dict) or [a for a in accessors if "sparse" in a]:
            raise _Leave
        self.count = _whole([accessor.get("count") for accessor in accessors])
        offset = _whole([accessor.get("byteOffset", 0) for accessor in accessors])
        kind = [accessor.get("componentType") for accessor in accessors]
        shape = [accessor.get("type") for accessor in accessors]
        if not all_of(kind, int) or not set(kind) <= set(_DTYPES):
            raise _Leave
        if not all_of(shape, str) or not set(shape) <= set(_WIDTH):
            raise _Leave
        view = _whole([accessor.get("bufferView") for accessor in accessors])
        if len(view) and view.max() >= len(views):
            raise _Leave
        if (self.count == 0).any():
            raise _Leave
        # the component types and the numbers a row: no two types a row reads as a drawing's
        # share a width (VEC3, SCALAR)
        self.kind = np.array(kind, np.int64)
        self.width = np.array([_WIDTH[t] for t in shape], np.int64)
        row = self.width * np.select([self.kind <= 5121, self.kind <= 5123], [1, 2], 4)
        stride = view_stride[view]
        if (stride[stride > 0] < row[stride > 0]).any():
            raise _Leave  # rows that overlap: spread out, they would take more than the file
        stride = np.where(stride > 0, stride, row)
        # the rows end within the view, told by division: the counts may be any JSON number
        room = view_length[view] - offset - row
        if (room < 0).any() or (self.count - 1 > room // stride).any():
            raise _Leave
        self.start = view_start[view] + offset
        self.stride = stride

    def rows(self, chosen: np.ndarray, dtype: str, width: int) -> np.ndarray:
        """The rows of the accessors ``chosen``, all of component type ``dtype`` and ``width``
        numbers a row, one accessor after another: (rows, width). Read in blocks of accessors
        side by side on the pool, each by one gather, or by one copy where its accessors' rows
        lie packed one after another, of the components as an array of their type: glTF aligns
        each accessor and its stride to its components (a file that does not is left to
        trimesh)."""
        item = np.dtype(dtype).itemsize
        start, stride, count = self.start[chosen], self.stride[chosen], self.count[chosen]
        if (start % item).any() or (stride % item).any():
            raise _Leave
        start, stride = start // item, stride // item
        typed = np.frombuffer(self.binary, dtype, len(self.binary) // item)
        out = np.empty((int(count.sum()), width), dtype)
        first = np.cumsum(count) - count

        def gather(block: tuple[int, int]) -> None:
            lo, hi = block
            held = count[lo:hi]
            ends = start[lo:hi] + held * width
            if (stride[lo:hi] == width).all() and (start[lo + 1 : hi] == ends[:-1]).all():
                # packed rows of accessors laid end to end (as most writers lay them): one span
                out[first[lo] : first[lo] + int(held.sum())] = typed[start[lo] : ends[-1]].reshape(-1, width)
                return
            rows = ranges(np.zeros(hi - lo, np.int64), count[lo:hi])
            at = np.repeat(start[lo:hi], count[lo:hi]) + rows * np.repeat(stride[lo:hi], count[lo:hi])
            out[first[lo] : first[lo] + len(rows)] = typed[at[:, None] + np.arange(width)]

        parallel.each(gather, list(runs(count, _BLOCK_ROWS)))
        return out


class _Meshes:
    """The document's meshes' primitives as columns: ``vertices`` and ``faces`` of each
    primitive one after another, where each one's start (``vertex_start``, ``face_start``,
    M + 1), each one's name (``names``) and where each mesh's primitives start (``first``)."""

    __slots__ = ("vertices", "faces", "vertex_start", "face_start", "names", "first")


def _meshes(doc: dict, access: _Accessors) -> _Meshes:
    """Each mesh's primitives (``_Meshes``), named as trimesh names them: the mesh's name,
    made unique across every primitive of the file."""
    meshes = _list(doc.get("meshes", []))
    if not all_of(meshes, dict):
        raise _Leave
    lists = [mesh.get("primitives") for mesh in meshes]
    if not all_of(lists, list) or not all(lists):
        raise _Leave
    named = [mesh.get("name", "GLTF") for mesh in meshes]
    if not all_of(named, str):
        raise _Leave
    primitives = [p for primitives in lists for p in primitives]
    if not all_of(primitives, dict) or [p for p in primitives if "extensions" in p]:
        raise _Leave
    if [p for p in primitives if p.get("mode", _TRIANGLES) != _TRIANGLES]:
        raise _Leave
    attributes = [p.get("attributes") for p in primitives]
    if not all_of(attributes, dict):
        raise _Leave
    position = _accessor_indices([a.get("POSITION") for a in attributes], len(access.count))
    indexed = [k for k, p in enumerate(primitives) if "indices" in p]
    index = _accessor_indices([primitives[k]["indices"] for k in indexed], len(access.count))
    if (access.kind[position] != 5126).any() or (access.width[position] != 3).any():
        raise _Leave
    if not np.isin(access.kind[index], _INDEX_TYPES).all() or (access.width[index] != 1).any():
        raise _Leave
    corners = access.count[position].copy()
    corners[indexed] = access.count[index]
    if (corners % 3).any():
        raise _Leave
    found = _Meshes()
    found.vertices = access.rows(position, "<f4", 3)
    found.vertex_start = np.r_[0, np.cumsum(access.count[position])]
    found.face_start = np.r_[0, np.cumsum(corners // 3)]
    flat = np.empty(int(corners.sum()), np.int64)
    corner_start = 3 * found.face_start[:-1]
    # a primitive without indices draws its vertices in order
    plain = np.ones(len(primitives), bool)
    plain[indexed] = False
    plain = np.flatnonzero(plain)
    flat[ranges(corner_start[plain], corners[plain])] = ranges(np.zeros(len(plain), np.int64), corners[plain])
    kinds = access.kind[index]
    for kind in _INDEX_TYPES:
        chosen = np.flatnonzero(kinds == kind)
        if len(chosen) == len(primitives):
            flat[:] = access.rows(index, _DTYPES[kind], 1).reshape(-1)  # the common file
        elif len(chosen):
            at = np.asarray(indexed, np.int64)[chosen]
            values = access.rows(index[chosen], _DTYPES[kind], 1).reshape(-1)
            flat[ranges(corner_start[at], corners[at])] = values
    found.faces = flat.reshape(-1, 3)
    found.first = np.r_[0, np.cumsum([len(p) for p in lists], dtype=np.int64)]
    found.names = _primitive_names(named, lists, len(primitives))
    return found


def _primitive_names(named: list[str], lists: list[list], count: int) -> list[str]:
    """Each of ``count`` primitives' name: its mesh's (``named``), made unique in turn."""
    if count == len(named) and "" not in named and len(set(named)) == count:
        return list(named)  # the common file: one primitive a mesh, every name its own
    taken: dict[str, None] = {}
    counts: dict = {}
    names = []
    for name, primitives_of in zip(named, lists, strict=True):
        for _ in primitives_of:
            unique = _unique_name(name, taken, counts)
            taken[unique] = None
            names.append(unique)
    return names


def _accessor_indices(values: list, count: int) -> np.ndarray:
    """``values`` as int64 indices of accessors, each one of the ``count`` there are."""
    indices = _whole(values)
    if len(indices) and indices.max() >= count:
        raise _Leave
    return indices


def _node_names(nodes: list) -> list[str]:
    """Each node's frame name as trimesh gives it: its name or its index, made unique."""
    if not all_of(nodes, dict):
        raise _Leave
    names = [node.get("name", str(index)) for index, node in enumerate(nodes)]
    if not all_of(names, str):
        raise _Leave
    if "" in names or len(set(names)) < len(names):
        # a name given twice, or empty: trimesh's numbers, node by node
        taken: dict[str, int] = {}
        counts: dict = {}
        for index, name in enumerate(names):
            taken[_unique_name(name, taken, counts)] = index
        names = [""] * len(nodes)
        for name, index in taken.items():
            names[index] = name
    if _BASE_FRAME in names:
        names[names.index(_BASE_FRAME)] = _unique_name(_BASE_FRAME, set(names))
    return names


def _scene_roots(doc: dict, count: int) -> list[int]:
    scenes = doc.get("scenes")
    chosen = doc.get("scene", 0)
    if (
        not isinstance(scenes, list)
        or not _is_index(chosen, len(scenes))
        or not isinstance(scenes[chosen], dict)
    ):
        raise _Leave  # no scene to draw: trimesh's load says so
    return _indices(scenes[chosen].get("nodes", []), count)


def _children(nodes: list, roots: list[int]) -> list[list[int]]:
    """Each node's children, checked; leave a node placed twice (in a scene or under two
    parents) to trimesh, whose graph keeps one parent a node."""
    children = [node.get("children", []) for node in nodes]
    if not all_of(children, list):
        raise _Leave
    placed = [child for below in children for child in below]
    if placed and (not all_of(placed, int) or min(placed) < 0 or max(placed) >= len(nodes)):
        raise _Leave
    if len(set(roots).union(placed)) != len(roots) + len(placed):
        raise _Leave
    return children


# the fields of a node's transform, the numbers each holds
_TRANSFORM = {"matrix": 16, "translation": 3, "rotation": 4, "scale": 3}


def _check_transform(node: dict) -> None:
    """Leave a node whose transform is not lists of numbers of the lengths glTF gives them."""
    for key, count in _TRANSFORM.items():
        if key in node:
            _numbers(node[key], count)


def _field(nodes: list[dict], key: str) -> tuple[np.ndarray, np.ndarray]:
    """The nodes that have ``key`` (their places) and its numbers, (K, count) float64."""
    count = _TRANSFORM[key]
    have = [k for k, node in enumerate(nodes) if key in node]
    values = [nodes[k][key] for k in have]
    if values and (not all_of(values, list) or set(map(len, values)) != {count}):
        raise _Leave
    flat = list(itertools.chain.from_iterable(values))
    if not all_of(flat, *_NUMBER):
        raise _Leave
    return np.array(have, np.int64), np.fromiter(flat, np.float64, len(flat)).reshape(-1, count)


def _local_matrices(nodes: list[dict]) -> np.ndarray:
    """(N, 4, 4) float64: each node's transform from its parent as trimesh composes it: its
    matrix, then times translation, rotation and scale. Made in bulk: where a node has no
    matrix, each entry of T R S is one product, which any order of summing gives alike."""
    local = np.broadcast_to(np.eye(4), (len(nodes), 4, 4)).copy()
    fields = {key: _field(nodes, key) for key in _TRANSFORM}
    have, matrices = fields["matrix"]
    local[have] = matrices.reshape(-1, 4, 4).transpose(0, 2, 1)
    # a matrix and TRS (which glTF forbids): composed by matrix products, as trimesh does
    both = np.zeros(len(nodes), bool)
    for key in ("translation", "rotation", "scale"):
        both[fields[key][0]] = True
    with_matrix = np.zeros(len(nodes), bool)
    with_matrix[have] = True
    both &= with_matrix
    for k in np.flatnonzero(both):
        local[k] = _node_matrix(nodes[k])
    have, translation = fields["translation"]
    keep = ~both[have]
    local[have[keep], :3, 3] = translation[keep]
    have, rotation = fields["rotation"]
    keep = ~both[have]
    local[have[keep], :3, :3] = _quaternion_matrices(rotation[keep][:, [3, 0, 1, 2]])[:, :3, :3]
    have, scale = fields["scale"]
    keep = ~both[have]
    local[have[keep], :3, :3] *= scale[keep][:, None, :]
    return local


def _node_matrix(node: dict) -> np.ndarray:
    """The node's transform from its parent as trimesh composes it: matrix, then T, R, S."""
    matrix = np.eye(4) if "matrix" not in node else _numbers(node["matrix"], 16).reshape((4, 4)).T
    if "translation" in node:
        translation = np.identity(4)
        translation[:3, 3] = _numbers(node["translation"], 3)
        matrix = np.dot(matrix, translation)
    if "rotation" in node:
        matrix = np.dot(matrix, _quaternion_matrices(_numbers(node["rotation"], 4)[None, [3, 0, 1, 2]])[0])
    if "scale" in node:
        matrix = np.dot(matrix, np.diag(np.concatenate((_numbers(node["scale"], 3), [1.0]))))
    return matrix


def _quaternion_matrices(q: np.ndarray) -> np.ndarray:
    """(N, 4, 4): trimesh.transformations.quaternion_matrix of each (w, x, y, z) quaternion of
    ``q`` (N, 4), computed as it computes one (its squared norm by ``np.dot``, each's own)."""
    # rows in memory one after another: np.dot sums a strided row in another order
    q = np.ascontiguousarray(q)
    n = np.array([np.dot(row, row) for row in q], np.float64)
    scaled = ~(n < _EPS)
    q = q.copy()
    q[scaled] = q[scaled] * np.sqrt(2.0 / n[scaled])[:, None]
    q = q[:, None, :] * q[:, :, None]
    out = np.zeros((len(q), 4, 4))
    out[:, 0, 0] = 1.0 - q[:, 2, 2] - q[:, 3, 3]
    out[:, 0, 1] = q[:, 1, 2] - q[:, 3, 0]
    out[:, 0, 2] = q[:, 1, 3] + q[:, 2, 0]
    out[:, 1, 0] = q[:, 1, 2] + q[:, 3, 0]
    out[:, 1, 1] = 1.0 - q[:, 1, 1] - q[:, 3, 3]
    out[:, 1, 2] = q[:, 2, 3] - q[:, 1, 0]
    out[:, 2, 0] = q[:, 1, 3] - q[:, 2, 0]
    out[:, 2, 1] = q[:, 2, 3] + q[:, 1, 0]
    out[:, 2, 2] = 1.0 - q[:, 1, 1] - q[:, 2, 2]
    out[:, 3, 3] = 1.0
    return out


def _is_camera(cameras, index) -> bool:
    """Whether trimesh makes a camera of a node's ``camera``: a perspective one with its
    fields (a missing field is no camera); a reference it cannot follow fails its load."""
    if cameras is None:
        return False
    if (
        not isinstance(cameras, list)
        or not _is_index(index, len(cameras))
        or not isinstance(cameras[index], dict)
    ):
        raise _Leave
    if "perspective" not in cameras[index]:
        return False
    perspective = cameras[index]["perspective"]
    if not isinstance(perspective, dict):
        raise _Leave
    fields = [perspective.get(k) for k in ("znear", "aspectRatio", "yfov")]
    if any(f is None for f in fields):
        return False
    if not all(_number(f) and math.isfinite(f) and f > 0 for f in fields):
        raise _Leave
    return True


def _unique_name(start: str, contains, counts: dict | None = None) -> str:
    """trimesh.util.unique_name: ``start``, else ``start_N`` with the first free N (counting on
    from a trailing number of ``start``, and from the last N given where ``counts`` keeps
    them)."""
    if start and start not in contains:
        return start
    increment = 0 if counts is None else counts.get(start, 0)
    if start:
        formatter = start + "_{}"
        split = start.rsplit("_", 1)
        if len(split) == 2 and increment == 0:
            try:
                increment = int(split[1])
                formatter = split[0] + "_{}"
            except ValueError:
                pass
    else:
        formatter = "geometry_{}"
    for i in range(increment + 1, 2 + increment + len(contains)):
        check = formatter.format(i)
        if check not in contains:
            if counts is not None:
                counts[start] = i
            return check
    raise _Leave


def _list(value) -> list:
    if not isinstance(value, list):
        raise _Leave
    return value


# the types of JSON numbers (a bool is an int to isinstance, not to type)
_NUMBER = (int, float)


def _number(value) -> bool:
    return type(value) in _NUMBER


def _count(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _whole(values: list) -> np.ndarray:
    """``values`` as int64, each a whole number of JSON (no bool) that an int64 holds."""
    if not all_of(values, int):
        raise _Leave
    try:
        whole = np.array(values, np.int64)
    except OverflowError:
        raise _Leave from None
    if len(whole) and whole.min() < 0:
        raise _Leave
    return whole


def _is_index(value, length: int) -> bool:
    return _count(value) and value < length


def _indices(value, length: int) -> list[int]:
    if not isinstance(value, list) or not all(_is_index(v, length) for v in value):
        raise _Leave
    return value


def _numbers(value, count: int) -> np.ndarray:
    if not isinstance(value, list) or len(value) != count or not all(_number(v) for v in value):
        raise _Leave
    return np.array(value, dtype=np.float64)


def read(path: Path, size: int) -> Placed | None:
    """The meshes and instances of a GLB file (``read_data``); None where trimesh reads it."""
    return read_data(path, read_file(path, settings.MODEL_FILE_LIMIT, "a model file"))


def read_data(path: Path, data: bytes) -> Placed | None:
    """The meshes and instances of the GLB bytes ``data`` (``read_glb``) of the file ``path``, its
    document and node graph checked first (``check_gltf_document``); None where trimesh
    reads them."""
    with collection_paused():
        doc = gltf_document(path, "glb", len(data), data)
        if doc is None:
            return None
        check_gltf_document(path, doc)
        return read_glb(data, doc)


def check_glb(path: Path, size: int, data: bytes | None = None) -> None:
    """``check_gltf_graph`` of a GLB file."""
    check_gltf_graph(path, "glb", size, data)


def check_gltf(path: Path, size: int, data: bytes | None = None) -> None:
    """``check_gltf_graph`` of a glTF file."""
    check_gltf_graph(path, "gltf", size, data)
