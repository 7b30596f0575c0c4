"""Bézier patch models (the ``.bpt`` format of the Utah teapot) tessellated into triangles.

A ``.bpt`` file holds the number of patches on its first line, then per patch a line with the
two degrees (``3 3`` for bicubic) followed by ``(du + 1) * (dv + 1)`` control points ``x y z``,
one per line, row after row. The paper's teapots of 6K, 25K and 61K triangles are the 32
bicubic patches of the Utah teapot cut into ``n x n`` quads each: ``2 * 32 * n**2`` triangles
for n = 10, 20 and 31.
"""

from __future__ import annotations

import os
from math import comb
from pathlib import Path

import numpy as np

from blueprint.errors import InputError
from blueprint.scene.model import Model

__all__ = ["read_bpt", "tessellate", "teapot_model"]


def read_bpt(path: str | os.PathLike) -> list[np.ndarray]:
    """Read Bézier patches: a list of (du + 1, dv + 1, 3) float64 control nets.

    Raises
    ------
    InputError
        The file is missing or does not follow the format (one line naming what is wrong).
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    lines = [ln.split() for ln in path.read_text(encoding="ascii", errors="replace").splitlines()]
    lines = [ln for ln in lines if ln]
    try:
        count = int(lines[0][0])
        patches, at = [], 1
        for k in range(count):
            du, dv = (int(v) for v in lines[at])
            points = np.array(lines[at + 1 : at + 1 + (du + 1) * (dv + 1)], dtype=np.float64)
            if points.shape != ((du + 1) * (dv + 1), 3):
                raise ValueError(f"patch {k + 1} needs {(du + 1) * (dv + 1)} points of 3 coordinates")
            patches.append(points.reshape(du + 1, dv + 1, 3))
            at += 1 + (du + 1) * (dv + 1)
    except (IndexError, ValueError) as exc:
        raise InputError(f"{path}: not a Bézier patch file ({exc or 'truncated'})") from None
    if not patches:
        raise InputError(f"{path}: holds no patches")
    return patches


def _bernstein(degree: int, t: np.ndarray) -> np.ndarray:
    """(len(t), degree + 1) Bernstein basis values."""
    k = np.arange(degree + 1)
    return np.array([comb(degree, i) for i in k]) * t[:, None] ** k * (1 - t[:, None]) ** (degree - k)


def tessellate(patches: list[np.ndarray], n: int, up: str = "z") -> Model:
    """Cut every patch into ``n x n`` quads of two triangles: ``2 * len(patches) * n**2`` faces.

    Vertices are shared within a patch, not across patches (a patch seam repeats its vertices,
    as a triangle soup would); triangles that collapse at a patch's pole stay, degenerate.
    """
    if n < 1:
        raise InputError(f"tessellation must be at least 1 quad per patch side, got {n}")
    t = np.linspace(0.0, 1.0, n + 1)
    grid = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b = grid[:-1, :-1].reshape(-1), grid[:-1, 1:].reshape(-1)
    c, d = grid[1:, :-1].reshape(-1), grid[1:, 1:].reshape(-1)
    quad = np.concatenate([np.stack([a, c, d], 1), np.stack([a, d, b], 1)])
    positions, faces = [], []
    for k, net in enumerate(patches):
        bu, bv = _bernstein(net.shape[0] - 1, t), _bernstein(net.shape[1] - 1, t)
        points = np.einsum("ui,vj,ijc->uvc", bu, bv, net).reshape(-1, 3)
        positions.append(points)
        faces.append(quad + k * (n + 1) ** 2)
    return Model.from_arrays(np.concatenate(positions), np.concatenate(faces), up=up, source="teapot.bpt")


def teapot_model(path: str | os.PathLike, n: int) -> Model:
    """The patches of `path` tessellated at `n` (see :func:`tessellate`), Z up."""
    return tessellate(read_bpt(path), n)
