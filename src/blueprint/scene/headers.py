"""Checks of what a model file declares, made before any loader believes it: counts in a
header against the file's size (an ASCII PLY that declares 10^12 faces, or an OFF that claims
ten times the faces it holds, is refused at once instead of being read or silently drawn
short), and scene graphs walked once for cycles, depth, instances and triangles. The checks of
one format live in its module of ``blueprint.scene.formats``; the glTF document's, shared by
GLB and glTF files, and the walk of a graph, shared with 3MF, live here."""

from __future__ import annotations

import contextlib
import contextvars
import gc
import io
from pathlib import Path

from blueprint import settings
from blueprint.errors import InputError
from blueprint.settings import human_size, open_file, read_at_most

# the most of a file read to find its header
HEADER_BYTES = 1 << 16
# the fewest bytes an ASCII value takes: a digit and a separator
ASCII_VALUE = 2
# levels of nodes a glTF scene, or of components a 3MF object, may nest: CAD assemblies go a
# dozen or two deep, and trimesh's 3MF loader takes time cubic in the depth
NODE_DEPTH_LIMIT = 64


def all_of(values: list, *types: type) -> bool:
    """Whether every one of ``values`` is of one of ``types`` exactly (a bool is no int here,
    as in JSON), found by one pass in C."""
    return set(map(type, values)) <= set(types)


def read_head(path: Path, data: bytes | None = None, size: int = HEADER_BYTES) -> bytes:
    """The first ``size`` bytes of a model file: of ``data`` where its contents are in memory
    already (a member of an archive), else read from ``path``."""
    if data is not None:
        return data[:size]
    with open_file(path, settings.MODEL_FILE_LIMIT, "a model file") as fh:
        return fh.read(size)


def read_all(path: Path, data: bytes | None = None) -> bytes:
    """The contents of a model file: ``data`` where given, else the file's, within the limit."""
    if data is not None:
        return data
    limit = settings.MODEL_FILE_LIMIT
    with open_file(path, limit, "a model file") as fh:
        return read_at_most(fh, limit + 1)


@contextlib.contextmanager
def collection_paused():
    """Within, Python's cyclic collector does not run (as it was after): a glTF document's JSON
    and the lists read from it are trees of millions of objects without a cycle, which every
    pass of the collector would walk again for nothing."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def refuse_count(path: Path, count: int, what: str, size: int) -> InputError:
    """The error of a header that declares ``count`` of ``what``, more than ``size`` bytes hold."""
    return InputError(
        f"{path}: the header declares {count} {what}, more than the file's {size} bytes can hold"
    )


def check_gltf_graph(path: Path, ext: str, size: int, data: bytes | None = None) -> None:
    """Raise ``InputError`` where a glTF or GLB file's document is not shaped as the
    specification says, or its node graph is hostile (``check_gltf_document``). ``data``: the
    file's bytes where they are in memory, else the file is read."""
    with collection_paused():
        doc = gltf_document(path, ext, size, data)
        if doc is not None:
            check_gltf_document(path, doc)


def gltf_document(path: Path, ext: str, size: int, data: bytes | None = None):
    """The JSON document of a glTF or GLB file, or None where it is not one a reader can
    follow (trimesh then says what is wrong). ``data`` as for ``check_gltf_graph``.

    Raises
    ------
    InputError
        A GLB header that declares more JSON than the file holds, or JSON nested too deeply.
    """
    return _gltf_json(path, ext, size, settings.MODEL_FILE_LIMIT, data)


def check_gltf_document(path: Path, doc) -> None:
    """Raise ``InputError`` where a glTF document is not shaped as the specification says
    (``check_gltf_shape``), or its node graph has a cycle (node 0 a child of node 1 and node 1
    of node 0), a child that does not exist, more than ``NODE_DEPTH_LIMIT`` levels, more than
    ``INSTANCE_LIMIT`` mesh instances or more triangles than the memory budget holds
    (``check_triangle_count``: their unique ones where the scene is kept as instances). The
    graph is walked once, without recursion, before any loader follows it: trimesh's walk of
    a cycle never ends, and of a deep chain takes time quadratic in its depth."""
    check_gltf_shape(path, doc)
    nodes = doc.get("nodes")
    if not isinstance(nodes, list) or not nodes:
        return
    triangles = _mesh_triangles(doc)
    roots = _gltf_roots(doc, len(nodes))
    if not all_of(roots, int) or (roots and (min(roots) < 0 or max(roots) >= len(nodes))):
        for root in roots:
            _node(path, nodes, root, None)  # the first that is no node, named

    def own(node: int) -> tuple[int, int, int | None]:
        mesh = nodes[node].get("mesh")
        if isinstance(mesh, int) and not isinstance(mesh, bool) and 0 <= mesh < len(triangles):
            return 1, triangles[mesh], mesh
        return 0, 0, None

    if _forest_within_limits(path, nodes, roots, triangles):
        return
    walk_graph(path, roots, lambda node: _children(path, nodes, node), own, "nodes")


def _forest_within_limits(path: Path, nodes: list, roots: list, triangles: list[int]) -> bool:
    """Whether the scene is a forest (no node placed twice, every child a node that exists)
    within the depth, instance and triangle limits, found a level of the tree at a time;
    where not, ``walk_graph`` walks it and names the first problem as it meets it."""
    children = [node.get("children") or [] for node in nodes]
    if not all_of(children, list):
        return False
    placed = [child for below in children for child in below]
    if not all_of(placed, int) or len(set(placed)) != len(placed) or set(placed) & set(roots):
        return False
    if placed and (min(placed) < 0 or max(placed) >= len(nodes)):
        return False
    level, depth, instances, drawn = list(roots), 0, 0, 0
    used: set[int] = set()  # the meshes placed
    while level:
        if depth >= NODE_DEPTH_LIMIT:
            return False
        meshes = [nodes[n].get("mesh") for n in level]
        held = [m for m in meshes if type(m) is int and 0 <= m < len(triangles)]
        instances += len(held)
        drawn += sum(triangles[m] for m in held)
        used.update(held)
        level = [child for n in level for child in children[n]]
        depth += 1
    unique = sum(triangles[m] for m in used)
    estimate = peak_estimate(drawn, unique, instances)
    return instances <= settings.INSTANCE_LIMIT and estimate <= settings.MEMORY_BUDGET


# The fields of a glTF 2.0 document that place and shape its triangles, by the type the
# specification gives them: a type, "numbers" (of the length given), "objects" (a list of
# objects), "nodes[]" (a list of node indices, checked by the walk of the graph), or the name
# of the top-level array an index refers into ("accessors{}": an object of such indices).
# Fields that do not decide the geometry (names, materials, cameras, bounds, extensions) are
# not looked at: trimesh reads past their mistakes, and so may a drawing.
_PRIMITIVE = {"attributes": "accessors{}", "indices": "accessors", "mode": int}
_GLTF_ARRAYS = {
    "scenes": {"nodes": "nodes[]"},
    "nodes": {
        "children": "nodes[]",
        "mesh": "meshes",
        "matrix": ("numbers", 16),
        "translation": ("numbers", 3),
        "rotation": ("numbers", 4),
        "scale": ("numbers", 3),
    },
    "meshes": {"primitives": "objects"},
    "accessors": {
        "bufferView": "bufferViews",
        "byteOffset": int,
        "componentType": int,
        "count": int,
        "type": str,
    },
    "bufferViews": {"byteOffset": int, "byteLength": int, "byteStride": int},
}
_SINGULAR = {"bufferViews": "buffer view", "meshes": "mesh"}
_KINDS = {dict: "an object", list: "a list", str: "a string"}


def _kind(value) -> str:
    """What a JSON value is, in a message: its kind, or a number, true, false or null itself."""
    import json

    if type(value) in _KINDS:
        return _KINDS[type(value)]
    shown = json.dumps(value)
    return shown if len(shown) <= 24 else f"a number of {len(shown)} digits"


def check_gltf_shape(path: Path, doc) -> None:
    """Raise ``InputError`` where a glTF document's JSON is not shaped as the specification
    says, in one line naming the field (``nodes[3].mesh is a string, not a whole number``),
    or where an index refers past the end of its array; checked once before any reader
    trusts a type. The children of nodes and the nodes of scenes are left to the walk of
    the graph, which names them as nodes. Each array is checked a field at a time over all
    its items first; an array where that finds a problem, item by item for its message."""
    if not isinstance(doc, dict):
        raise InputError(f"{path}: not a glTF document (its JSON is {_kind(doc)}, not an object)")
    for name in _GLTF_ARRAYS:
        if name in doc and not isinstance(doc[name], list):
            raise InputError(f"{path}: {name} is {_kind(doc[name])}, not a list")
    _check_field(path, doc, "scene", doc, "scenes", "")
    for name, fields in _GLTF_ARRAYS.items():
        items = doc.get(name, [])
        if _all_fine(doc, items, fields) and (name != "meshes" or _primitives_fine(doc, items)):
            continue
        for index, item in enumerate(items):
            where = f"{name}[{index}]"
            if not isinstance(item, dict):
                raise InputError(f"{path}: {where} is {_kind(item)}, not an object")
            _check_fields(path, doc, item, fields, where + ".")
            if name == "meshes":
                for k, primitive in enumerate(item.get("primitives", [])):
                    _check_fields(path, doc, primitive, _PRIMITIVE, f"{where}.primitives[{k}].")


def _primitives_fine(doc: dict, meshes: list) -> bool:
    primitives = [p for mesh in meshes for p in mesh.get("primitives", [])]
    return all_of(primitives, dict) and _all_fine(doc, primitives, _PRIMITIVE)


def _all_fine(doc: dict, items: list, fields: dict) -> bool:
    """Whether every item is an object whose fields are as ``fields`` wants them (see
    ``_GLTF_ARRAYS``), checked a field at a time over all the items."""
    if not all_of(items, dict):
        return False
    for key, want in fields.items():
        values = [item[key] for item in items if key in item]
        if values and not _values_fine(doc, values, want):
            return False
    return True


def _values_fine(doc: dict, values: list, want) -> bool:
    if want is int:
        return all_of(values, int) and min(values) >= 0
    if want is str:
        return all_of(values, str)
    if want == "nodes[]":
        return all_of(values, list)
    if want == "objects":
        return all_of(values, list) and all_of([v for value in values for v in value], dict)
    if isinstance(want, tuple):
        if not all_of(values, list) or {len(v) for v in values} != {want[1]}:
            return False
        return all_of([v for value in values for v in value], int, float)
    if want.endswith("{}"):
        if not all_of(values, dict):
            return False
        return _values_fine(doc, [v for value in values for v in value.values()], want[:-2])
    count = len(doc.get(want, []))
    return all_of(values, int) and min(values) >= 0 and max(values) < count


def _check_fields(path: Path, doc: dict, item: dict, fields: dict, prefix: str) -> None:
    for key in item:
        want = fields.get(key)
        if want is not None:
            _check_field(path, doc, key, item, want, prefix)


def _check_field(path: Path, doc: dict, key: str, item: dict, want, prefix: str) -> None:
    """Check ``item[key]``, where present, against ``want`` (see ``_GLTF_ARRAYS``)."""
    if key not in item:
        return
    value, where = item[key], f"{prefix}{key}"

    def refuse(expected: str) -> InputError:
        return InputError(f"{path}: {where} is {_kind(value)}, not {expected}")

    if want is int:
        if not _whole(value):
            raise refuse("a whole number")
    elif want is str:
        if not isinstance(value, str):
            raise refuse("a string")
    elif want == "nodes[]":
        if not isinstance(value, list):
            raise refuse("a list")
    elif want == "objects" or isinstance(want, tuple):
        what, count = ("numbers", want[1]) if isinstance(want, tuple) else (want, None)
        if not isinstance(value, list):
            raise refuse(f"a list of {count} {what}" if count else f"a list of {what}")
        odd = [v for v in value if not _ELEMENT[what](v)][:1]
        if odd:
            raise InputError(f"{path}: {where} holds {_kind(odd[0])}, not only {what}")
        if count is not None and len(value) != count:
            raise InputError(f"{path}: {where} holds {len(value)} numbers, not {count}")
    elif want.endswith("{}"):
        if not isinstance(value, dict):
            raise refuse("an object")
        for name, index in value.items():
            _check_index(path, doc, f"{where}.{name}", index, want[:-2])
    else:
        _check_index(path, doc, where, value, want)


def _check_index(path: Path, doc: dict, where: str, value, array: str) -> None:
    if not _whole(value):
        raise InputError(f"{path}: {where} is {_kind(value)}, not a whole number")
    count = len(doc.get(array, []))
    if value >= count:
        what = _SINGULAR.get(array, array[:-1])
        raise InputError(f"{path}: {where} refers to {what} {value}, which does not exist")


_ELEMENT = {
    "objects": lambda v: isinstance(v, dict),
    "numbers": lambda v: isinstance(v, int | float) and not isinstance(v, bool),
}


def _whole(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _gltf_json(path: Path, ext: str, size: int, limit: int, data: bytes | None):
    # imported here: the files of one mesh (STL, OBJ, PLY, OFF) parse no JSON
    import json

    with contextlib.ExitStack() as stack:
        fh = (
            io.BytesIO(data)
            if data is not None
            else stack.enter_context(open_file(path, limit, "a model file"))
        )
        if ext == "gltf":
            raw = read_at_most(fh, limit + 1)
        else:
            head = fh.read(20)
            if len(head) < 20 or head[:4] != b"glTF" or head[16:20] != b"JSON":
                return None
            length = int.from_bytes(head[12:16], "little")
            if length > size - 20:
                raise InputError(
                    f"{path}: the header declares a JSON chunk of {length} bytes, more than the file's "
                    f"{size} bytes can hold"
                )
            raw = fh.read(length)
    try:
        return json.loads(raw.decode("utf-8"))
    except RecursionError:
        raise InputError(f"{path}: its JSON nests too deeply") from None
    except (UnicodeDecodeError, ValueError):
        return None  # not JSON: trimesh's message


def _mesh_triangles(doc: dict) -> list[int]:
    """Triangles of each of the document's meshes, as their accessors declare them, of a
    document whose shape is checked (``check_gltf_shape``): its indices are accessors'."""
    counts = [accessor.get("count", 0) for accessor in doc.get("accessors", [])]
    out = []
    for mesh in doc.get("meshes", []):
        total = 0
        for primitive in mesh.get("primitives", []):
            index = primitive.get("indices")
            if index is None:
                index = primitive.get("attributes", {}).get("POSITION")
            if index is not None:
                total += counts[index] // 3
        out.append(total)
    return out


def _gltf_roots(doc: dict, count: int) -> list:
    scenes = doc.get("scenes")
    roots = []
    if isinstance(scenes, list):
        for scene in scenes:
            if isinstance(scene, dict) and isinstance(scene.get("nodes"), list):
                roots += scene["nodes"]
    return roots if roots else list(range(count))


def walk_graph(path: Path, roots: list, children, own, what: str) -> None:
    """Walk a graph from ``roots`` once, without recursion: ``children(node)`` lists a node's
    children (checked), ``own(node)`` the mesh instances (0 or 1) and triangles a node holds
    itself and its mesh (a key, None where it holds none); ``what`` names the nodes in
    messages ("nodes", "objects"). Refuses a cycle, more than ``NODE_DEPTH_LIMIT`` levels,
    and more instances or triangles than the limits, counted over every path (a node placed
    twice counts twice; ``check_triangle_count`` weighs the meshes' unique triangles too)."""
    instances: dict = {}  # per node: mesh instances below it, itself included
    triangles: dict = {}
    meshes: dict = {}  # the triangles of each mesh placed
    on_path: dict = {}  # nodes of the current path, to their depth
    for root in roots:
        if root in instances:
            continue
        stack = [(root, iter(children(root)))]
        on_path[root] = 0
        while stack:
            node, pending = stack[-1]
            child = next(pending, None)
            if child is None:
                stack.pop()
                del on_path[node]
                kids = children(node)
                count, held, mesh = own(node)
                if mesh is not None:
                    meshes[mesh] = held
                instances[node] = count + sum(instances[c] for c in kids)
                triangles[node] = held + sum(triangles[c] for c in kids)
                check_instance_count(path, instances[node])
                continue
            if child in on_path:
                chain = [n for n, _ in stack[on_path[child] :]] + [child]
                shown = " → ".join(map(str, chain[:8])) + (" → ..." if len(chain) > 8 else "")
                raise InputError(f"{path}: its {what} form a cycle ({shown})")
            if child in instances:
                continue
            if len(stack) >= NODE_DEPTH_LIMIT:
                raise InputError(f"{path}: its {what} nest more than {NODE_DEPTH_LIMIT} deep (the limit)")
            on_path[child] = len(stack)
            stack.append((child, iter(children(child))))
    placed = sum(instances[r] for r in roots)
    check_instance_count(path, placed)
    check_triangle_count(path, sum(triangles[r] for r in roots), placed, sum(meshes.values()))


def _kept(triangles: int, unique: int | None) -> bool:
    """Whether the loader keeps a scene of ``triangles`` drawn of ``unique`` as instances;
    a single mesh (``unique`` None) loads nothing of the instances' module."""
    if unique is None:
        return False
    from blueprint.scene.instances import worth_instancing

    return worth_instancing(triangles, unique)


# The bytes a triangle is weighed at where set (``pictures_only``); else the vector drawing's,
# the most any drawing of a loaded model may take.
_TRIANGLE_BYTES: contextvars.ContextVar[int | None] = contextvars.ContextVar("triangle_bytes", default=None)


@contextlib.contextmanager
def pictures_only():
    """Within, models are loaded to be drawn as pictures alone (PNG, layers, pipelines), never
    as vector lines: their triangles are weighed at ``settings.PICTURE_TRIANGLE_BYTES``, not
    the vector drawing's ``settings.TRIANGLE_BYTES``, so a picture the memory budget holds is
    not refused for the lines it will not find."""
    token = _TRIANGLE_BYTES.set(settings.PICTURE_TRIANGLE_BYTES)
    try:
        yield
    finally:
        _TRIANGLE_BYTES.reset(token)


def triangle_bytes() -> int:
    """The bytes a drawn triangle is weighed at here: a picture's within ``pictures_only``,
    else a vector drawing's."""
    chosen = _TRIANGLE_BYTES.get()
    return settings.TRIANGLE_BYTES if chosen is None else chosen


def peak_estimate(triangles: int, unique: int | None = None, instances: int = 0) -> int:
    """Bytes a drawing of ``triangles`` triangles (all instances together) is expected to take
    at its peak over what the process holds before it: ``triangle_bytes()`` a triangle
    and ``settings.PART_BYTES`` each of its ``instances`` mesh instances; where they are
    instances of ``unique`` triangles that the loader keeps as instances
    (``instances.worth_instancing``), its unique triangles' and ``settings.INSTANCE_BYTES``
    an instance."""
    rate = triangle_bytes()
    if _kept(triangles, unique):
        return int(unique) * rate + int(instances) * settings.INSTANCE_BYTES
    return int(triangles) * rate + int(instances) * settings.PART_BYTES


def check_triangle_count(name, count: int, instances: int | None = None, unique: int | None = None) -> None:
    """Raise ``InputError`` where the peak memory of drawing ``count`` triangles (of
    ``instances`` mesh instances of ``unique`` triangles, where a scene places meshes),
    ``peak_estimate``, passes the memory budget (``settings.MEMORY_BUDGET``), naming ``name``,
    the counts, the estimate and the budget: from the header's counts, before any triangle is
    read or made."""
    kept = _kept(count, unique)
    estimate = peak_estimate(count, unique if kept else None, instances or 0)
    if estimate <= settings.MEMORY_BUDGET:
        return
    each = triangle_bytes()
    placed, rate = "", f"{each} bytes a triangle"
    if instances is not None:
        placed = f" ({instances} mesh instances)"
        rate = f"{each} bytes a triangle and {settings.PART_BYTES} an instance"
    if kept:
        placed = f" ({instances} mesh instances of {unique} unique triangles)"
        rate = f"{each} bytes a unique triangle and {settings.INSTANCE_BYTES} an instance"
    raise InputError(
        f"{name}: {count} triangles to draw{placed} need about {human_size(estimate)} of memory at "
        f"{rate}, more than the memory budget of "
        f"{human_size(settings.MEMORY_BUDGET)} ({settings.MEMORY_ENV} sets the budget)"
    )


def check_instance_count(name, count: int) -> None:
    """Raise ``InputError`` naming ``name`` where a scene places more than
    ``settings.INSTANCE_LIMIT`` mesh instances, the most the memory budget holds."""
    limit = settings.INSTANCE_LIMIT
    if count > limit:
        raise InputError(
            f"{name}: its scene holds more than {limit} mesh instances, the most the memory budget of "
            f"{human_size(settings.MEMORY_BUDGET)} holds at {settings.INSTANCE_BYTES} bytes an instance "
            f"({settings.MEMORY_ENV} sets the budget)"
        )


def _node(path: Path, nodes: list, index, parent) -> dict:
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(nodes):
        where = f"node {parent}" if parent is not None else "a scene"
        raise InputError(f"{path}: {where} refers to node {index!r}, which does not exist")
    node = nodes[index]
    if not isinstance(node, dict):
        raise InputError(f"{path}: node {index} is not an object")
    return node


def _children(path: Path, nodes: list, index: int) -> list:
    children = nodes[index].get("children") or []
    if not isinstance(children, list):
        raise InputError(f"{path}: the children of node {index} are not a list")
    for child in children:
        _node(path, nodes, child, index)
    return children
