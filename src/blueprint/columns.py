"""Reductions and products of (N, k) arrays, for small k, column by column: the smallest and
largest value of each column, the length of each row, cross products of rows.

NumPy reduces ``a.min(axis=0)`` of an (N, 3) array one row at a time, far slower than one
reduction a column, ``np.linalg.norm(a, axis=1)`` is slower than the sum of squares it stands
for, and ``np.cross`` of (N, 3) rows slower than the same products a column; the values are
the same.
"""

from __future__ import annotations

import numpy as np

from blueprint import parallel
from blueprint.sorting import grouped

__all__ = [
    "column_cross",
    "column_max",
    "column_min",
    "column_ptp",
    "cross",
    "face_cross",
    "indexed_cross",
    "ranges",
    "row_norm",
    "square_blocks",
    "used_bounds",
]

# Faces whose cross products ``indexed_cross`` makes at a time.
_BLOCK = 1 << 15


def column_min(values: np.ndarray) -> np.ndarray:
    """``values.min(axis=0)`` of a 2-D array."""
    return np.array([values[:, k].min() for k in range(values.shape[1])], dtype=values.dtype)


def column_max(values: np.ndarray) -> np.ndarray:
    """``values.max(axis=0)`` of a 2-D array."""
    return np.array([values[:, k].max() for k in range(values.shape[1])], dtype=values.dtype)


def used_bounds(positions: np.ndarray, faces: np.ndarray) -> np.ndarray | None:
    """(2, 3) float64: the lowest and highest corner of the ``positions`` (V, 3) that ``faces``
    use, each once (all of them where there are no faces); None where that is none."""
    used = positions
    if len(faces):
        # each used vertex marked once, not read once a corner (some six times in a closed mesh)
        mask = np.zeros(len(positions), bool)
        parallel.mark(mask, np.asarray(faces).reshape(-1))
        if not mask.all():
            used = positions[mask]
    if len(used) == 0:
        return None
    return np.array([column_min(used), column_max(used)], dtype=np.float64)


def column_ptp(values: np.ndarray) -> np.ndarray:
    """``np.ptp(values, axis=0)`` of a 2-D array."""
    return column_max(values) - column_min(values)


def row_norm(values: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(values, axis=1)`` of a real 2-D array."""
    total = values[:, 0] * values[:, 0]
    for k in range(1, values.shape[1]):
        total = total + values[:, k] * values[:, k]
    return np.sqrt(total)


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of two (N, 3) arrays."""
    return _cross((a[:, 0], a[:, 1], a[:, 2]), (b[:, 0], b[:, 1], b[:, 2]), np.result_type(a, b))


def column_cross(a, b) -> np.ndarray:
    """(N, 3) float64: ``cross`` of two (N, 3) arrays given as their three columns each."""
    return _cross(a, b, np.dtype(np.float64))


def face_cross(tri: np.ndarray) -> np.ndarray:
    """``np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])`` of triangles (N, 3, 3): twice
    their areas along their normals."""
    u = [tri[:, 1, k] - tri[:, 0, k] for k in range(3)]
    v = [tri[:, 2, k] - tri[:, 0, k] for k in range(3)]
    return _cross(u, v, tri.dtype)


def indexed_cross(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``face_cross(positions[faces].astype(np.float64))`` of (V, 3) positions and (F, 3)
    faces, a block of faces and a coordinate at a time: without the (F, 3, 3) float64 corners,
    and each block's differences still in the cache when their products read them; the blocks
    side by side (``blueprint.parallel``)."""
    out = np.empty((len(faces), 3), np.float64)
    columns = [positions[:, k] for k in range(3)]

    def crossed(lo: int, hi: int) -> None:
        for start in range(lo, hi, _BLOCK):
            block = faces[start : min(start + _BLOCK, hi)]
            u, v = [], []
            for column in columns:
                first = column[block[:, 0]].astype(np.float64)
                u.append(column[block[:, 1]].astype(np.float64) - first)
                v.append(column[block[:, 2]].astype(np.float64) - first)
            _cross(u, v, out=out[start : start + len(block)])

    parallel.run(crossed, len(faces))
    return out


def _cross(a, b, dtype=None, out=None) -> np.ndarray:
    out = np.empty((len(a[0]), 3), dtype) if out is None else out
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        np.subtract(a[i] * b[j], a[j] * b[i], out=out[:, k])
    return out


def square_blocks(sizes: np.ndarray, cells: int, most: int | None = None) -> list[tuple[int, np.ndarray]]:
    """The groups of ``sizes`` (N,) int (of sizes up to ``most`` where given), those of one size
    d together in blocks of about ``cells`` d x d cells: (d, the groups' indices) a block, for
    work that compares a group's members pairwise as one table."""
    kept = np.arange(len(sizes)) if most is None else np.flatnonzero(sizes <= most)
    work = []
    for d, which in grouped(sizes[kept]):
        chosen = kept[which]
        step = max(1, cells // (d * d))
        work += [(d, chosen[at : at + step]) for at in range(0, len(chosen), step)]
    return work


def runs(counts: np.ndarray, most: int) -> list[tuple[int, int]]:
    """Consecutive items of ``counts`` (N,) int (rows each, at least one) in runs of about
    ``most`` rows: (first, past the last) a run, in order; a run holds at least one item, and
    what it holds before its last item comes to less than ``most``."""
    first = np.cumsum(counts) - counts
    out, k = [], 0
    while k < len(counts):
        end = max(k + 1, int(np.searchsorted(first, first[k] + most)))
        out.append((k, end))
        k = end
    return out


def ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """The indices ``starts[k]`` to ``starts[k] + counts[k]`` of every ``k``, in order."""
    total = int(counts.sum())
    offsets = np.repeat(starts - (np.cumsum(counts) - counts), counts)
    return offsets + np.arange(total)
