"""STL, binary and ASCII: Z-up by the convention of CAD and printing, no unit.

Both are read with NumPy alone, as trimesh reads them (three vertices a triangle, in file
order): trimesh, with the scipy and networkx it imports, takes most of a small drawing's start,
and its ASCII reader splits the file into a Python string a vertex. An ASCII file is read here
where it holds one solid whose ``vertex`` lines each hold three numbers; other ASCII files, and
binary files longer than their triangle count says, go to trimesh.
"""

from __future__ import annotations

import os
from functools import partial
from pathlib import Path

import numpy as np

from blueprint import parallel, settings
from blueprint.errors import InputError
from blueprint.scene.formats.base import Mesh
from blueprint.scene.formats.text import affordable, blanked, find_all, is_ascii, only, parse
from blueprint.scene.headers import check_triangle_count
from blueprint.scene.order import local_order
from blueprint.scene.weld import distinct_rows
from blueprint.settings import open_file, read_at_most

__all__ = ["read_stl"]

_VERTEX = b"vertex"
# the bytes the numbers of a vertex line may hold besides whitespace (no "nan", "inf", ...)
_NUMBER = b"0123456789+-.eE"
_RECORD = np.dtype([("normal", "<f4", 3), ("triangle", "<f4", (3, 3)), ("attribute", "<u2")])
# Binary records read at a time.
_RECORDS = 1 << 16


def read_stl(path: Path, size: int) -> Mesh | None:
    """The triangles of an STL file, or None for trimesh (see the module's docstring). A
    binary file shorter than its count says is refused, as is a count whose drawing the memory
    budget does not hold (``headers.check_triangle_count``)."""
    with open_file(path, settings.MODEL_FILE_LIMIT, "a model file") as fh:
        head = fh.read(84)
        count = int.from_bytes(head[80:84], "little") if len(head) == 84 else -1
        if size != 84 + _RECORD.itemsize * count:
            if count >= 0 and size < 84 + _RECORD.itemsize * count and not _ascii_stl(head):
                raise InputError(
                    f"{path}: the header declares {count} triangles, more than the file's {size} bytes "
                    f"can hold ({84 + _RECORD.itemsize * count} bytes)"
                )
            if not head.lstrip().lower().startswith(b"solid"):
                return None
            return _ascii(path, head + read_at_most(fh, settings.MODEL_FILE_LIMIT + 1 - len(head)))
        check_triangle_count(path, count)
        positions = np.empty((3 * count, 3), np.float32)
        parallel.run(partial(_records, fh.fileno(), positions), count, min_block=_RECORDS)
    # triangles a file scatters put together before their corners are numbered by first use
    order = local_order(positions[0::3])
    if order is not None:
        positions = parallel.taken(positions.reshape(-1, 9), order).reshape(-1, 3)
    return _corners(positions)


def _corners(positions: np.ndarray) -> Mesh:
    """The mesh of a binary file's corners ``positions`` (3F, 3) float32, three a triangle in
    order: its distinct corners, bit for bit, numbered by first corner, as a soup
    (``Model.soup``): a corner is repeated by each face around it, some six times, and the
    model holds its positions through the drawing. Where a coordinate is -0.0 (equal to 0.0,
    apart in its bits) every corner stays a vertex of its own."""
    # int32 where they fit, as the model keeps them
    dtype = np.int32 if len(positions) <= np.iinfo(np.int32).max else np.int64
    if any(parallel.run(partial(_negative_zero, positions), len(positions))):
        return Mesh(positions, np.arange(len(positions), dtype=dtype).reshape(-1, 3))
    first, inverse = distinct_rows(positions, dtype)
    return Mesh(positions[first], inverse.reshape(-1, 3), soup=True)


def _records(fd: int, positions: np.ndarray, lo: int, hi: int) -> None:
    """Records ``lo`` to ``hi`` of a binary STL file open as ``fd`` into their rows of
    ``positions`` (3 a record), a block of records at a time: the file's bytes are never all
    held beside the positions."""
    for start in range(lo, hi, _RECORDS):
        n = min(_RECORDS, hi - start)
        data = os.pread(fd, _RECORD.itemsize * n, 84 + _RECORD.itemsize * start)
        records = np.frombuffer(data, dtype=_RECORD, count=n)
        positions[3 * start : 3 * (start + n)] = records["triangle"].reshape(-1, 3)


def _ascii(path: Path, data: bytes) -> Mesh | None:
    """The triangles of an ASCII STL file of one solid as trimesh reads them: the numbers after
    each ``vertex`` (any case) up to the end of its line, three a vertex; None for any other
    file (several solids, two ``vertex`` on a line, numbers NumPy does not read the same way)."""
    if not affordable(data):
        return None
    lower = data.lower()
    begin, end = lower.find(b"solid"), lower.find(b"endsolid")
    if begin < 0 or end < begin or lower.find(b"solid", end + len(b"endsolid")) >= 0:
        return None
    buf = np.frombuffer(lower, np.uint8)
    if not is_ascii(buf) or data.count(b"\r") != data.count(b"\r\n"):
        return None
    keyword = find_all(buf, _VERTEX, begin, end)
    if len(keyword) == 0:
        return None
    newline = np.r_[np.flatnonzero(buf == ord("\n")), len(buf)]
    line_end = np.minimum(newline[np.searchsorted(newline, keyword)], end)
    if (line_end[:-1] > keyword[1:]).any():
        return None  # two on a line: trimesh reads the first to the second
    text = blanked(buf, keyword + len(_VERTEX), line_end)
    if not only(text, _NUMBER):
        return None
    values = parse(text, np.float64)
    if values is None or len(values) == 0 or len(values) % 9:
        return None
    check_triangle_count(path, len(values) // 9)
    return Mesh(values.reshape(-1, 3), np.arange(len(values) // 3, dtype=np.int64).reshape(-1, 3))


def _ascii_stl(head: bytes) -> bool:
    """Whether a file that begins with ``head`` can be ASCII STL: "solid", then text. Binary
    files may begin with "solid" too, but rarely go on in text for 84 bytes."""
    if not head.lstrip().lower().startswith(b"solid"):
        return False
    return all(32 <= b < 127 or b in (9, 10, 13) for b in head)


def _negative_zero(positions: np.ndarray, lo: int, hi: int) -> bool:
    """Whether rows ``lo`` to ``hi`` of ``positions`` hold a -0.0."""
    block = positions[lo:hi]
    return bool(np.signbit(block[block == 0]).any())
