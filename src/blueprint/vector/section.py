"""Section hatching as vectors: each part's cut faces projected to the picture and joined into
polygons (shapely), hatch lines clipped to them, their outlines as the heavy cut outline.

The hatch patterns are those of the raster overlay (``blueprint.compose.hatch``), different
between parts whose cut faces touch. Cut faces are the nearest surfaces where the section
removed what was in front; parts drawn whole (``section_keep``) in front of a cut face do not
clip its hatching.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from blueprint.compose.hatch import HATCH_PATTERNS
from blueprint.scene.camera import to_pixels
from blueprint.scene.section import Cut
from blueprint.sorting import grouped

__all__ = ["SECTION_HATCH_WIDTH", "SECTION_OUTLINE_WIDTH", "SectionLines", "section_lines"]

# Widths in base line widths: thin hatching, a heavy cut outline (ISO 128: 0.5 mm to 0.25 mm).
SECTION_HATCH_WIDTH = 0.7
SECTION_OUTLINE_WIDTH = 2.0


@dataclass(frozen=True)
class SectionLines:
    """A section's hatching and cut outline in pixels (x right, y down).

    Attributes
    ----------
    hatch : (K, 2, 2) float64
        Hatch line segments.
    hatch_part : (K,) int32
        The part each hatch segment fills.
    outline : (M, 2, 2) float64
        Segments of the cut outline.
    area : dict of int to float
        Hatched area per part, in square pixels.
    """

    hatch: np.ndarray
    hatch_part: np.ndarray
    outline: np.ndarray
    area: dict[int, float]

    def shifted(self, by: np.ndarray) -> SectionLines:
        """The same lines moved by ``by`` (2,) pixels (a view's place on a sheet)."""
        shift = np.asarray(by, np.float64).reshape(1, 1, 2)
        return SectionLines(self.hatch + shift, self.hatch_part, self.outline + shift, dict(self.area))

    @staticmethod
    def concatenate(items: list[SectionLines]) -> SectionLines:
        area: dict[int, float] = {}
        for item in items:
            for part, value in item.area.items():
                area[part] = area.get(part, 0.0) + value
        return SectionLines(
            np.concatenate([i.hatch for i in items]).reshape(-1, 2, 2),
            np.concatenate([i.hatch_part for i in items]).astype(np.int32),
            np.concatenate([i.outline for i in items]).reshape(-1, 2, 2),
            area,
        )


def _segments(geometry) -> list[np.ndarray]:
    """(2, 2) segments of every line string in a shapely geometry."""
    out = []
    for line in getattr(geometry, "geoms", [geometry]):
        if line.is_empty:
            continue
        if hasattr(line, "geoms"):
            out.extend(_segments(line))
            continue
        coords = np.asarray(line.coords, np.float64)
        out.extend(np.stack([coords[:-1], coords[1:]], axis=1))
    return out


def _patterns(polygons: dict[int, object]) -> dict[int, int]:
    """Each part's pattern (an index into ``HATCH_PATTERNS``), by part: the first not taken by
    a part before it whose region lies less than half a pixel from its own. The parts near
    each found through a tree of their regions, not by every pair (a section through an
    assembly cuts hundreds of parts)."""
    import shapely

    parts = sorted(polygons)
    regions = [polygons[part] for part in parts]
    near: list[list[int]] = [[] for _ in parts]
    if regions:
        # candidates: the regions whose boxes meet each one's box grown by half a pixel (no
        # "dwithin" predicate: it needs GEOS 3.10, which a Shapely 2 may lack)
        x0, y0, x1, y1 = shapely.bounds(regions).T
        grown = shapely.box(x0 - 0.5, y0 - 0.5, x1 + 0.5, y1 + 0.5)
        a, b = shapely.STRtree(regions).query(grown)
        close = (b < a) & (shapely.distance(np.take(regions, a), np.take(regions, b)) < 0.5)
        for i, j in zip(a[close].tolist(), b[close].tolist(), strict=True):
            near[i].append(j)
    chosen: list[int] = []
    for i in range(len(parts)):
        used = {chosen[j] for j in near[i]}
        chosen.append(next((k for k in range(len(HATCH_PATTERNS)) if k not in used), 0))
    return dict(zip(parts, chosen, strict=True))


def section_lines(
    cut: Cut, view: np.ndarray, projection: np.ndarray, size: tuple[int, int], spacing: float
) -> SectionLines:
    """The hatching and outline of ``cut``'s cut faces as seen through ``view`` and
    ``projection`` on a picture of ``size`` pixels, hatch lines ``spacing`` pixels apart in the
    base pattern."""
    import shapely
    from shapely.geometry import LineString, MultiLineString

    model = cut.model
    projected = to_pixels(model.positions.astype(np.float64), view, projection, size)
    polygons = {}
    # the cut faces a part at a time, in part order
    capped = np.flatnonzero(cut.cap)
    for part, which in grouped(model.face_part[capped]):
        triangles = shapely.polygons(projected[model.faces[capped[which]]])
        # tiny growth then shrink welds triangles that meet along shared edges despite rounding
        region = shapely.union_all(shapely.buffer(triangles, 1e-6)).buffer(-1e-6)
        if not region.is_empty and region.area > 0:
            polygons[part] = region
    patterns = _patterns(polygons)

    hatch, hatch_part, outline = [], [], []
    for part, region in polygons.items():
        angle, factor = HATCH_PATTERNS[patterns[part]]
        a = math.radians(angle)
        step = spacing * factor
        normal = np.array([math.sin(a), math.cos(a)])  # the raster overlay's, y down
        direction = np.array([normal[1], -normal[0]])
        x0, y0, x1, y1 = region.bounds
        corners = np.array([[x0, y0], [x0, y1], [x1, y0], [x1, y1]])
        d = corners @ normal
        t = corners @ direction
        first = math.ceil(d.min() / step)
        offsets = np.arange(first, math.floor(d.max() / step) + 1) * step
        reach = np.array([t.min() - 1.0, t.max() + 1.0])
        if len(offsets):
            lines = MultiLineString(
                [
                    [tuple(o * normal + reach[0] * direction), tuple(o * normal + reach[1] * direction)]
                    for o in offsets
                ]
            )
            found = _segments(region.intersection(lines))
            hatch.extend(found)
            hatch_part.extend([part] * len(found))
        for piece in getattr(region, "geoms", [region]):
            for ring in [piece.exterior, *piece.interiors]:
                outline.extend(_segments(LineString(ring.coords)))
    return SectionLines(
        np.asarray(hatch, np.float64).reshape(-1, 2, 2),
        np.asarray(hatch_part, np.int32),
        np.asarray(outline, np.float64).reshape(-1, 2, 2),
        {part: float(region.area) for part, region in polygons.items()},
    )
