"""Anti-aliased line drawing into a NumPy image, vectorised over segments."""

from __future__ import annotations

import numpy as np

__all__ = ["draw_segments"]

# Segments are cut into collinear pieces at most this many pixels long: the union of the
# pieces' capsules is the segment's capsule, and short pieces keep bounding boxes tight for
# diagonal lines, whose boxes would otherwise be mostly empty.
_PIECE_LENGTH = 8.0
# Candidate pixels evaluated per NumPy pass; bounds the temporary arrays to tens of MB.
_CHUNK_PIXELS = 1 << 20


def _clip_to_box(segments: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Liang-Barsky clip of (N, 2, 2) segments to the box [lo, hi].

    Returns the clipped (M, 2, 2) segments and the (N,) bool mask of those that survived.
    """
    p0, delta = segments[:, 0], segments[:, 1] - segments[:, 0]
    t_enter = np.zeros(len(segments))
    t_leave = np.ones(len(segments))
    keep = np.ones(len(segments), dtype=bool)
    for axis in (0, 1):
        d, start = delta[:, axis], p0[:, axis]
        flat = d == 0.0
        keep &= ~flat | ((start >= lo[axis]) & (start <= hi[axis]))
        safe = np.where(flat, 1.0, d)
        t_lo, t_hi = (lo[axis] - start) / safe, (hi[axis] - start) / safe
        t_enter = np.where(flat, t_enter, np.maximum(t_enter, np.minimum(t_lo, t_hi)))
        t_leave = np.where(flat, t_leave, np.minimum(t_leave, np.maximum(t_lo, t_hi)))
    keep &= t_enter <= t_leave
    p0, delta = p0[keep], delta[keep]
    t = np.stack([t_enter[keep], t_leave[keep]], axis=1)
    return p0[:, None, :] + t[:, :, None] * delta[:, None, :], keep


def draw_segments(
    segments2d: np.ndarray,
    width: int,
    height: int,
    line_width: float = 1.0,
    intensity: float | np.ndarray | None = None,
) -> np.ndarray:
    """Draw anti-aliased line segments, combining overlaps by maximum.

    A pixel's coverage falls linearly from 1 to 0 as the distance from its centre to the
    segment grows from ``line_width / 2 - 0.5`` to ``line_width / 2 + 0.5``, so a line
    deposits about ``line_width`` of ink per pixel of length, and its ends are round.

    Parameters
    ----------
    segments2d : np.ndarray
        (N, 2, 2) float endpoints in pixels: x right, y down, origin at the top-left corner,
        pixel centres at +0.5.
    width, height : int
        Image size in pixels.
    line_width : float
        Line width in pixels, > 0.
    intensity : float or np.ndarray, optional
        Scalar or (N,) per-segment peak values in [0, 1]; defaults to 1.

    Returns
    -------
    np.ndarray
        (height, width) float32 image in [0, 1].
    """
    segments = np.asarray(segments2d, dtype=np.float64)
    if segments.ndim != 3 or segments.shape[1:] != (2, 2):
        raise ValueError(f"segments2d must have shape (N, 2, 2), got {segments.shape}")
    if not np.isfinite(segments).all():
        raise ValueError("segments2d must be finite")
    if int(width) != width or int(height) != height or width <= 0 or height <= 0:
        raise ValueError(f"width and height must be positive integers, got {width}x{height}")
    if not (np.isfinite(line_width) and line_width > 0):
        raise ValueError(f"line_width must be a positive number, got {line_width}")
    value = np.asarray(1.0 if intensity is None else intensity, dtype=np.float64)
    if value.shape not in ((), (len(segments),)):
        raise ValueError(f"intensity must be a scalar or shape ({len(segments)},), got {value.shape}")
    value = np.broadcast_to(value, len(segments))
    if not ((value >= 0.0) & (value <= 1.0)).all():
        raise ValueError("intensity must lie in [0, 1]")
    width, height = int(width), int(height)

    # Coverage is zero farther than `reach` from the segment; parts of a segment beyond
    # `reach` of every pixel centre cannot change the image, so clip them away.
    reach = 0.5 * line_width + 0.5
    segments, kept = _clip_to_box(
        segments, np.array([0.5 - reach] * 2), np.array([width - 0.5, height - 0.5]) + reach
    )
    value = value[kept]

    length = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=1)
    pieces_per = np.maximum(np.ceil(length / _PIECE_LENGTH), 1).astype(np.int64)
    owner = np.repeat(np.arange(len(segments)), pieces_per)
    k = np.arange(len(owner)) - np.repeat(np.cumsum(pieces_per) - pieces_per, pieces_per)
    t = np.stack([k, k + 1], axis=1) / pieces_per[owner, None]
    a, d = segments[owner, 0], segments[owner, 1] - segments[owner, 0]
    piece_a, piece_d = a + t[:, :1] * d, (t[:, 1:] - t[:, :1]) * d
    value = value[owner]

    # Pixel i is a candidate when its centre i + 0.5 can lie within `reach` of the piece.
    ends = np.stack([piece_a, piece_a + piece_d], axis=1)
    first = np.maximum(np.ceil(ends.min(axis=1) - reach - 0.5), 0).astype(np.int64)
    limit = np.array([width - 1, height - 1])
    last = np.minimum(np.floor(ends.max(axis=1) + reach - 0.5), limit).astype(np.int64)
    box = np.maximum(last - first + 1, 0)
    box_pixels = box[:, 0] * box[:, 1]

    # Per-piece constants, gathered once per candidate pixel below. Offsets are taken from
    # the box corner's pixel centre so that candidates only need their in-box position.
    origin = piece_a - first - 0.5
    len2 = np.einsum("ij,ij->i", piece_d, piece_d)
    # A zero-length piece is a dot: its projection parameter stays 0.
    inv_len2 = np.divide(1.0, len2, out=np.zeros_like(len2), where=len2 > 0)
    corner_index = first[:, 1] * width + first[:, 0]

    image = np.zeros(height * width, dtype=np.float64)
    # Split the pieces wherever the running pixel count crosses a multiple of the chunk size.
    chunk = (np.cumsum(box_pixels) - box_pixels) // _CHUNK_PIXELS
    bounds = np.flatnonzero(np.diff(chunk)) + 1
    for lo, hi in zip(np.r_[0, bounds], np.r_[bounds, len(box_pixels)], strict=True):
        n = box_pixels[lo:hi]
        piece = np.repeat(np.arange(lo, hi), n)
        qy, qx = np.divmod(np.arange(len(piece)) - np.repeat(np.cumsum(n) - n, n), box[piece, 0])
        rx, ry = qx - origin[piece, 0], qy - origin[piece, 1]
        dx, dy = piece_d[piece, 0], piece_d[piece, 1]
        along = np.clip((rx * dx + ry * dy) * inv_len2[piece], 0.0, 1.0)
        coverage = reach - np.hypot(rx - along * dx, ry - along * dy)
        coverage = np.minimum(coverage, 1.0) * value[piece]
        hit = np.flatnonzero(coverage > 0)
        pixel = corner_index[piece[hit]] + qy[hit] * width + qx[hit]
        np.maximum.at(image, pixel, coverage[hit])
    return image.reshape(height, width).astype(np.float32)
