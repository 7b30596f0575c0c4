"""Wavefront OBJ: no up axis of its own (the shape decides), no unit.

Plain OBJ files are read with NumPy alone: the scans and meshes written as nothing
but ``v x y z`` and ``f i j k`` lines (MeshLab, many exporters). trimesh parses OBJ a line at a
time in Python, which took most of a drawing's time on a 70K-triangle scan; here every line
is classified, counted and converted in a few whole-file passes.

Anything else (normals, texture coordinates, materials, groups, polygons, negative or
out-of-range indices, line continuations, numbers NumPy does not read the same way) is left
to trimesh, which gives such files their meaning and their error messages: ``plain_obj``
answers None for them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from blueprint import settings
from blueprint.errors import InputError
from blueprint.scene.formats.base import Format, Mesh
from blueprint.scene.headers import check_triangle_count, read_all
from blueprint.settings import read_file

__all__ = ["FORMAT", "PLAIN_OBJ_LIMIT", "check", "plain_obj", "read_obj", "short_vertex"]

# Files read here at most: the passes hold up to some 50 bytes of index per byte of the file
# (a file of nothing but newlines), so larger files go to trimesh, as every OBJ did before.
PLAIN_OBJ_LIMIT = min(256 << 20, settings.MEMORY_BUDGET // 128)

# Tables of byte values, 1 where a byte is of the kind: uint8, so that ``np.take`` looks a whole
# file up (faster than indexing a bool table).
_SPACE = np.zeros(256, np.uint8)
_SPACE[[ord(" "), ord("\t"), ord("\r"), ord("\n")]] = 1
# bytes a vertex line may not hold besides its keyword: all but decimal numbers as NumPy and
# Python read them alike (no "nan", "inf", hexadecimal or digit separators)
_NOT_VERTEX = 1 - _SPACE
_NOT_VERTEX[np.frombuffer(b"0123456789+-.eE", np.uint8)] = 0
_NOT_FACE = 1 - _SPACE
_NOT_FACE[np.frombuffer(b"0123456789", np.uint8)] = 0
# the bytes ``bytes.split`` splits words at
_WHITE = _SPACE.copy()
_WHITE[[0x0B, 0x0C]] = 1
# Bytes ``short_vertex`` scans at a time: its passes hold up to some 25 bytes of index per byte
# of a block (a block of empty lines), so a file of any size costs a few blocks' worth.
_BLOCK = 1 << 22


def _counts(flags: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """How many of ``flags`` (one a byte, 0 or 1) are set in each line (lines begin at
    ``starts``, the first at 0; a last one at the end of the file holds nothing)."""
    inside = starts < len(flags)
    counts = np.zeros(len(starts), np.int64)
    counts[inside] = np.add.reduceat(flags, starts[inside], dtype=np.int32)
    return counts


def _numbers(data: bytes, starts: np.ndarray, ends: np.ndarray, keyword: bytes, dtype) -> np.ndarray | None:
    """The numbers of the lines ``starts[i]:ends[i]`` (their ``keyword`` read as a space), or
    None where one is not a number. Lines of a kind mostly come in long runs: a slice a run."""
    follows = np.r_[False, starts[1:] <= ends[:-1] + 1]
    run_start = starts[~follows]
    run_end = ends[np.r_[np.flatnonzero(~follows)[1:] - 1, len(ends) - 1]]
    text = b"\n".join(data[a:b] for a, b in zip(run_start.tolist(), run_end.tolist(), strict=True))
    try:
        return np.fromstring(text.replace(keyword, b" "), dtype=dtype, sep=" ")
    except ValueError:  # a word that is not a number
        return None


def plain_obj(data: bytes) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices and triangles of a plain OBJ file, as trimesh loads it (``process=False``):
    vertices no face uses left out, the rest in file order.

    Parameters
    ----------
    data : bytes
        The file's contents.

    Returns
    -------
    (positions, faces) or None
        (V, 3) float64 and (F, 3) int64 zero-based, or None where the file is anything but
        ``v`` lines of three numbers, ``f`` lines of three positive vertex numbers that exist,
        comments and blank lines (then trimesh reads it), or holds no face.
    """
    if not data or len(data) > PLAIN_OBJ_LIMIT:
        return None
    buf = np.frombuffer(data, np.uint8)
    newline = np.flatnonzero(buf == ord("\n"))
    starts = np.r_[0, newline + 1]
    ends = np.r_[newline, len(buf)]
    lengths = ends - starts
    first = buf[np.minimum(starts, len(buf) - 1)]
    second = buf[np.minimum(starts + 1, len(buf) - 1)]
    spaced = (lengths > 1) & ((second == ord(" ")) | (second == ord("\t")))
    vertex = spaced & (first == ord("v"))
    face = spaced & (first == ord("f"))
    blank = (lengths == 0) | ((first == ord("#")) & (lengths > 0)) | ((lengths == 1) & (first == ord("\r")))
    if not (vertex | face | blank).all() or not vertex.any() or not face.any():
        return None
    vs, ve, fs, fe = starts[vertex], ends[vertex], starts[face], ends[face]
    # the keyword is each line's only byte outside its kind's set
    if (_counts(np.take(_NOT_VERTEX, buf), starts)[vertex] != 1).any():
        return None
    if (_counts(np.take(_NOT_FACE, buf), starts)[face] != 1).any():
        return None
    # words: a byte that is not a space after one that is (or at the file's start)
    space = np.take(_SPACE, buf)
    starting = np.empty(len(buf), bool)
    starting[0] = space[0] == 0
    np.less(space[1:], space[:-1], out=starting[1:])
    words = _counts(starting, starts)
    if (words[vertex] != 4).any() or (words[face] != 4).any():
        return None
    vertices = _numbers(data, vs, ve, b"v", np.float64)
    faces = _numbers(data, fs, fe, b"f", np.int64)
    if vertices is None or faces is None:
        return None
    if len(vertices) != 3 * len(vs) or len(faces) != 3 * len(fs):
        return None
    if faces.min() < 1 or faces.max() > len(vs):
        return None
    faces = faces.reshape(-1, 3) - 1
    used = np.zeros(len(vs), bool)
    used[faces] = True
    remap = np.cumsum(used) - 1
    return vertices.reshape(-1, 3)[used], remap[faces]


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
    """The mesh of a plain OBJ file (``plain_obj``), or None for trimesh."""
    if size > PLAIN_OBJ_LIMIT:
        return None
    found = plain_obj(read_file(path, settings.MODEL_FILE_LIMIT, "a model file"))
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


FORMAT = Format("OBJ", ("obj",), up="guess", check=check, read=read_obj, common=True)
