"""A glyph file's dimensions anchored to the model's edges: ``edge = N`` measures edge ``N``
between its two ends, ``edges = [N, M]`` the distance between two edges (``edge_distance``),
by the stable numbers of ``edge_numbers``. The anchor points are found in model space once, so
every view projects the same edge ends and prints the same value."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from blueprint.compose.glyphs.parse import Glyphs
from blueprint.errors import InputError
from blueprint.scene.model import Model

from .lines import edge_numbers, edge_segments

__all__ = ["PARALLEL", "anchor_glyphs", "edge_distance"]

#: Two edges are parallel where the sine of the angle between them is below this: the sides of a
#: tessellated face stay parallel through float32 vertex rounding far from the origin.
PARALLEL = 1e-5


def edge_distance(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two points, one on each edge's line, that a dimension between edges ``a`` and ``b``
    ((2, 3) float64 ends each) measures between.

    Parallel edges: the perpendicular distance between their lines, taken at the middle of the
    stretch of ``a`` that ``b`` lies beside (where none does, at the end of ``a`` nearest to
    ``b``), the second point the foot of the first on ``b``'s line. Other edges: their closest
    points (the shortest distance between the two segments, ends included).

    Returns
    -------
    (3,) float64, (3,) float64
        The point on ``a`` (or its line) and the point on ``b`` (or its line).
    """
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    da, db = a[1] - a[0], b[1] - b[0]
    la, lb = float(np.linalg.norm(da)), float(np.linalg.norm(db))
    ua, ub = da / la, db / lb
    if float(np.linalg.norm(np.cross(ua, ub))) < PARALLEL:
        along = np.sort((b - a[0]) @ ua)
        middle = float(np.clip((max(along[0], 0.0) + min(along[1], la)) / 2, 0.0, la))
        start = a[0] + ua * middle
        return start, b[0] + ub * ((start - b[0]) @ ub)
    # the closest points of two segments (Ericson, Real-Time Collision Detection, 5.1.9)
    r = a[0] - b[0]
    aa, bb, ab = da @ da, db @ db, da @ db
    c, f = da @ r, db @ r
    denom = aa * bb - ab * ab
    s = float(np.clip((ab * f - c * bb) / denom, 0.0, 1.0))
    t = (ab * s + f) / bb
    if t < 0.0:
        t, s = 0.0, float(np.clip(-c / aa, 0.0, 1.0))
    elif t > 1.0:
        t, s = 1.0, float(np.clip((ab - c) / aa, 0.0, 1.0))
    return a[0] + da * s, b[0] + db * t


def anchor_glyphs(glyphs: Glyphs, model: Model) -> Glyphs:
    """``glyphs`` with the points of every dimension given by edges found on ``model`` (the
    model as loaded, whose ``edge_numbers`` the edges are): one edge's two ends, or the points
    of ``edge_distance`` between two edges. Dimensions given by points stay as they are.

    Raises ``InputError`` naming the glyph file, the dimension and the edge where an edge is
    no edge of the model, where an edge has no length, or where two edges meet (no distance
    lies between them).
    """
    if not any(d.edges for d in glyphs.dimensions):
        return glyphs
    count = len(edge_numbers(model))
    name = model.source or "the model"
    scale = float(np.linalg.norm(np.diff(model.bounds, axis=0))) or 1.0
    out = []
    for i, dimension in enumerate(glyphs.dimensions, 1):
        if not dimension.edges:
            out.append(dimension)
            continue
        where = f"{glyphs.source}: dimension {i}"
        for edge in dimension.edges:
            if edge >= count:
                raise InputError(
                    f"{where}: edge {edge} is no edge of {name} (it has {count}: 0 to {count - 1})"
                )
        segments = edge_segments(model, np.asarray(dimension.edges, np.int64))
        for edge, (p, q) in zip(dimension.edges, segments, strict=True):
            if np.linalg.norm(q - p) <= 1e-12 * scale:
                raise InputError(f"{where}: edge {edge} of {name} has no length")
        start, end = segments[0] if len(segments) == 1 else edge_distance(*segments)
        if np.linalg.norm(end - start) <= 1e-9 * scale:
            n, m = dimension.edges
            raise InputError(f"{where}: edges {n} and {m} of {name} meet: no distance lies between them")
        out.append(replace(dimension, start=tuple(start.tolist()), end=tuple(end.tolist())))
    return replace(glyphs, dimensions=tuple(out))
