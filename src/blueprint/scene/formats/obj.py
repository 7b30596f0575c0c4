"""Wavefront OBJ: no up axis of its own (the shape decides), no unit.

OBJ files are read with NumPy alone, as trimesh reads them (``process=False``): ``v``, ``vt``,
``vn`` and ``f`` lines, faces of any corner count with vertex, texture and normal indices
(``f 1/2/3``, ``f 1//3``), negative indices, comments, objects, groups and smoothing groups.
trimesh parses OBJ a line at a time in Python; here every line is classified, counted and
converted in a few whole-file passes, and the result is trimesh's to the vertex: faces
triangulated as it triangulates them (quads of one kind in two blocks, polygons as fans),
vertices that differ in texture or normal index split by ``unmerge_faces``, rows in its order.

Anything else (materials, which can split a file into meshes; line continuations; other
keywords; rows of uneven length; numbers NumPy does not read the same way; indices out of
range) is left to trimesh, which gives such files their meaning and their error messages:
``obj_arrays`` answers None for them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from blueprint import settings
from blueprint.errors import InputError
from blueprint.scene.formats.base import Mesh
from blueprint.scene.formats.polygons import triangulated
from blueprint.scene.formats.text import affordable, gathered, line_words, lines, only, parse, word_spans
from blueprint.scene.headers import check_triangle_count, read_all
from blueprint.settings import read_file

__all__ = ["check", "obj_arrays", "read_obj", "short_vertex"]

# the bytes the numbers of a line may hold besides whitespace: decimal numbers as NumPy and
# Python read them alike (no "nan", "inf", hexadecimal or digit separators)
_NUMBER = b"0123456789+-.eE"
_INDEX = b"0123456789+-/"
# the bytes ``bytes.split`` splits words at
_WHITE = np.zeros(256, np.uint8)
_WHITE[np.frombuffer(b" \t\r\n\x0b\x0c", np.uint8)] = 1
# Bytes ``short_vertex`` scans at a time: its passes hold up to some 25 bytes of index per byte
# of a block (a block of empty lines), so a file of any size costs a few blocks' worth.
_BLOCK = 1 << 22
# the kinds of lines read, by their keywords (0: lines passed over)
_KEYWORDS = {1: b"v", 2: b"vt", 3: b"vn", 4: b"f"}
_VERTEX, _TEXTURE, _NORMAL, _FACE = 1, 2, 3, 4
# forms of a face corner, by its slashes and how many of them are doubled: whether it gives a
# texture index and a normal index
_FORMS = {(0, 0): (False, False), (1, 0): (True, False), (2, 1): (False, True), (2, 0): (True, True)}


def _kinds(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, words: np.ndarray) -> np.ndarray | None:
    """Each line's kind (``_VERTEX`` ... ``_FACE``, 0 for lines passed over: comments, blank
    lines, objects, groups and smoothing groups), or None where a line is of any other kind."""
    length = ends - starts
    last = len(buf) - 1

    def byte(offset: int) -> np.ndarray:
        return np.where(length > offset, buf[np.minimum(starts + offset, last)], 0)

    first, second, third = byte(0), byte(1), byte(2)
    spaced = (second == ord(" ")) | (second == ord("\t"))
    after_two = (third == ord(" ")) | (third == ord("\t"))
    kind = np.full(len(starts), -1, np.int8)
    kind[words == 0] = 0
    kind[first == ord("#")] = 0
    named = (first == ord("o")) | (first == ord("g")) | (first == ord("s"))
    kind[named & (spaced | (length == 1))] = 0
    kind[(first == ord("v")) & spaced] = _VERTEX
    kind[(first == ord("v")) & (second == ord("t")) & after_two] = _TEXTURE
    kind[(first == ord("v")) & (second == ord("n")) & after_two] = _NORMAL
    kind[(first == ord("f")) & spaced] = _FACE
    return None if (kind < 0).any() else kind


def obj_arrays(data: bytes) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices and triangles of an OBJ file as trimesh loads it (``process=False``).

    Parameters
    ----------
    data : bytes
        The file's contents.

    Returns
    -------
    (positions, faces) or None
        (V, 3) float64 and (F, 3) int64 zero-based, or None where the file is anything the
        module's docstring leaves to trimesh, or holds no face.
    """
    if not data or not affordable(data) or b"\\" in data:
        return None
    if data.count(b"\r") != data.count(b"\r\n"):
        return None  # trimesh splits lines at newlines only
    buf = np.frombuffer(data, np.uint8)
    starts, ends = lines(buf)
    words = line_words(buf, starts)
    kind = _kinds(buf, starts, ends, words)
    if kind is None or not (kind == _VERTEX).any() or not (kind == _FACE).any():
        return None
    rows = {}
    for k in (_VERTEX, _TEXTURE, _NORMAL):
        chosen = kind == k
        if chosen.any():
            # trimesh reads every kind of row, each kind of one length
            rows[k] = _rows(data, starts[chosen], ends[chosen], words[chosen] - 1, _KEYWORDS[k])
            if rows[k] is None:
                return None
    vertices = rows[_VERTEX]
    if vertices.shape[1] < 3:
        return None
    chosen = kind == _FACE
    corners = words[chosen] - 1
    if corners.min() == corners.max() and corners[0] < 3:
        return None  # trimesh makes no triangle of them
    found = _corners(data, starts[chosen], ends[chosen], int(corners.sum()))
    if found is None:
        return None
    v, texture, normal = found
    if v.min() < -len(vertices) or v.max() >= len(vertices):
        return None  # trimesh fails: its message
    return _mesh(vertices[:, :3], corners, v, texture, normal, _NORMAL in rows)


def _rows(data: bytes, starts, ends, counts, keyword: bytes) -> np.ndarray | None:
    """(R, C) float64: the numbers of the lines ``starts:ends`` after their ``keyword``, or None
    where they are not numbers, or not as many on every line."""
    if counts.min() != counts.max() or counts[0] == 0:
        return None
    text = gathered(data, starts, ends, keyword)
    if not only(text, _NUMBER):
        return None
    values = parse(text, np.float64, int(counts.sum()))
    return None if values is None else values.reshape(len(counts), -1)


def _corners(data: bytes, starts, ends, total: int):
    """The vertex, texture and normal indices of every face corner in file order (texture
    and normal None where the corners have none), as trimesh takes them (zero-based: one less
    where positive), or None where the corners are not all of one form."""
    text = gathered(data, starts, ends, b"f")
    if not only(text, _INDEX):
        return None
    corner = np.frombuffer(text, np.uint8)
    first, last = word_spans(corner)
    if len(first) != total:
        return None
    slash = np.flatnonzero(corner == ord("/"))
    doubled = int(np.count_nonzero(slash[1:] == slash[:-1] + 1))
    form = (len(slash) // total, doubled // total)
    if form not in _FORMS or len(slash) != form[0] * total or doubled != form[1] * total:
        return None
    if form[0]:
        # each corner has its own slashes, none at its ends, doubled where the form says
        owner = np.searchsorted(first, slash, side="right") - 1
        if not np.array_equal(owner, np.repeat(np.arange(total), form[0])):
            return None
        if (corner[first] == ord("/")).any() or (corner[last - 1] == ord("/")).any():
            return None
        if form == (2, 1) and not (slash[1::2] == slash[0::2] + 1).all():
            return None
    has_texture, has_normal = _FORMS[form]
    per = 1 + has_texture + has_normal
    values = parse(text.replace(b"/", b" "), np.int64, per * total)
    if values is None:
        return None
    values[values > 0] -= 1
    values = values.reshape(-1, per)
    return values[:, 0], values[:, 1] if has_texture else None, values[:, -1] if has_normal else None


def _mesh(vertices, corners, v, texture, normal, has_normals: bool):
    """Positions and triangles as trimesh makes them of the corners of faces of ``corners``
    corners each: vertices split by ``_unmerged`` where corners give texture or normal indices,
    faces triangulated after (``polygons.triangulated``) where they are all of one size, as
    they are read (``_fan_inline``) where not."""
    uniform = corners.min() == corners.max()
    if uniform:
        # trimesh's whole-file path: polygons of one size, triangulated after the unmerging
        k = int(corners[0])
        faces, tex, norm = (None if a is None else a.reshape(-1, k) for a in (v, texture, normal))
    else:
        # trimesh's line by line path: every face triangulated as it is read
        faces, tex, norm = (None if a is None else _fan_inline(a, corners) for a in (v, texture, normal))
    if tex is not None:
        new_faces, mask_v = _unmerged(faces, tex, norm) if norm is not None else _unmerged(faces, tex)
    elif norm is not None and has_normals:
        new_faces, mask_v = _unmerged(faces, norm)
    else:
        used = np.zeros(len(vertices), bool)
        used[faces] = True
        inverse = np.zeros(len(vertices), np.int64)
        inverse[used] = np.arange(used.sum())
        new_faces, mask_v = inverse[faces], used
    k = new_faces.shape[1]
    return vertices[mask_v], triangulated(new_faces.reshape(-1), np.full(len(new_faces), k))


def _fan_inline(values: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(T, 3): the corners of faces of ``corners`` corners each triangulated as trimesh's
    line by line reader does: a triangle as it is, a quad as (0, 1, 2) and (2, 3, 0), a
    polygon as a fan from its first corner, faces of fewer than three corners left out."""
    start = np.cumsum(corners) - corners
    tris = np.where(corners >= 3, corners - 2, 0)
    face = np.repeat(np.arange(len(corners)), tris)
    step = np.arange(len(face)) - np.repeat(np.cumsum(tris) - tris, tris)
    base = start[face]
    quad = corners[face] == 4
    a = np.where(quad & (step == 1), base + 2, base)
    b = np.where(quad & (step == 1), base + 3, base + step + 1)
    c = np.where(quad & (step == 1), base, base + step + 2)
    return values[np.stack([a, b, c], axis=1)]


def _unmerged(faces: np.ndarray, *others: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """trimesh.visual.texture.unmerge_faces: a vertex for every distinct (vertex, texture,
    normal) index of the corners, in trimesh's order, and the faces of those vertices. Made
    with the same NumPy calls on the same arrays, so that rows tied in its (unstable) sort
    come out in the same order."""
    stack = np.column_stack([faces.reshape(-1)] + [o.reshape(-1) for o in others])
    _, unique, inverse = np.unique(_hashable_rows(stack), return_index=True, return_inverse=True)
    pairs = stack[unique]
    order = pairs[:, 0].argsort()
    pairs = pairs[order]
    remap = np.zeros(len(order), dtype=np.int64)
    remap[order] = np.arange(len(order))
    return remap[inverse].reshape((-1, faces.shape[1])), pairs[:, 0]


def _hashable_rows(rows: np.ndarray) -> np.ndarray:
    """trimesh.grouping.hashable_rows of (n, 2 to 4) int64 rows: each row packed into one
    integer where its values fit, else viewed as one opaque value."""
    precision = 64 // rows.shape[1]
    threshold = (2 ** (precision - 1)) - 1
    if rows.max() < threshold and rows.min() > -threshold:
        hashable = np.zeros(len(rows), dtype=np.uint64)
        packed = (rows.T + (threshold + 1)).astype(np.uint64)
        for offset, column in enumerate(packed):
            np.bitwise_xor(hashable, column << (offset * precision), out=hashable)
        return hashable
    dtype = np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))
    return np.ascontiguousarray(rows).view(dtype).reshape(-1)


def short_vertex(data: bytes) -> tuple[int, int] | None:
    """The first vertex line of an OBJ file with fewer than three numbers, as (line number
    from 1, how many words it has after ``v``), or None. Vertex lines are found as trimesh
    finds them: ``v`` and a space at a line's start. trimesh cuts every vertex to the shortest
    such line, so that one line of two numbers makes a mesh of 2-D vertices, or where the
    numbers happen to add up, shifts the numbers of the vertices after it.

    Parameters
    ----------
    data : bytes
        The file's contents, scanned a block of whole lines at a time.
    """
    line, start = 1, 0
    while start < len(data):
        cut = data.find(b"\n", start + _BLOCK)
        end = len(data) if cut < 0 else cut + 1
        buf = np.frombuffer(data, np.uint8, end - start, start)
        newline = np.flatnonzero(buf == ord("\n"))
        starts = np.r_[0, newline + 1]
        starts = starts[starts < len(buf)]
        white = np.take(_WHITE, buf)
        starting = np.empty(len(buf), np.uint8)
        starting[0] = 1 - white[0]
        np.less(white[1:], white[:-1], out=starting[1:])
        words = np.add.reduceat(starting, starts, dtype=np.int32)
        spaced = (buf[np.minimum(starts + 1, len(buf) - 1)] == ord(" ")) & (starts + 1 < len(buf))
        short = np.flatnonzero((buf[starts] == ord("v")) & spaced & (words < 4))
        if len(short):
            return line + int(short[0]), int(words[short[0]]) - 1
        line += len(newline)
        start = end
    return None


def read_obj(path: Path, size: int) -> Mesh | None:
    """The mesh of an OBJ file (``obj_arrays``), or None for trimesh."""
    found = obj_arrays(read_file(path, settings.MODEL_FILE_LIMIT, "a model file"))
    if found is None:
        return None
    check_triangle_count(path, len(found[1]))
    return Mesh(*found)


def check(path: Path, size: int, data: bytes | None = None) -> None:
    """Refuse a vertex line of fewer than three numbers, which trimesh reads as 2-D vertices
    (or, where the counts happen to add up, as vertices shifted by a number)."""
    found = short_vertex(read_all(path, data))
    if found is not None:
        line, numbers = found
        counted = f"{numbers} number" + ("" if numbers == 1 else "s")
        raise InputError(f"{path}: line {line}: a vertex of {counted} (x, y and z are needed)")
