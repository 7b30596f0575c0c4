"""The pixels occlusion looks at: which ones a peel must keep for the samples of a drawing, and
the peeled layers' triangle IDs kept there."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from blueprint import parallel

from ..lines import BORDER, CREASE, SILHOUETTE
from .samples import Samples

__all__ = ["NEIGHBOURS", "PixelLayers", "across_line", "around", "flat_index", "probe_pixels"]

# The pixels whose centres surround a point, from the one ``around`` gives.
NEIGHBOURS = np.array([(0, 0), (1, 0), (0, 1), (1, 1)], np.int64)


def around(pixel: np.ndarray) -> np.ndarray:
    """(N, 2) int64: for (N, 2) pixel positions, the pixel up and left of each one whose centre
    is one corner of the square of pixel centres the position lies in (``NEIGHBOURS`` the four)."""
    return np.floor(pixel - 0.5).astype(np.int64)


@dataclass(frozen=True)
class PixelLayers:
    """Triangle IDs of the peeled layers at the pixels the occlusion tests look at.

    ``stacks[i, k]`` is the face of layer ``k`` at pixel ``pixels[i]`` (flat index
    ``y * width + x``, row 0 at the top), -1 where none; layers hold surfaces from the front,
    so the first ``count[i]`` are surfaces. ``pixels`` None stands for every pixel in order.
    """

    pixels: np.ndarray | None
    stacks: np.ndarray
    count: np.ndarray
    layers: int
    height: int
    width: int

    @classmethod
    def from_layers(cls, triangle: np.ndarray) -> PixelLayers:
        """Every pixel of (L, H, W) triangle layers."""
        layers, height, width = triangle.shape
        stacks = np.ascontiguousarray(triangle.reshape(layers, -1).T)
        return cls(None, stacks, (stacks >= 0).sum(axis=1), layers, height, width)

    def at(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(len(q), L) faces and (len(q),) surface counts at flat pixel indices ``q``, which
        must be among ``pixels``."""
        rows = q if self.pixels is None else np.take(self._rows, q)
        return np.take(self.stacks, rows, axis=0), self.count[rows]

    @functools.cached_property
    def _rows(self) -> np.ndarray:
        """Row of ``stacks`` for every flat pixel index (-1 where not kept): one gather a lookup."""
        rows = np.full(self.height * self.width, -1, np.int64)
        rows[self.pixels] = np.arange(len(self.pixels))
        return rows


def flat_index(spot: np.ndarray, height: int, width: int) -> np.ndarray:
    """Flat indices of (N, 2) integer pixel positions, clamped to the image."""
    return np.clip(spot[..., 1], 0, height - 1) * width + np.clip(spot[..., 0], 0, width - 1)


def probe_pixels(samples: Samples, size: tuple[int, int], offset: float = 1.0) -> np.ndarray:
    """Sorted flat indices of every pixel that ``levels.classify_samples`` and
    ``levels.verify_creases`` look at for these samples: what a peel must keep of its layers.
    Marked a block of samples a thread, a step of them at a time (only True is written, by any
    of them)."""
    width, height = size
    probed = np.zeros(height * width, bool)
    inside = np.flatnonzero(samples.inside)

    def corners(lo: int, hi: int) -> None:
        px = around(samples.pixel[inside[lo:hi]])
        # the 2 x 2 pixels' columns and rows clamped once each, as ``flat_index`` clamps them
        columns = [np.clip(px[:, 0] + dx, 0, width - 1) for dx in (0, 1)]
        rows = [np.clip(px[:, 1] + dy, 0, height - 1) * width for dy in (0, 1)]
        for dx, dy in NEIGHBOURS.tolist():
            probed[rows[dy] + columns[dx]] = True

    parallel.run(parallel.stepped(corners), len(inside))
    edges = np.flatnonzero(np.isin(samples.kind, (SILHOUETTE, BORDER, CREASE)) & samples.inside)
    edges, across = across_line(samples, edges)

    def sides(lo: int, hi: int) -> None:
        pixel, step = samples.pixel[edges[lo:hi]], offset * across[lo:hi]
        for side in (np.add, np.subtract):
            probed[flat_index(np.floor(side(pixel, step)).astype(np.int64), height, width)] = True

    parallel.run(parallel.stepped(sides), len(edges))
    return np.flatnonzero(probed)


def across_line(samples: Samples, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rows whose line has a screen direction there (from the neighbouring samples on the
    same line), and the unit vectors across it (``Samples.across``)."""
    if len(rows) == 0:
        return rows, np.zeros((0, 2))
    good, across = samples.across
    rows = rows[good[rows]]
    return rows, across[rows]
