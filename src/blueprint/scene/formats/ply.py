"""PLY, ASCII and binary: no up axis of its own (scans lie any way: the shape decides), no unit.

Files of a ``vertex`` element (scalar properties, ``x``, ``y`` and ``z`` among them) and a
``face`` element (one list of vertex indices, and scalar properties) are read with NumPy alone,
as trimesh reads them: a binary file by one ``np.frombuffer`` an element, every list as long as
the first one (trimesh reads no other length from a binary file); an ASCII file by one
``np.fromstring`` an element, values cast to their declared types; faces triangulated as
trimesh triangulates them. Anything else (texture coordinates, which trimesh splits vertices
by; edges; other elements; declared sizes the data does not match) is left to trimesh.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

from blueprint import parallel, settings
from blueprint.errors import InputError
from blueprint.scene.formats.base import Mesh
from blueprint.scene.formats.polygons import triangulated
from blueprint.scene.formats.text import affordable, gathered, is_ascii, line_words, lines, only, parse
from blueprint.scene.headers import ASCII_VALUE, check_triangle_count, read_head, refuse_count
from blueprint.settings import read_file

__all__ = ["check", "ply_arrays", "read_ply"]

# NumPy's types of PLY's, as trimesh maps them (the specification's names and others in use)
_TYPES = {
    **dict.fromkeys(("char", "int8"), "i1"),
    **dict.fromkeys(("uchar", "uint8"), "u1"),
    **dict.fromkeys(("short", "int16"), "i2"),
    **dict.fromkeys(("ushort", "uint16"), "u2"),
    **dict.fromkeys(("int", "int32"), "i4"),
    **dict.fromkeys(("uint", "uint32"), "u4"),
    "int64": "i8",
    "uint64": "u8",
    "float16": "f2",
    **dict.fromkeys(("float", "float32"), "f4"),
    **dict.fromkeys(("double", "float64"), "f8"),
}
# vertex properties trimesh reads texture coordinates from, splitting vertices by them
_TEXTURE = {"texture_u", "texture_v", "u", "v", "s", "t"}
_INDEX_NAMES = ("vertex_index", "vertex_indices")
_NUMBER = b"0123456789+-.eE"

# the bytes of a binary value, by its PLY type
_SIZES = {
    **dict.fromkeys(("char", "uchar", "int8", "uint8"), 1),
    **dict.fromkeys(("short", "ushort", "int16", "uint16"), 2),
    **dict.fromkeys(("int", "uint", "float", "int32", "uint32", "float32"), 4),
    **dict.fromkeys(("double", "float64"), 8),
}


def check(path: Path, size: int, data: bytes | None = None) -> None:
    """Refuse a header whose element counts are not whole, are negative, or need more bytes
    than the file's ``size`` holds (each value at least its type's size, or two characters), and
    faces whose drawing would pass the memory budget (each is a triangle at least)."""
    text = read_head(path, data).decode("latin-1")
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
                each += _SIZES.get(kind, 1)
            else:
                each += ASCII_VALUE
            elements[-1] = (name, count, each)
    body = size - end
    need = 0
    for name, count, each in elements:
        need += count * max(each, 1)
        if need > body:
            raise refuse_count(path, count, f"{name} elements", size)
        if name == "face":
            check_triangle_count(path, count)


@dataclass
class _Element:
    name: str
    count: int
    # (name, NumPy type) of each property; a list's type is (count type, item type)
    properties: list[tuple[str, str | tuple[str, str]]] = field(default_factory=list)

    def lists(self) -> list[int]:
        return [i for i, (_, kind) in enumerate(self.properties) if isinstance(kind, tuple)]


def _header(data: bytes) -> tuple[str, list[_Element], int] | None:
    """The format ("ascii", "<" or ">" for binary), the elements and where the body begins, of a
    header this reader reads (see the module's docstring), else None."""
    end = data.find(b"end_header", 0, 1 << 16)
    newline = data.find(b"\n", end)
    if end < 0 or newline < 0:
        return None
    try:
        text = data[:end].decode("ascii")
    except UnicodeDecodeError:
        return None
    rows = [line.split() for line in text.split("\n")]
    if rows[0] != ["ply"] or len(rows) < 2 or data[end:newline].strip() != b"end_header":
        return None
    kinds = {("format", "ascii", "1.0"): "ascii"}
    kinds[("format", "binary_little_endian", "1.0")] = "<"
    kinds[("format", "binary_big_endian", "1.0")] = ">"
    encoding = kinds.get(tuple(rows[1]))
    if encoding is None:
        return None
    elements: list[_Element] = []
    for words in rows[2:]:
        if not words or words[0] == "obj_info":
            continue
        if words[0] == "comment":
            if "texturefile" in " ".join(words).lower():
                return None  # trimesh reads the texture, through the checked resolver
            continue
        if words[0] == "element" and len(words) == 3 and words[2].isdigit():
            elements.append(_Element(words[1], int(words[2])))
        elif words[0] == "property" and elements and len(words) == 3 and words[1] in _TYPES:
            elements[-1].properties.append((words[2], _TYPES[words[1]]))
        elif words[0] == "property" and elements and len(words) == 5 and words[1] == "list":
            if words[2] not in _TYPES or words[3] not in _TYPES:
                return None
            elements[-1].properties.append((words[4], (_TYPES[words[2]], _TYPES[words[3]])))
        else:
            return None
    if not _readable(elements):
        return None
    return encoding, elements, newline + 1


def _readable(elements: list[_Element]) -> bool:
    """Whether the elements are a vertex and a face element as the module's docstring says."""
    named = {e.name: e for e in elements}
    if sorted(named) != ["face", "vertex"] or len(elements) != 2:
        return False
    vertex, face = named["vertex"], named["face"]
    names = {name for name, _ in vertex.properties}
    if vertex.lists() or not {"x", "y", "z"} <= names or names & _TEXTURE or vertex.count == 0:
        return False
    if len(face.lists()) != 1 or face.count == 0 or "texcoord" in {n for n, _ in face.properties}:
        return False
    index = face.properties[face.lists()[0]][0]
    return len(face.properties) == 1 or index in _INDEX_NAMES


def ply_arrays(data: bytes) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices and triangles of a PLY file as trimesh loads it (``process=False``).

    Parameters
    ----------
    data : bytes
        The file's contents.

    Returns
    -------
    (positions, faces) or None
        (V, 3) float32 where the file's coordinates are, else float64, and (F, 3) integers of
        the file's index type (int64 where it is wider than 32 bits or not an integer), the
        values trimesh reads; or None where the file is anything the module's docstring
        leaves to trimesh.
    """
    header = _header(data)
    if header is None:
        return None
    encoding, elements, body = header
    # a binary body's rows are read in place: its lines hold no index
    if not affordable(data, lines=encoding == "ascii"):
        return None
    tables = _ascii(data, elements, body) if encoding == "ascii" else _binary(data, elements, body, encoding)
    if tables is None:
        return None
    vertex, (corners, counts) = tables
    # float32 coordinates stay float32, as the model keeps them: their float64 copies are the
    # same values
    single = all(vertex[axis].dtype.kind == "f" and vertex[axis].dtype.itemsize == 4 for axis in "xyz")
    positions = np.empty((len(vertex["x"]), 3), np.float32 if single else np.float64)
    for k, axis in enumerate("xyz"):
        positions[:, k] = vertex[axis]
    return positions, triangulated(corners, counts)


def _binary(data: bytes, elements: list[_Element], body: int, endian: str):
    """The vertex table and the face corners of a binary body, read as trimesh reads it: the
    length of every list that of the element's first."""
    at = body
    tables = {}
    for element in elements:
        fields = []
        for name, kind in element.properties:
            if isinstance(kind, tuple):
                # the list's length, read where the first row holds it
                before = sum(np.dtype(k).itemsize for _, k in fields)
                if at + before + np.dtype(kind[0]).itemsize > len(data):
                    return None
                length = int(np.frombuffer(data, endian + kind[0], 1, at + before)[0])
                kind = np.dtype([("f0", endian + kind[0]), ("f1", endian + kind[1], (length,))])
            else:
                kind = endian + kind
            fields.append((name, kind))
        try:
            dtype = np.dtype(fields)
        except (TypeError, ValueError):  # names NumPy does not take (twice, or empty)
            return None
        if at + element.count * dtype.itemsize > len(data):
            return None
        tables[element.name] = np.frombuffer(data, dtype, element.count, at)
        at += element.count * dtype.itemsize
    if at != len(data):
        return None  # trimesh fails: "PLY is unexpected length"
    face = _by_name(elements)["face"]
    corners = tables["face"][face.properties[face.lists()[0]][0]]["f1"]
    if corners.shape[1] < 3:
        return None
    flat = np.empty(corners.shape, _index_type(corners.dtype))
    parallel.run(partial(_copied, corners, flat), len(corners))
    return tables["vertex"], (flat.reshape(-1), np.full(len(corners), corners.shape[1]))


def _index_type(kind: np.dtype) -> np.dtype:
    """The type a face's indices are kept in: their own (native order) where they are integers
    of 32 bits or fewer, else int64, into which they are cast as trimesh casts them."""
    if kind.kind in "iu" and kind.itemsize <= 4:
        return kind.newbyteorder("=")
    return np.dtype(np.int64)


def _copied(rows: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi] = rows[lo:hi]``: the faces' corners out of their records, a block of rows a
    thread."""
    out[lo:hi] = rows[lo:hi]


def _by_name(elements: list[_Element]) -> dict[str, _Element]:
    return {e.name: e for e in elements}


def _ascii(data: bytes, elements: list[_Element], body: int):
    """The vertex table and the face corners of an ASCII body, read as trimesh reads it: a
    line a row, values cast to their declared types; lists as long as the first row's where
    the rows are all as long, each its own length where not."""
    buf = np.frombuffer(data, np.uint8, offset=body)
    if not is_ascii(buf) or data.count(b"\r", body) != data.count(b"\r\n", body):
        return None
    if any(data.count(c, body) for c in (b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e")):
        return None  # trimesh splits lines at them too
    starts, ends = lines(buf)
    words = line_words(buf, starts)
    row = 0
    tables = {}
    for element in elements:
        if row + element.count > len(starts):
            return None
        chosen = slice(row, row + element.count)
        text = gathered(data[body:], starts[chosen], ends[chosen])
        if not only(text, _NUMBER):
            return None
        values = parse(text, np.float64, int(words[chosen].sum()))
        if values is None:
            return None
        tables[element.name] = (values, words[chosen])
        row += element.count
    vertex, face = _by_name(elements)["vertex"], _by_name(elements)["face"]
    values, width = tables["vertex"]
    if (width != len(vertex.properties)).any():
        return None
    table = values.reshape(len(width), -1)
    columns = {name: table[:, i].astype(kind) for i, (name, kind) in enumerate(vertex.properties)}
    corners = _ascii_corners(face, *tables["face"])
    return None if corners is None else (columns, corners)


def _ascii_corners(face: _Element, values: np.ndarray, width: np.ndarray):
    """The corners (flat, cast to the list's item type, then int64) and corner counts of an
    ASCII face element (``values``, ``width`` numbers a row)."""
    at = face.lists()[0]
    item = face.properties[at][1][1]
    offset = np.cumsum(width) - width
    if (width == width[0]).all():
        # trimesh's rows of one length: every list as long as the first row's
        table = values.reshape(len(width), -1)
        length = int(table[0, at])
        if (
            length < 3
            or at + 1 + length > table.shape[1]
            or len(face.properties) - 1 > table.shape[1] - 1 - length
        ):
            return None
        corners = table[:, at + 1 : at + 1 + length].astype(item).astype(np.int64)
        return corners.reshape(-1), np.full(len(width), length)
    # trimesh's rows of several lengths: each list as long as its own count says
    if len(face.properties) != 1:
        return None
    counts = values[offset]
    if (counts != width - 1).any():
        return None
    keep = np.ones(len(values), bool)
    keep[offset] = False
    return values[keep].astype(item).astype(np.int64), (width - 1).astype(np.int64)


def read_ply(path: Path, size: int) -> Mesh | None:
    """The mesh of a PLY file (``ply_arrays``), its header checked first, or None for trimesh."""
    check(path, size)
    found = ply_arrays(read_file(path, settings.MODEL_FILE_LIMIT, "a model file"))
    if found is None:
        return None
    check_triangle_count(path, len(found[1]))
    return Mesh(*found)
