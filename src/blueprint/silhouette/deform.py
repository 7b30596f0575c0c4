"""Deforming meshes that change topology: the animations of ``blueprint silhouettes --animate``.

An :class:`Animation` bends a model every frame (``twist`` about its up axis, or a travelling
``wave``) and, part-way through, splits it into two pieces that move apart. The split keeps the
number of triangles: every face goes to the piece its centroid lies in, and the vertices on the
cut are duplicated, so the pieces open along a jagged border. That is the case the paper's
vertex-storage method handles with no preprocessing at all (its per-face positions keep their
layout), while the object-space method must weld, connect and orient from scratch.

Everything here is GPU-free: an animation hands out positions; :class:`blueprint.gpu_silhouettes.
SoupMesh` uploads them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from blueprint.errors import InputError
from blueprint.scene.model import Model
from blueprint.scene.weld import weld

__all__ = ["KINDS", "Animation", "Pose"]

KINDS = ("twist", "wave")
_UP_AXIS = {"y": 1, "z": 2}


@dataclass(frozen=True)
class Pose:
    """One frame of an animation.

    Attributes
    ----------
    positions : np.ndarray
        (V, 3) float32 vertex positions, the model's welded.
    faces : np.ndarray
        (F, 3) int32 vertex indices, in the model's face order; F never changes, the indices
        change once, at the split.
    topology : int
        0 before the split, 1 after: the connectivity of `faces` is the same for equal values.
    """

    positions: np.ndarray
    faces: np.ndarray
    topology: int

    def corners(self) -> np.ndarray:
        """(F, 3, 3) float32 positions of each face's corners: what the GPU method uploads."""
        return self.positions[self.faces]


class Animation:
    """A model deformed over ``frames`` frames, split in two at ``split_at``.

    Parameters
    ----------
    model : Model
    kind : {"twist", "wave"}
        ``twist`` turns horizontal slices about the up axis by up to ±90° at the ends, swinging
        back and forth; ``wave`` bends the model with a sine wave running along its longest
        horizontal axis.
    frames : int
        Number of frames, at least 1.
    split_at : float
        Fraction of the animation, in [0, 1], after which the model is in two pieces moving
        apart along its longest axis; 1 never splits.
    """

    def __init__(self, model: Model, kind: str = "twist", frames: int = 60, split_at: float = 0.5) -> None:
        if kind not in KINDS:
            raise InputError(f"unknown animation {kind!r} (choose {', '.join(KINDS)})")
        if int(frames) != frames or frames < 1:
            raise InputError(f"frames must be a positive integer, got {frames}")
        if not 0.0 <= split_at <= 1.0:
            raise InputError(f"split-at must be in [0, 1], got {split_at}")
        self.model, self.kind, self.frames, self.split_at = model, kind, int(frames), float(split_at)
        # welded, so that a pose's faces say which corners are one vertex even for a soup (an
        # STL): the methods that take the topology from it (ID lists, edge records) need that
        rest, faces = weld(model.positions, model.faces)
        self.faces = faces.astype(np.int32)
        used = rest[faces.reshape(-1)] if len(faces) else rest
        lo, hi = used.min(axis=0), used.max(axis=0)
        self.center = (lo + hi) / 2
        self.extent = float(np.linalg.norm(hi - lo)) or 1.0
        self.up = _UP_AXIS[model.up]
        horizontal = [a for a in range(3) if a != self.up]
        self.along = max(horizontal, key=lambda a: hi[a] - lo[a])
        self.across = next(a for a in horizontal if a != self.along)
        self.half_height = max((hi[self.up] - lo[self.up]) / 2, 1e-12 * self.extent)
        self.half_length = max((hi[self.along] - lo[self.along]) / 2, 1e-12 * self.extent)
        self.cut_axis = int(np.argmax(hi - lo))

        # The split topology: faces on the far side of the cut plane take copies of the
        # vertices they share with the near side.
        side = rest[faces].mean(axis=1)[:, self.cut_axis] > self.center[self.cut_axis]
        shared = np.zeros(len(rest), bool)
        near_used = np.zeros(len(rest), bool)
        near_used[faces[~side].reshape(-1)] = True
        shared[faces[side].reshape(-1)] = True
        shared &= near_used
        copy_of = np.flatnonzero(shared)
        remap = np.arange(len(rest))
        remap[copy_of] = len(rest) + np.arange(len(copy_of))
        self.split_faces = np.where(side[:, None], remap[faces], faces).astype(np.int32)
        self.split_source = np.concatenate([np.arange(len(rest)), copy_of])
        piece = np.zeros(len(self.split_source), np.float64)
        piece[self.split_faces[side].reshape(-1)] = 1.0
        self.piece_sign = 2.0 * piece - 1.0
        self._rest = rest

    def phase(self, frame: int) -> float:
        """The frame's place in the animation, in [0, 1]."""
        return frame / (self.frames - 1) if self.frames > 1 else 0.0

    def _deform(self, p: np.ndarray, s: float) -> np.ndarray:
        rel = p - self.center
        out = p.copy()
        if self.kind == "twist":
            h = rel[:, self.up] / self.half_height
            angle = 0.5 * math.pi * math.sin(2.0 * math.pi * s) * h
            c, sn = np.cos(angle), np.sin(angle)
            a, b = self.along, self.across
            out[:, a] = self.center[a] + c * rel[:, a] - sn * rel[:, b]
            out[:, b] = self.center[b] + sn * rel[:, a] + c * rel[:, b]
        else:
            x = rel[:, self.along] / self.half_length
            amplitude = 0.08 * self.extent
            out[:, self.up] += amplitude * np.sin(math.pi * (1.5 * x - 4.0 * s))
        return out

    def split(self, frame: int) -> bool:
        """Whether the model is in two pieces at `frame`."""
        return self.split_at < 1.0 and self.phase(frame) >= self.split_at

    def pose(self, frame: int) -> Pose:
        """Positions and faces at `frame` (0-based)."""
        if not 0 <= frame < self.frames:
            raise InputError(f"frame {frame} is outside the animation's {self.frames} frames")
        s = self.phase(frame)
        if not self.split(frame):
            return Pose(self._deform(self._rest, s).astype(np.float32), self.faces, 0)
        moved = self._deform(self._rest[self.split_source], s)
        gap = 0.35 * self.extent * (s - self.split_at) / max(1.0 - self.split_at, 1e-9)
        moved[:, self.cut_axis] += 0.5 * gap * self.piece_sign
        return Pose(moved.astype(np.float32), self.split_faces, 1)

    def bounds(self, samples: int = 9) -> np.ndarray:
        """(2, 3) float64 box around the model over the whole animation (sampled frames)."""
        frames = np.unique(np.linspace(0, self.frames - 1, min(samples, self.frames)).round().astype(int))
        if self.split_at < 1.0:
            frames = np.append(frames, self.frames - 1)
        points = np.concatenate([self.pose(int(f)).corners().reshape(-1, 3) for f in frames])
        return np.array([points.min(axis=0), points.max(axis=0)], dtype=np.float64)
