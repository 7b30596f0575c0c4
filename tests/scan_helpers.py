"""Generated scans and the measures of issue 39, point 2: specks (small blobs of ink) and
zigzag (a contour's length against its length smoothed along the line)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy import ndimage

import blueprint


def stanford_bunny(shared_models) -> blueprint.Model:
    """The stanford bunny of the shared models (``shared_models``: the fixture's folder); the
    test skips where a user's fresh clone has no shared models beside it."""
    path = shared_models / "common-3d-test-models" / "stanford-bunny.obj"
    if not path.exists():
        pytest.skip(f"{path} is missing from the shared models")
    return blueprint.load_model(path)


def ink(image: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels that differ from the paper (the top-left pixel) by more than 60 in
    summed RGB."""
    rgb = image[..., :3].astype(int)
    return np.abs(rgb - rgb[0, 0]).sum(axis=-1) > 60


def specks(image: np.ndarray) -> int:
    """The 8-connected blobs of ``ink`` of at most 12 pixels."""
    labels, _ = ndimage.label(ink(image), np.ones((3, 3)))
    return int((np.bincount(labels.ravel())[1:] <= 12).sum())


def zigzag(points: np.ndarray, sigma: float = 3.0, step: float = 0.25) -> tuple[float, float]:
    """(length, smoothed length) in pixels of a polyline (n, 2): resampled every ``step``
    pixels along its length, each coordinate filtered with a Gaussian of ``sigma`` pixels
    along the line (wrapping round where the line is closed)."""
    along = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))]
    at = np.arange(0.0, along[-1], step)
    even = np.column_stack([np.interp(at, along, points[:, k]) for k in (0, 1)])
    closed = np.linalg.norm(points[0] - points[-1]) < 1e-9
    smooth = ndimage.gaussian_filter1d(even, sigma / step, axis=0, mode="wrap" if closed else "nearest")
    return float(along[-1]), float(np.linalg.norm(np.diff(smooth, axis=0), axis=1).sum())


def zigzag_ratio(polylines, shortest: float = 40.0) -> float:
    """Summed length over summed smoothed length (``zigzag``) of the polylines (each (n, 2)
    pixels) at least ``shortest`` pixels long."""
    measured = [zigzag(p) for p in polylines]
    measured = [(a, b) for a, b in measured if a >= shortest]
    assert measured, "no polyline long enough to measure"
    return sum(a for a, _ in measured) / sum(b for _, b in measured)


def noisy_sphere(amplitude: float, subdivisions: int = 4, seed: int = 7) -> blueprint.Model:
    """A unit icosphere with each vertex moved radially by ``amplitude`` times a normal deviate:
    a generated scan of a surface with no crease at all."""
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    rng = np.random.default_rng(seed)
    radius = 1 + amplitude * rng.standard_normal(len(sphere.vertices))
    return blueprint.Model.from_arrays(
        np.asarray(sphere.vertices) * radius[:, None], np.asarray(sphere.faces)
    )


RIDGE_WIDTH = 0.25  # radians of longitude to either side of the ridge's crest
RIDGE_LATITUDES = (0.6, 2.5)  # polar angles (radians from +y) where the ridge is full height


def noisy_bust(amplitude: float = 0.0015, seed: int = 3) -> tuple[blueprint.Model, np.ndarray]:
    """A bust-like head: an ellipsoid (0.8 x 1 x 0.9, y up) of 96 x 192 latitude-longitude
    quads with noise on its radii of ``amplitude`` times a normal deviate times the sine of the
    polar angle (so the noise keeps to the quads' size near the poles), and a sharp ridge
    (a nose) down its front: the radius grows by 0.3 at longitude 0 (facing +z), falling off
    linearly over ``RIDGE_WIDTH`` to either side, between the polar angles ``RIDGE_LATITUDES``,
    tapering smoothly to nothing a quarter radian beyond. Its crest runs along a row of mesh
    edges, where the faces meet at about 80 degrees.

    Returns the model and the (n, 3) model-space points of the crest, every vertex on it where
    the ridge is full height.
    """
    rows, columns = 96, 192
    theta = np.linspace(0, np.pi, rows + 1)  # polar angle from +y
    phi = np.linspace(-np.pi, np.pi, columns, endpoint=False)  # 0 faces +z
    t, p = np.meshgrid(theta, phi, indexing="ij")
    lo, hi = RIDGE_LATITUDES
    window = np.clip(np.minimum(t - (lo - 0.25), (hi + 0.25) - t) / 0.25, 0, 1)
    window = window * window * (3 - 2 * window)
    radius = 1 + 0.3 * np.clip(1 - np.abs(p) / RIDGE_WIDTH, 0, 1) * window
    rng = np.random.default_rng(seed)
    radius = radius * (1 + amplitude * np.sin(t) * rng.standard_normal(radius.shape))
    points = np.stack([0.8 * np.sin(t) * np.sin(p), np.cos(t), 0.9 * np.sin(t) * np.cos(p)], axis=-1)
    points *= radius[..., None]
    # the poles are one vertex each
    body = points[1:-1].reshape(-1, 3)
    positions = np.vstack([body, [[0, radius[0].mean(), 0], [0, -radius[-1].mean(), 0]]])
    top, bottom = len(body), len(body) + 1
    index = np.arange((rows - 1) * columns).reshape(rows - 1, columns)
    right = np.roll(index, -1, axis=1)
    quads_a = np.stack([index[:-1], index[1:], right[1:]], axis=-1).reshape(-1, 3)
    quads_b = np.stack([index[:-1], right[1:], right[:-1]], axis=-1).reshape(-1, 3)
    caps_top = np.stack([np.full(columns, top), index[0], right[0]], axis=-1)
    caps_bottom = np.stack([np.full(columns, bottom), right[-1], index[-1]], axis=-1)
    faces = np.vstack([quads_a, quads_b, caps_top, caps_bottom])
    mesh = trimesh.Trimesh(positions, faces, process=False)
    if mesh.volume < 0:
        faces = faces[:, ::-1]
    crest = points[(t[:, 0] >= lo) & (t[:, 0] <= hi), columns // 2]
    return blueprint.Model.from_arrays(positions, faces), crest
