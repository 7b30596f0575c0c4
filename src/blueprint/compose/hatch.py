"""Section hatching over a finished picture: thin lines at 45° across each cut face and a heavy
outline around it, found from the first layer's triangle IDs (the cut faces are the nearest
surfaces wherever a section removed what was in front).

ISO 128-50 varies the hatching of adjacent parts; here the parts whose cut faces touch get
different patterns (two directions by two spacings, chosen greedily over the parts that touch).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["HATCH_PATTERNS", "hatch_overlay", "hatch_patterns", "hatch_spacing_px"]

#: (degrees, spacing factor) of the patterns given to the cut faces of parts that touch.
HATCH_PATTERNS = ((45.0, 1.0), (135.0, 1.0), (45.0, 1.6), (135.0, 1.6))
# Cut outlines are drawn this many times the base line width (ISO 128: 0.5 mm against 0.25 mm).
OUTLINE_WIDTH = 2.0


def hatch_spacing_px(size: tuple[int, int], line_width: float = 1.0) -> float:
    """Pixels between hatch lines of the base pattern on a picture of ``size``: about 1/90 of
    its smaller side (2.5 mm on an A4 sheet's short side), never under five line widths."""
    return max(5.0 * line_width, min(size) / 90.0)


def hatch_patterns(part_image: np.ndarray, parts: np.ndarray) -> dict[int, int]:
    """Pattern index (into ``HATCH_PATTERNS``) of each part in ``parts``, different between parts
    whose cut faces share a pixel edge in ``part_image`` ((H, W) int, -1 where no cut face).

    The greedy colouring goes by part index, so a part keeps its pattern where it touches no
    more than three others."""
    touching: dict[int, set[int]] = {int(p): set() for p in parts}
    for a, b in (
        (part_image[:, 1:], part_image[:, :-1]),
        (part_image[1:, :], part_image[:-1, :]),
    ):
        edge = (a != b) & (a >= 0) & (b >= 0)
        for p, q in np.unique(np.stack([a[edge], b[edge]], axis=1), axis=0).tolist() if edge.any() else []:
            touching.setdefault(p, set()).add(q)
            touching.setdefault(q, set()).add(p)
    chosen: dict[int, int] = {}
    for part in sorted(touching):
        used = {chosen[q] for q in touching[part] if q in chosen}
        chosen[part] = next(
            (k for k in range(len(HATCH_PATTERNS)) if k not in used), part % len(HATCH_PATTERNS)
        )
    return {int(p): chosen[int(p)] for p in parts}


def hatch_overlay(
    image: np.ndarray,
    triangles: np.ndarray,
    face_part: np.ndarray,
    cap: np.ndarray,
    ink: tuple[float, float, float, float],
    *,
    supersample: int = 1,
    spacing: float | None = None,
    line_width: float = 1.0,
) -> np.ndarray:
    """Hatch the cut faces of a section onto ``image``.

    Parameters
    ----------
    image : (H, W, 4) uint8
        The drawing, straight (not premultiplied) alpha.
    triangles : (H * s, W * s) int32
        The first layer's triangle IDs at ``supersample`` times the image's size, -1 where none.
    face_part : (F,) int32
        Part of each face.
    cap : (F,) bool
        The cut faces.
    ink : RGBA floats in [0, 1]
        Colour of the hatching and the outline.
    supersample : int
        ``s`` above: coverage is computed at that resolution and averaged down.
    spacing : float, optional
        Pixels between hatch lines of the base pattern (default ``hatch_spacing_px``).
    line_width : float
        Hatch line width in pixels; the cut outline is ``OUTLINE_WIDTH`` times as wide.

    Returns
    -------
    (H, W, 4) uint8
        A new image.
    """
    from scipy import ndimage

    h, w = image.shape[:2]
    s = int(supersample)
    if triangles.shape != (h * s, w * s):
        raise ValueError(f"triangles must be {(h * s, w * s)}, got {triangles.shape}")
    spacing = hatch_spacing_px((w, h), line_width) if spacing is None else float(spacing)
    covered = triangles >= 0
    on_cap = np.zeros(triangles.shape, bool)
    on_cap[covered] = cap[triangles[covered]]
    part_image = np.full(triangles.shape, -1, np.int64)
    part_image[on_cap] = face_part[triangles[on_cap]]
    parts = np.unique(part_image[on_cap])
    patterns = hatch_patterns(part_image, parts)

    # pixel centres in output pixels
    y, x = np.mgrid[0 : h * s, 0 : w * s].astype(np.float64)
    x, y = (x + 0.5) / s, (y + 0.5) / s
    # each cut pixel's pattern: the lines drawn a pattern at a time, not a part at a time (a
    # section through an assembly cuts hundreds of parts, and each pass reads every pixel)
    pattern_of = np.full(int(parts.max()) + 1 if len(parts) else 0, -1, np.int64)
    pattern_of[parts] = [patterns[part] for part in parts.tolist()]
    pattern_image = np.full(triangles.shape, -1, np.int64)
    pattern_image[on_cap] = pattern_of[part_image[on_cap]]
    lines = np.zeros(triangles.shape, bool)
    for pattern in sorted(set(patterns.values())):
        angle, factor = HATCH_PATTERNS[pattern]
        a = math.radians(angle)
        step = spacing * factor
        # distance along the normal of lines at ``angle`` (y grows downwards: a picture's 45°)
        d = x * math.sin(a) + y * math.cos(a)
        phase = np.mod(d, step)
        near = np.minimum(phase, step - phase) <= 0.5 * line_width
        lines |= near & (pattern_image == pattern)

    boundary = np.zeros(triangles.shape, bool)
    for axis in (0, 1):
        differs = np.diff(part_image, axis=axis) != 0
        edge = differs & ((np.delete(part_image, 0, axis) >= 0) | (np.delete(part_image, -1, axis) >= 0))
        if axis == 0:
            boundary[1:] |= edge
            boundary[:-1] |= edge
        else:
            boundary[:, 1:] |= edge
            boundary[:, :-1] |= edge
    radius = max(int(round(0.5 * OUTLINE_WIDTH * line_width * s)) - 1, 0)
    if radius:
        boundary = ndimage.binary_dilation(boundary, iterations=radius)
    strokes = (lines | boundary).astype(np.float64)
    coverage = strokes.reshape(h, s, w, s).mean(axis=(1, 3))

    a = coverage * float(ink[3])
    src = image.astype(np.float64) / 255.0
    out_a = a + src[..., 3] * (1.0 - a)
    rgb = np.asarray(ink[:3], np.float64) * a[..., None] + src[..., :3] * (src[..., 3] * (1.0 - a))[..., None]
    rgb = np.divide(rgb, out_a[..., None], out=np.zeros_like(rgb), where=out_a[..., None] > 0)
    out = np.concatenate([rgb, out_a[..., None]], axis=-1)
    return np.round(np.clip(out, 0.0, 1.0) * 255.0).astype(np.uint8)
