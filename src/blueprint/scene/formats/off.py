"""OFF: no up axis of its own (the shape decides), no unit.

Files of an ``OFF`` or ``COFF`` header, a line of counts, vertex lines (the first three numbers
of each are the vertex) and face lines (a corner count, whole vertex indices, anything after)
are read with NumPy alone, as trimesh reads them: comments cut, faces triangulated as trimesh
triangulates them. Anything else is left to trimesh and the checks of ``check``, among them a
comment after the first line that is not at a line's start: trimesh's comment stripping repeats
the lines before it, so that the file reads differently there.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from blueprint import settings
from blueprint.errors import InputError
from blueprint.scene.formats.base import Mesh
from blueprint.scene.formats.polygons import triangulated
from blueprint.scene.formats.text import affordable, blanked, is_ascii, line_words, lines, only, parse
from blueprint.scene.headers import ASCII_VALUE, check_triangle_count, read_all, read_head, refuse_count
from blueprint.settings import read_file

__all__ = ["check", "off_arrays", "read_off"]

_NUMBER = b"0123456789+-.eE"
_INDEX = b"0123456789+-"


def check(path: Path, size: int, data: bytes | None = None) -> None:
    """Refuse negative counts, counts the file's ``size`` cannot hold, faces whose drawing would
    pass the memory budget, and a face whose corner count is more than the values its line holds."""
    if _check_counts(path, read_head(path, data).decode("latin-1"), size):
        _check_faces(path, read_all(path, data))


def _check_counts(path: Path, text: str, size: int) -> bool:
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
    if vertices * 3 * ASCII_VALUE > size:
        raise refuse_count(path, vertices, "vertices", size)
    if vertices * 3 * ASCII_VALUE + faces * 4 * ASCII_VALUE > size:
        raise refuse_count(path, faces, "faces", size)
    check_triangle_count(path, faces)  # each face a triangle at least: refused before the body is read
    return True


def _check_faces(path: Path, data: bytes) -> None:
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


def off_arrays(data: bytes) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices and triangles of an OFF file as trimesh loads it (``process=False``).

    Parameters
    ----------
    data : bytes
        The file's contents.

    Returns
    -------
    (positions, faces) or None
        (V, 3) float64 and (F, 3) int64, or None where the file is anything the module's
        docstring leaves to trimesh.
    """
    if not affordable(data):
        return None
    buf = np.frombuffer(data, np.uint8)
    if not is_ascii(buf) or data.count(b"\r") != data.count(b"\r\n"):
        return None
    if any(c in data for c in (b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e")):
        return None  # trimesh splits lines at them too
    comment, first_newline = data.find(b"#"), data.find(b"\n")
    if 0 <= first_newline < comment and comment != first_newline + 1:
        return None  # trimesh repeats the lines before it (see the module's docstring)
    starts, ends = lines(buf)
    if comment >= 0:
        # a line ends at its first comment
        hashes = np.flatnonzero(buf == ord("#"))
        commented, first = np.unique(np.searchsorted(starts, hashes, side="right") - 1, return_index=True)
        ends[commented] = hashes[first]
        buf = np.frombuffer(blanked(buf, starts, ends), np.uint8)
    words = line_words(buf, starts)
    filled = np.flatnonzero(words > 0)
    if not len(filled):
        return None
    head = filled[0]
    line = bytes(buf[starts[head] : ends[head]])
    keyword = line.split()[0]
    if keyword not in (b"OFF", b"COFF"):
        return None
    # the counts: the rest of the keyword's line, or the next line that holds anything
    if words[head] > 1:
        counts_text, after = line[line.index(keyword) + len(keyword) :], 1
    elif len(filled) > 1:
        counts_text, after = bytes(buf[starts[filled[1]] : ends[filled[1]]]), 2
    else:
        return None
    if not only(counts_text, b"0123456789"):
        return None
    counts = counts_text.split()
    if len(counts) < 2:
        return None
    vertex_count, face_count = int(counts[0]), int(counts[1])
    data_line = filled[after:]
    if vertex_count == 0 or face_count == 0 or len(data_line) < vertex_count + face_count:
        return None
    vertices = _vertices(
        buf, starts[data_line[:vertex_count]], ends[data_line[:vertex_count]], words[data_line[:vertex_count]]
    )
    if vertices is None:
        return None
    chosen = data_line[vertex_count : vertex_count + face_count]
    faces = _faces(buf, starts[chosen], ends[chosen], words[chosen], vertex_count)
    if faces is None:
        return None
    return vertices, faces


def _vertices(buf, starts, ends, words) -> np.ndarray | None:
    """(V, 3) float64: the first three numbers of each vertex line (all must be numbers)."""
    if words.min() < 3:
        return None
    text = blanked(buf, starts, ends)
    if not only(text, _NUMBER):
        return None
    values = parse(text, np.float64, int(words.sum()))
    if values is None:
        return None
    first = np.cumsum(words) - words
    return values[first[:, None] + np.arange(3)]


def _faces(buf, starts, ends, words, vertex_count: int) -> np.ndarray | None:
    """(T, 3) int64: the faces' corners triangulated; None where a face line is not whole
    numbers, its corner count is 0 or more than its line lists, or a corner does not exist."""
    text = blanked(buf, starts, ends)
    if not only(text, _INDEX):
        return None
    values = parse(text, np.int64, int(words.sum()))
    if values is None:
        return None
    first = np.cumsum(words) - words
    counts = values[first]
    if counts.min() < 1 or (counts > words - 1).any():
        return None
    # the corners: the ``counts[i]`` values after each count
    owner = np.repeat(np.arange(len(counts)), counts)
    step = np.arange(len(owner)) - np.repeat(np.cumsum(counts) - counts, counts)
    corners = values[first[owner] + 1 + step]
    if len(corners) and (corners.min() < 0 or corners.max() >= vertex_count):
        return None  # trimesh fails: its message
    return triangulated(corners, counts)


def read_off(path: Path, size: int) -> Mesh | None:
    """The mesh of an OFF file (``off_arrays``), or None for trimesh."""
    found = off_arrays(read_file(path, settings.MODEL_FILE_LIMIT, "a model file"))
    if found is None:
        return None
    check_triangle_count(path, len(found[1]))
    return Mesh(*found)
