"""Glyph geometry on screen: model points to pixels and eye depths for a camera at an image
size, segments clipped to the near plane and to the image, and the depth test against the
blueprint's front surface that tells which glyph samples lie behind it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.scene.camera import Camera, clip_to_pixels, transform

__all__ = ["DEPTH_TOLERANCE", "View", "near_clip", "screen_range"]

# A sample is hidden when the front surface is nearer than its eye depth by more than this
# fraction of it. The surface is taken as the farthest of the 3x3 pixels around the sample's, so
# a glyph lying on a face (even one seen at a grazing angle) or along a silhouette never hides
# itself; an occluder's outline lets the glyph through by at most a pixel.
DEPTH_TOLERANCE = 1e-3


@dataclass
class View:
    """A camera at an image size: model points to pixels and eye depths, and the surface test."""

    camera: Camera
    width: int
    height: int
    depth: np.ndarray | None  # (H, W) window depth of the front surface, 1.0: none

    def __post_init__(self) -> None:
        self.mvp = self.camera.projection_matrix() @ self.camera.view_matrix()

    def clip(self, points: np.ndarray) -> np.ndarray:
        """(..., 3) model points -> (..., 4) clip coordinates."""
        return transform(points, self.mvp)

    def screen(self, clip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(..., 4) clip coordinates in front of the near plane -> (..., 2) pixels, (...) NDC z."""
        pixels = clip_to_pixels(clip, (self.width, self.height), depth=True)
        return pixels[..., :2], pixels[..., 2]

    def eye_depth(self, z_ndc: np.ndarray) -> np.ndarray:
        """Distance along the view axis from NDC z (the inverse of the projection's z)."""
        n, f = self.camera.near, self.camera.far
        if self.camera.ortho:
            return (z_ndc * (f - n) + (f + n)) / 2
        return 2 * f * n / ((f + n) - z_ndc * (f - n))

    def hidden(self, xy: np.ndarray, eye: np.ndarray) -> np.ndarray:
        """(N,) bool: the front surface lies nearer than these (N, 2) screen samples at (N,) eye
        depths by more than ``DEPTH_TOLERANCE``; the surface is the farthest of the 3x3 pixels
        around the sample's pixel (window depth grows with eye depth, so the farthest window
        depth is the farthest surface). Samples off the image are never hidden."""
        if self.depth is None:
            return np.zeros(len(xy), bool)
        ix = np.floor(xy[:, 0]).astype(np.int64)
        iy = np.floor(xy[:, 1]).astype(np.int64)
        inside = (ix >= 0) & (ix < self.width) & (iy >= 0) & (iy < self.height)
        ix, iy = ix[inside], iy[inside]
        far = np.zeros(len(ix), np.float64)
        for dy in (-1, 0, 1):
            rows = np.clip(iy + dy, 0, self.height - 1)
            for dx in (-1, 0, 1):
                np.maximum(far, self.depth[rows, np.clip(ix + dx, 0, self.width - 1)], out=far)
        surface = np.full(len(xy), np.inf)
        covered = far < 1.0
        surface[np.flatnonzero(inside)[covered]] = self.eye_depth(2.0 * far[covered] - 1.0)
        return surface < eye * (1 - DEPTH_TOLERANCE)


def near_clip(clip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cut (S, 2, 4) clip-space segments at the near plane (z >= -w); returns the kept
    segments and the mask of those kept."""
    e = clip[..., 2] + clip[..., 3]
    keep = (e[:, 0] > 0) | (e[:, 1] > 0)
    clip, e = clip[keep].copy(), e[keep]
    for end in (0, 1):
        cut = e[:, end] <= 0
        if cut.any():
            a, b = e[cut, end], e[cut, 1 - end]
            # a hair inside the plane, so w stays positive
            t = (a / (a - b))[:, None] * (1 + 1e-9)
            clip[cut, end] = clip[cut, end] + np.minimum(t, 1.0) * (clip[cut, 1 - end] - clip[cut, end])
    return clip, keep


def screen_range(
    p0: np.ndarray, p1: np.ndarray, lo: float, hi_x: float, hi_y: float
) -> tuple[np.ndarray, np.ndarray]:
    """Liang-Barsky: the (S,) parameter range [t0, t1] of each screen segment inside the box."""
    t0 = np.zeros(len(p0))
    t1 = np.ones(len(p0))
    d = p1 - p0
    for axis, hi in ((0, hi_x), (1, hi_y)):
        flat = d[:, axis] == 0
        inside = (p0[:, axis] >= lo) & (p0[:, axis] <= hi)
        safe = np.where(flat, 1.0, d[:, axis])
        a, b = (lo - p0[:, axis]) / safe, (hi - p0[:, axis]) / safe
        t0 = np.where(flat, np.where(inside, t0, 2.0), np.maximum(t0, np.minimum(a, b)))
        t1 = np.where(flat, np.where(inside, t1, -1.0), np.minimum(t1, np.maximum(a, b)))
    return t0, t1
