"""Shaded parts as filled polygons: every face of the parts to shade, projected, lit as the
raster lights them (a headlight and ambient, in the style's shade colour) and listed back to
front, so that painted in order the nearer faces cover the farther ones."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.scene.camera import clip_to_pixels, transform
from blueprint.scene.model import Model

__all__ = ["AMBIENT", "ShadedFaces", "shaded_faces"]

# The raster's shade.frag: light = AMBIENT + (1 - AMBIENT) * (n . towards the eye).
AMBIENT = 0.35


@dataclass(frozen=True)
class ShadedFaces:
    """Triangles to fill, back to front: ``points`` (T, 3, 2) pixels, ``color`` (T, 3) RGB in
    [0, 1], all at ``opacity``."""

    points: np.ndarray
    color: np.ndarray
    opacity: float

    def __len__(self) -> int:
        return len(self.points)


def shaded_faces(
    model: Model,
    faces: np.ndarray,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
    color: tuple[float, float, float],
    opacity: float,
) -> ShadedFaces:
    """The faces ``faces`` (indices into ``model.faces``) as lit triangles in depth order.

    Faces with a corner behind the eye are left out, and so are faces seen edge-on (no area
    on screen). Depth order is by the eye depth of each face's centroid, farthest first.
    """
    tri = model.positions[model.faces[faces]].astype(np.float64)
    eye = transform(tri, view)[..., :3]
    clip = transform(eye, projection)
    in_front = np.all(clip[..., 3] > 1e-12, axis=1)
    eye, pixels = eye[in_front], clip_to_pixels(clip[in_front], size)
    edge_a, edge_b = pixels[:, 1] - pixels[:, 0], pixels[:, 2] - pixels[:, 0]
    area = 0.5 * np.abs(edge_a[:, 0] * edge_b[:, 1] - edge_a[:, 1] * edge_b[:, 0])
    keep = area > 1e-9
    eye, pixels = eye[keep], pixels[keep]
    normal = np.cross(eye[:, 1] - eye[:, 0], eye[:, 2] - eye[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
    centroid = eye.mean(axis=1)
    ortho = bool(np.isclose(projection[3, 3], 1.0))
    toward = np.broadcast_to([0.0, 0.0, 1.0], centroid.shape) if ortho else -centroid
    toward = toward / np.maximum(np.linalg.norm(toward, axis=1), 1e-300)[:, None]
    # either side of a face is lit alike: open surfaces show their backs
    light = AMBIENT + (1 - AMBIENT) * np.abs(np.einsum("ij,ij->i", normal, toward))
    order = np.argsort(centroid[:, 2], kind="stable")  # eye z grows towards the eye
    shade = np.clip(light[order, None] * np.asarray(color, np.float64)[None, :3], 0.0, 1.0)
    return ShadedFaces(pixels[order], shade, float(opacity))
