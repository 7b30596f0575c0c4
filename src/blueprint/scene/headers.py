"""Counts a model file's header declares, checked against the file's size before any loader
believes them: an ASCII PLY that declares 10^12 faces, or an OFF that claims ten times the faces
it holds, is refused at once instead of being read (or silently drawn short)."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

from blueprint.errors import InputError
from blueprint.settings import human_size, open_file

# the most of a file read to find its header
HEADER_BYTES = 1 << 16
_PLY_SIZES = {
    **dict.fromkeys(("char", "uchar", "int8", "uint8"), 1),
    **dict.fromkeys(("short", "ushort", "int16", "uint16"), 2),
    **dict.fromkeys(("int", "uint", "float", "int32", "uint32", "float32"), 4),
    **dict.fromkeys(("double", "float64"), 8),
}
# the fewest bytes an ASCII value takes: a digit and a separator
_ASCII_VALUE = 2
# levels of nodes a glTF scene, or of components a 3MF object, may nest: CAD assemblies go a
# dozen or two deep, and trimesh's 3MF loader takes time cubic in the depth
NODE_DEPTH_LIMIT = 64


def check_declared_counts(path: Path, ext: str, size: int, limit: int, data: bytes | None = None) -> None:
    """Raise ``InputError`` where the header of a PLY or OFF file declares more elements than
    ``size`` bytes can hold, or a vertex line of an OBJ file has fewer than three numbers
    (other formats: nothing to check). ``data``: the file's contents where they are in memory
    already (a member of an archive), else the file is read."""
    if ext == "obj":
        _check_obj(path, limit, data)
        return
    if ext not in ("ply", "off"):
        return
    if data is not None:
        head = data[:HEADER_BYTES]
    else:
        with open_file(path, limit, "a model file") as fh:
            head = fh.read(HEADER_BYTES)
    text = head.decode("latin-1")
    if ext == "ply":
        _check_ply(path, text, size)
    elif _check_off(path, text, size):
        if data is None:
            with open_file(path, limit, "a model file") as fh:
                data = fh.read(limit + 1)
        _check_off_faces(path, data)


def _check_obj(path: Path, limit: int, data: bytes | None) -> None:
    """Refuse a vertex line of fewer than three numbers, which trimesh reads as 2-D vertices
    (or, where the counts happen to add up, as vertices shifted by a number)."""
    from blueprint.scene.obj import short_vertex

    if data is None:
        with open_file(path, limit, "a model file") as fh:
            data = fh.read(limit + 1)
    found = short_vertex(data)
    if found is not None:
        line, numbers = found
        counted = f"{numbers} number" + ("" if numbers == 1 else "s")
        raise InputError(f"{path}: line {line}: a vertex of {counted} (x, y and z are needed)")


def _refuse(path: Path, count: int, what: str, size: int) -> InputError:
    return InputError(
        f"{path}: the header declares {count} {what}, more than the file's {size} bytes can hold"
    )


def _check_ply(path: Path, text: str, size: int) -> None:
    end = text.find("end_header")
    if not text.startswith("ply") or end < 0:
        return  # not a header we can read: the loader says what is wrong
    binary = False
    elements: list[tuple[str, int, int]] = []  # name, count, fewest bytes each
    for line in text[:end].splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] == "format" and len(words) > 1:
            binary = words[1].startswith("binary")
        elif words[0] == "element" and len(words) == 3:
            try:
                count = int(words[2])
            except ValueError:
                raise InputError(f"{path}: element {words[1]!r} has no whole count ({words[2]!r})") from None
            if count < 0:
                raise InputError(f"{path}: element {words[1]!r} has a negative count ({count})")
            elements.append((words[1], count, 0))
        elif words[0] == "property" and elements and len(words) >= 3:
            name, count, each = elements[-1]
            if binary:
                # a list takes at least its count; a scalar its type's size
                kind = words[2] if words[1] == "list" else words[1]
                each += _PLY_SIZES.get(kind, 1)
            else:
                each += _ASCII_VALUE
            elements[-1] = (name, count, each)
    body = size - end
    need = 0
    for name, count, each in elements:
        need += count * max(each, 1)
        if need > body:
            raise _refuse(path, count, f"{name} elements", size)


def _check_off(path: Path, text: str, size: int) -> bool:
    """Whether ``text`` begins an OFF header whose counts ``size`` bytes can hold (refused if not)."""
    words: list[str] = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            words += line.split()
        if len(words) >= 4:
            break
    if not words or not words[0].endswith("OFF") or len(words) < 3:
        return False
    try:
        vertices, faces = int(words[1]), int(words[2])
    except ValueError:
        return False
    if vertices < 0 or faces < 0:
        raise InputError(f"{path}: the header declares a negative count ({vertices} vertices, {faces} faces)")
    # a vertex is at least three values, a face its corner count and three corners
    if vertices * 3 * _ASCII_VALUE > size:
        raise _refuse(path, vertices, "vertices", size)
    if vertices * 3 * _ASCII_VALUE + faces * 4 * _ASCII_VALUE > size:
        raise _refuse(path, faces, "faces", size)
    return True


def _check_off_faces(path: Path, data: bytes) -> None:
    """Refuse an OFF face whose corner count is more than the values its line holds (a face
    of 10^9 corners listing three): trimesh reads the first corners and says nothing."""
    lines = (line.split(b"#", 1)[0].split() for line in data.splitlines())
    lines = (words for words in lines if words)
    header = next(lines, [])
    counts = header[1:] if len(header) > 1 else next(lines, [])
    try:
        vertices, faces = int(counts[0]), int(counts[1])
    except (ValueError, IndexError):
        return  # the loader says what is wrong
    for _ in range(vertices):
        if next(lines, None) is None:
            return
    for index in range(faces):
        words = next(lines, None)
        if words is None:
            return
        try:
            corners = int(words[0])
        except ValueError:
            raise InputError(f"{path}: face {index} does not begin with its corner count") from None
        if corners < 1 or corners > len(words) - 1:
            raise InputError(f"{path}: face {index} declares {corners} corners and lists {len(words) - 1}")


def check_scene_graph(path: Path, ext: str, size: int, limit: int, data: bytes | None = None) -> None:
    """Raise ``InputError`` where a glTF or GLB file's node graph has a cycle (node 0 a child of
    node 1 and node 1 of node 0), a child that does not exist, more than ``NODE_DEPTH_LIMIT``
    levels, more than ``INSTANCE_LIMIT`` mesh instances or more than ``TRIANGLE_LIMIT``
    triangles in all. The graph is walked once, without recursion, before any loader follows
    it: trimesh's walk of a cycle never ends, and of a deep chain takes time quadratic in its
    depth. ``data`` as for ``check_declared_counts``."""
    if ext == "3mf":
        _check_3mf(path, limit, data)
        return
    if ext not in ("glb", "gltf"):
        return
    doc = _gltf_json(path, ext, size, limit, data)
    if doc is None:
        return  # not a document we can read: the loader says what is wrong
    check_gltf_shape(path, doc)
    nodes = doc.get("nodes")
    if not isinstance(nodes, list) or not nodes:
        return
    triangles = _mesh_triangles(doc)
    roots = _gltf_roots(doc, len(nodes))
    for root in roots:
        _node(path, nodes, root, None)

    def own(node: int) -> tuple[int, int]:
        mesh = nodes[node].get("mesh")
        if isinstance(mesh, int) and not isinstance(mesh, bool) and 0 <= mesh < len(triangles):
            return 1, triangles[mesh]
        return 0, 0

    _walk(path, roots, lambda node: _children(path, nodes, node), own, "nodes")


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
    if type(value) in _KINDS:
        return _KINDS[type(value)]
    shown = json.dumps(value)
    return shown if len(shown) <= 24 else f"a number of {len(shown)} digits"


def check_gltf_shape(path: Path, doc) -> None:
    """Raise ``InputError`` where a glTF document's JSON is not shaped as the specification
    says, in one line naming the field (``nodes[3].mesh is a string, not a whole number``),
    or where an index refers past the end of its array; checked once before any reader
    trusts a type. The children of nodes and the nodes of scenes are left to the walk of
    the graph, which names them as nodes."""
    if not isinstance(doc, dict):
        raise InputError(f"{path}: not a glTF document (its JSON is {_kind(doc)}, not an object)")
    for name in _GLTF_ARRAYS:
        if name in doc and not isinstance(doc[name], list):
            raise InputError(f"{path}: {name} is {_kind(doc[name])}, not a list")
    _check_field(path, doc, "scene", doc, "scenes", "")
    for name, fields in _GLTF_ARRAYS.items():
        for index, item in enumerate(doc.get(name, [])):
            where = f"{name}[{index}]"
            if not isinstance(item, dict):
                raise InputError(f"{path}: {where} is {_kind(item)}, not an object")
            _check_fields(path, doc, item, fields, where + ".")
            if name == "meshes":
                for k, primitive in enumerate(item.get("primitives", [])):
                    _check_fields(path, doc, primitive, _PRIMITIVE, f"{where}.primitives[{k}].")


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


def _check_3mf(path: Path, limit: int, data: bytes | None) -> None:
    """The component graph of each model part of a 3MF (a zip whose expanded size
    ``blueprint.scene.archive.check_zip`` has bounded), walked as glTF nodes are: objects made
    of components of other objects, placed by build items."""
    import zipfile
    import zlib

    with contextlib.ExitStack() as stack:
        fh = (
            io.BytesIO(data)
            if data is not None
            else stack.enter_context(open_file(path, limit, "a model file"))
        )
        try:
            archive = stack.enter_context(zipfile.ZipFile(fh))
            parts = [i for i in archive.infolist() if i.filename.lower().endswith(".model")]
            documents = [archive.read(i) for i in parts]
        except (zipfile.BadZipFile, zlib.error, OSError, ValueError, EOFError, NotImplementedError):
            return  # the loader says what is wrong
    for document in documents:
        _check_3mf_document(path, document)


def _check_3mf_document(path: Path, document: bytes) -> None:
    import xml.etree.ElementTree as ElementTree

    objects: dict[str, tuple[int, list[str]]] = {}  # id: triangles, component object ids
    items: list[str] = []
    current = None
    try:
        for event, element in ElementTree.iterparse(io.BytesIO(document), events=("start", "end")):
            tag = element.tag.rsplit("}", 1)[-1]
            if event == "start":
                if tag == "object":
                    current = element.get("id", "")
                    objects[current] = (0, [])
                elif tag == "component" and current is not None and not _elsewhere(element):
                    objects[current][1].append(element.get("objectid", ""))
                elif tag == "triangle" and current is not None:
                    count, components = objects[current]
                    objects[current] = (count + 1, components)
                elif tag == "item":
                    items.append(element.get("objectid", ""))
            else:
                if tag == "object":
                    current = None
                element.clear()
    except ElementTree.ParseError:
        return  # the loader says what is wrong

    def children(index: str) -> list[str]:
        found = objects[index][1]
        for child in found:
            if child not in objects:
                raise InputError(f"{path}: object {index} has a component {child!r}, which does not exist")
        return found

    roots = [item for item in items if item in objects]
    _walk(path, roots, children, lambda index: (int(objects[index][0] > 0), objects[index][0]), "objects")


def _elsewhere(component) -> bool:
    """Whether a 3MF component names an object of another model part (``p:path``)."""
    return any(key.rsplit("}", 1)[-1] == "path" for key in component.keys())


def _gltf_json(path: Path, ext: str, size: int, limit: int, data: bytes | None):
    with contextlib.ExitStack() as stack:
        fh = (
            io.BytesIO(data)
            if data is not None
            else stack.enter_context(open_file(path, limit, "a model file"))
        )
        if ext == "gltf":
            raw = fh.read(limit + 1)
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
    """Triangles of each of the document's meshes, as their accessors declare them."""
    accessors = doc.get("accessors") if isinstance(doc.get("accessors"), list) else []
    out = []
    for mesh in doc.get("meshes") or []:
        total = 0
        for primitive in (mesh.get("primitives") or []) if isinstance(mesh, dict) else []:
            if not isinstance(primitive, dict):
                continue
            index = primitive.get("indices")
            if index is None:
                attributes = primitive.get("attributes")
                index = attributes.get("POSITION") if isinstance(attributes, dict) else None
            accessor = accessors[index] if isinstance(index, int) and 0 <= index < len(accessors) else None
            count = accessor.get("count") if isinstance(accessor, dict) else None
            if isinstance(count, int) and count > 0:
                total += count // 3
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


def _walk(path: Path, roots: list, children, own, what: str) -> None:
    """Walk a graph from ``roots`` once, without recursion: ``children(node)`` lists a node's
    children (checked), ``own(node)`` the mesh instances (0 or 1) and triangles a node holds
    itself; ``what`` names the nodes in messages ("nodes", "objects"). Refuses a cycle, more
    than ``NODE_DEPTH_LIMIT`` levels, and more instances or triangles than the limits, counted
    over every path (a node placed twice counts twice)."""
    from blueprint import settings

    instances: dict = {}  # per node: mesh instances below it, itself included
    triangles: dict = {}
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
                count, held = own(node)
                instances[node] = count + sum(instances[c] for c in kids)
                triangles[node] = held + sum(triangles[c] for c in kids)
                _limit(path, instances[node], settings.INSTANCE_LIMIT, "mesh instances")
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
    _limit(path, placed, settings.INSTANCE_LIMIT, "mesh instances")
    check_triangle_count(path, sum(triangles[r] for r in roots), placed)


def check_triangle_count(name, count: int, instances: int | None = None) -> None:
    """Raise ``InputError`` where ``count`` triangles to draw (of ``instances`` mesh instances,
    where a scene places them) are more than ``TRIANGLE_LIMIT``, the memory budget's worth,
    naming ``name``, the count and the budget: before any of them is made."""
    from blueprint import settings

    if count <= settings.TRIANGLE_LIMIT:
        return
    placed = "" if instances is None else f" ({instances} mesh instances)"
    raise InputError(
        f"{name}: {count} triangles to draw{placed}, more than the {settings.TRIANGLE_LIMIT} that the "
        f"memory budget of {human_size(settings.MEMORY_BUDGET)} holds at {settings.TRIANGLE_BYTES} bytes "
        f"a triangle ({settings.MEMORY_ENV} sets the budget)"
    )


def _limit(path: Path, count: int, limit: int, what: str) -> None:
    if count > limit:
        raise InputError(f"{path}: its scene holds more than {limit} {what} (the limit)")


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
