"""Edge records for drawing object-space silhouettes on the GPU (GPU-free).

The GPU line method classifies the same edges as :func:`blueprint.silhouette.classify_edges`,
but in a vertex shader, one instance per record, from the corner positions the geometry pass
draws (so a deforming mesh uploads its positions and nothing else). A record names two faces
across one edge and where the edge's endpoints lie among the first face's corners:

``(corner0, corner1, face_a, face_b)``, int32, where a corner is ``3 * face + k`` (corner ``k`` of
that face as the model stores it) and a face is ``±(index + 1)``, negative where
:func:`build_adjacency` reversed that face's winding to orient the mesh. ``face_b`` is 0 for a
border (one face). An edge of ``m >= 3`` faces (non-manifold) gives ``m - 1`` records, its faces
chained in index order: some neighbouring pair in the chain faces opposite ways exactly when
the edge has a front and a back face, the CPU method's test for such edges.
"""

from __future__ import annotations

import numpy as np

from .mesh import Adjacency

__all__ = ["edge_records"]


def edge_records(adj: Adjacency) -> np.ndarray:
    """The GPU line method's records of a mesh's edges.

    Parameters
    ----------
    adj : Adjacency
        Output of :func:`blueprint.silhouette.build_adjacency` or
        :func:`blueprint.silhouette.mesh.connect`, whose face order is the model's.

    Returns
    -------
    np.ndarray
        (N, 4) int32 records ``(corner0, corner1, face_a, face_b)`` as described in the module.
    """
    edge, face = adj.edge_faces[:, 0], adj.edge_faces[:, 1]
    # incidences are sorted by edge then face: each one pairs with the next of its edge
    chained = np.flatnonzero(edge[1:] == edge[:-1])
    count = np.bincount(edge, minlength=len(adj.edges))
    single = np.flatnonzero(count[edge] == 1)
    first = np.concatenate([chained, single])
    second = np.concatenate([face[chained + 1], np.full(len(single), -1)])
    a, e = face[first], edge[first]

    # the model's own corner order: build_adjacency swaps corners 1 and 2 of the faces it flips
    stored = np.where(adj.flipped[:, None], adj.faces[:, [0, 2, 1]], adj.faces)
    ends = adj.edges[e]
    slot0 = np.argmax(stored[a] == ends[:, :1], axis=1)
    slot1 = np.argmax(stored[a] == ends[:, 1:], axis=1)

    def signed(f: np.ndarray) -> np.ndarray:
        return np.where(f < 0, 0, np.where(adj.flipped[np.maximum(f, 0)], -(f + 1), f + 1))

    order = np.lexsort((second, a))
    records = np.stack([3 * a + slot0, 3 * a + slot1, signed(a), signed(second)], axis=1)[order]
    return records.astype(np.int32)
