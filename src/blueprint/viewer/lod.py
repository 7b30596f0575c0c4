"""A coarse level of detail of a big model, drawn while the view moves: vertex clustering.

The model's vertices are snapped to a grid of cubic cells, each cell's vertices merged at their
mean; triangles whose corners fall in fewer than three cells vanish, and triangles left with the
same three cells are drawn once. A cell is sized from the model's surface area so that about
``triangles`` triangles are left (a closed surface of N vertices has about 2N triangles, and a
surface crosses about 1.5 cells per square cell of its area). Parts keep their faces' parts,
so picking and highlighting see the same parts.
"""

from __future__ import annotations

import numpy as np

from blueprint.scene.model import Model

# Triangles a coarse mesh is made to hold, about.
COARSE_TRIANGLES = 60_000
# Cells a surface crosses per square cell of its area, and triangles a merged vertex leaves.
_CELLS_PER_AREA = 1.5
_TRIANGLES_PER_CELL = 2.0


def _cluster(model: Model, cell: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions (C, 3) float32, faces (F', 3) int64, face_part (F',) int32) of the model's
    vertices merged in cubes of side ``cell``."""
    lo = model.bounds[0]
    cells = np.floor((model.positions - lo) / cell).astype(np.int64)
    span = cells.max(axis=0) + 1 if len(cells) else np.ones(3, np.int64)
    keys = (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]
    unique, cluster = np.unique(keys, return_inverse=True)
    counts = np.bincount(cluster, minlength=len(unique)).astype(np.float64)
    positions = np.stack(
        [np.bincount(cluster, model.positions[:, axis], len(unique)) / counts for axis in range(3)], axis=1
    ).astype(np.float32)
    faces = cluster[model.faces]
    kept = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
    faces, parts = faces[kept], model.face_part[kept]
    # a triangle once, whichever way round its corners go
    ordered = np.sort(faces, axis=1)
    n = np.int64(len(unique))
    _, first = np.unique((ordered[:, 0] * n + ordered[:, 1]) * n + ordered[:, 2], return_index=True)
    first.sort()
    return positions, faces[first], parts[first]


def coarse_model(model: Model, triangles: int = COARSE_TRIANGLES) -> Model:
    """``model`` with about ``triangles`` triangles (at most twice as many), its vertices
    clustered; the model itself where it holds no more than that.

    Parameters
    ----------
    model : Model
    triangles : int
        The triangles to keep, about.

    Returns
    -------
    Model
        Same parts, up axis, unit and source; positions (C, 3) float32 the clusters' means,
        faces (F', 3) int32.
    """
    if model.triangle_count <= triangles:
        return model
    area = 0.5 * float(np.linalg.norm(model.corner_cross(), axis=1).sum())
    cell = np.sqrt(area * _CELLS_PER_AREA * _TRIANGLES_PER_CELL / triangles)
    if not np.isfinite(cell) or cell <= 0:
        return model
    positions, faces, parts = _cluster(model, cell)
    if len(faces) > 2 * triangles:
        # a surface folded more than a plane's (noise, thin shells): cells in proportion
        positions, faces, parts = _cluster(model, cell * np.sqrt(len(faces) / triangles))
    return Model.from_arrays(
        positions, faces, parts, model.part_names, up=model.up, source=model.source, unit=model.unit
    )
