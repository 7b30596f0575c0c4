"""Object-space silhouette extraction: the CPU baseline of triangle-ID silhouette rendering.

The method has two timed stages, kept as separate calls so a benchmark can time each:

* preprocessing, :func:`build_adjacency`: vertex welding, edge connectivity and consistent
  winding, which depend on the geometry only;
* per-frame extraction, :func:`classify_edges`: facing tests and edge classification for one
  camera, followed by drawing with :func:`draw_segments`.

:func:`silhouette_image` chains all three. The GPU method, triangle-ID silhouettes, is
:mod:`blueprint.gpu_silhouettes`: it draws with the renderer, so it lies in a layer above this
package's (numpy only) and is imported by name where it is used.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from blueprint.scene.weld import weld

from .contours import ContourSet, SmoothSurface, smooth_contours, smooth_surface, toward_eye
from .deform import Animation, Pose
from .edges import BORDER, CREASE, SILHOUETTE, EdgeSet, classify_edges, mesh_sharp_edges
from .idlist import IdLists, build_id_lists, id_lists_from_topology
from .mesh import Adjacency, build_adjacency
from .raster import draw_segments

__all__ = [
    "BORDER",
    "CREASE",
    "SILHOUETTE",
    "Adjacency",
    "Animation",
    "ContourSet",
    "EdgeSet",
    "IdLists",
    "Pose",
    "SmoothSurface",
    "build_adjacency",
    "build_id_lists",
    "classify_edges",
    "mesh_sharp_edges",
    "draw_segments",
    "id_lists_from_topology",
    "silhouette_image",
    "smooth_contours",
    "smooth_surface",
    "toward_eye",
    "weld",
]


def silhouette_image(
    positions: np.ndarray,
    faces: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    width: int,
    height: int,
    crease_angle: float = 30.0,
    kinds: Iterable[int] = (SILHOUETTE, BORDER),
    line_width: float = 1.0,
) -> np.ndarray:
    """Draw the feature edges of a triangle soup seen through one camera.

    Parameters
    ----------
    positions, faces : np.ndarray
        The soup: (V, 3) float vertex positions, (F, 3) integer vertex indices.
    view, projection : np.ndarray
        (4, 4) float OpenGL model-to-eye and eye-to-clip matrices (column vectors).
    width, height : int
        Image size in pixels.
    crease_angle : float
        Dihedral threshold in degrees for crease edges.
    kinds : iterable of int
        Edge kinds to draw, from `SILHOUETTE`, `BORDER`, `CREASE`.
    line_width : float
        Line width in pixels.

    Returns
    -------
    np.ndarray
        (height, width) float32 line coverage in [0, 1].
    """
    kinds = np.asarray(list(kinds), dtype=np.int64)
    if not np.isin(kinds, (SILHOUETTE, BORDER, CREASE)).all():
        raise ValueError(f"kinds must be among SILHOUETTE, BORDER, CREASE, got {kinds.tolist()}")
    edge_set = classify_edges(
        build_adjacency(positions, faces), view, projection, width, height, crease_angle
    )
    chosen = np.isin(edge_set.kind, kinds)
    return draw_segments(edge_set.segments2d[chosen], width, height, line_width)
