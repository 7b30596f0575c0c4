"""Faces in an order that keeps neighbours together, for mesh files that scatter them.

A GPU's vertex stage reuses a vertex shaded for the faces just before, and a software
rasteriser's works through a draw a piece at a time: a file whose consecutive faces lie all
over the model (a subdivided sphere written level by level, a mesh whose faces were shuffled)
shades each corner anew and touches the whole vertex array in every piece. Such a file's faces
are ordered by the cell of a grid over the model that their first corner lies in (a Morton
order of the cells, each cell's faces in the file's order). An STL's triangles are put in
that order as they are read, before their corners are numbered (``formats.stl``); other
files' vertices keep their numbers.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from blueprint import parallel
from blueprint.columns import column_max, column_min
from blueprint.sorting import stable_argsort

__all__ = ["MIN_FACES", "local_order", "reordered_faces"]

# Meshes of fewer faces keep the file's order: a software rasteriser draws them in one piece.
MIN_FACES = 1 << 16
# Bits of a cell's coordinate on each axis (a grid of 1024^3 cells), and the highest coordinate.
_BITS = 10
_CELLS = (1 << _BITS) - 1
# Windows of consecutive faces measured, spread evenly through the file, and the faces of each;
# and the median spread of a window's first corners (root mean square about their mean), in
# that of as many faces side by side (their count's square root times the faces' spacing), past
# which the file's faces count as scattered: a Morton order's windows measure 0.3-0.4, the
# shared scans' 0.4-1.6, a shuffled mesh's 1.5 and more, growing with its faces.
_WINDOWS = 64
_WINDOW = 1024
_SCATTERED = 1.0


def _spread(value: np.ndarray) -> np.ndarray:
    """The bits of ``value`` (< 1024) two apart, for interleaving three coordinates."""
    value = (value | (value << 16)) & 0x030000FF
    value = (value | (value << 8)) & 0x0300F00F
    value = (value | (value << 4)) & 0x030C30C3
    return (value | (value << 2)) & 0x09249249


# every cell coordinate's bits spread, looked up a key at a time
_SPREAD = _spread(np.arange(_CELLS + 1, dtype=np.uint32))


def local_order(points: np.ndarray, first: np.ndarray | None = None) -> np.ndarray | None:
    """The order to put a mesh's faces in where its file scatters them: the faces' first
    corners are the rows ``first`` (F,) of ``points`` (N, 3), or with ``first`` None the rows
    themselves. None for fewer than ``MIN_FACES`` faces, where windows of consecutive faces lie
    together already (``_SCATTERED``), and for points that are not finite, which the loader's
    checks refuse after (as it does corners out of range: read clipped here)."""
    count = len(points) if first is None else len(first)
    if count < max(MIN_FACES, _WINDOW):
        return None
    low = column_min(points).astype(np.float64)
    high = column_max(points).astype(np.float64)
    extent = high - low
    # the spacing of the faces were they spread evenly over the bounds' surface
    area = 2.0 * (extent[0] * extent[1] + extent[1] * extent[2] + extent[2] * extent[0])
    spacing = np.sqrt(area / count)
    if not 0.0 < spacing < np.inf:
        return None
    rows = np.linspace(0, count - _WINDOW, _WINDOWS).astype(np.int64)[:, None] + np.arange(_WINDOW)
    at = rows if first is None else np.take(first, rows, mode="clip")
    window = np.take(points, at, axis=0, mode="clip").astype(np.float64)
    spread = np.sqrt(((window - window.mean(axis=1, keepdims=True)) ** 2).sum(axis=2).mean(axis=1))
    if np.median(spread) <= _SCATTERED * np.sqrt(_WINDOW) * spacing:
        return None
    scale = _CELLS / max(float(extent.max()), np.finfo(np.float32).tiny)
    key = np.empty(count, np.uint32)
    parallel.run(partial(_cell_keys, points, first, low, scale, key), count)
    return stable_argsort(key)


def _cell_keys(points, first, low: np.ndarray, scale: float, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]``: the Morton keys of the grid cells of faces ``lo:hi``'s first corners (as
    ``local_order`` reads them), the grid's ``low`` corner and cells a unit ``scale``."""
    corner = points[lo:hi] if first is None else np.take(points, first[lo:hi], axis=0, mode="clip")
    key = out[lo:hi]
    key[:] = 0
    for axis in range(3):
        # in the points' own type: float32 for every format that reads into it
        offset = (corner[:, axis] - corner.dtype.type(low[axis])) * corner.dtype.type(scale)
        cell = offset.astype(np.uint32)
        key |= np.take(_SPREAD, np.minimum(cell, _CELLS, out=cell)) << axis


def reordered_faces(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``faces`` (F, 3) of ``positions`` in ``local_order``; the array itself where the file's
    order stands. The vertices keep their numbers."""
    order = local_order(positions, faces[:, 0])
    return faces if order is None else parallel.taken(faces, order)
