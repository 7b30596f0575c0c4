"""Close pairs and exact duplicates of the weld against brute force."""

from __future__ import annotations

import numpy as np
import pytest

from blueprint import parallel, settings
from blueprint.scene import weld


def brute_pairs(points: np.ndarray, tol: float) -> set[tuple[int, int]]:
    diff = points[:, None] - points[None]
    close = np.einsum("ijk,ijk->ij", diff, diff) <= tol * tol
    i, j = np.nonzero(np.triu(close, 1))
    return set(zip(i.tolist(), j.tolist(), strict=True))


def as_set(pairs) -> set[tuple[int, int]]:
    i, j = pairs
    return set(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist(), strict=True))


@pytest.mark.parametrize(("seed", "block"), [(0, None), (1, None), (2, None), (0, 7)])
def test_close_pairs_are_all_pairs_within_tolerance(seed, block, monkeypatch):
    if block is not None:  # the sweep's candidates a few at a time
        monkeypatch.setattr(weld, "_SWEEP_BLOCK", block)
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-1, 1, (60, 3))
    points = np.repeat(centres, 6, axis=0) + rng.normal(0, 0.004, (360, 3))
    for tol in (0.002, 0.01, 0.05):
        found = weld._close_pairs(points, tol)
        assert as_set(found) == brute_pairs(points, tol)
        assert len(as_set(found)) == len(found[0])  # each pair once


@pytest.mark.parametrize("stepped", [True, False])
def test_pairs_at_the_tolerance_along_the_sweep(stepped, monkeypatch):
    """Points a tolerance apart along the sweep's direction, where a step of the integer sweep
    (``_sweep_order``) or the window's own end falls between them, far from the origin: every
    pair brute force finds within the tolerance, by the projections in steps and by the
    projections themselves (steps too fine to fit)."""
    if not stepped:
        monkeypatch.setattr(weld, "_SWEEP_STEPS", 2.0**60)
    rng = np.random.default_rng(5)
    tol = 0.01
    k = np.arange(150)
    points = 1e3 + (k * tol)[:, None] * weld._SWEEP_DIRECTION
    points = np.concatenate([points, points[::3] + rng.normal(0, tol / 3, (50, 3))])
    order = weld._sweep_order(points @ weld._SWEEP_DIRECTION, tol)[0]
    assert (order.dtype == np.int64) and (len(order) == len(points))
    for scale in (1.0, 1.0 - 1e-12, 1.0 + 1e-12):
        found = weld._close_pairs(points, tol * scale)
        assert as_set(found) == brute_pairs(points, tol * scale)
        assert len(as_set(found)) == len(found[0])


def test_points_along_the_sweep_are_found_by_the_grid():
    """Points that share their projection on the sweep's direction (laid across it) are too
    many candidates for the sweep; the grid's answer is the same set."""
    rng = np.random.default_rng(3)
    across = np.cross(weld._SWEEP_DIRECTION, [0.0, 0.0, 1.0])
    across /= np.linalg.norm(across)
    points = rng.uniform(0, 1, 500)[:, None] * across + rng.normal(0, 1e-9, (500, 3))
    tol = 0.003
    assert as_set(weld._close_pairs(points, tol)) == brute_pairs(points, tol)
    assert as_set(weld._grid_pairs(points, tol)) == brute_pairs(points, tol)


def test_exact_duplicates_match_numpy_unique():
    rng = np.random.default_rng(4)
    points = rng.integers(0, 4, (2000, 3)).astype(np.float64) * 0.25 + 0.0
    unique, inverse = weld._exact_duplicates(points)
    np.testing.assert_array_equal(unique[inverse], points)
    assert len(unique) == len(np.unique(points, axis=0))


@pytest.mark.parametrize("threads", [1, 3])
def test_distinct_rows_numbered_as_int32_equal_those_as_int64(threads, monkeypatch):
    """The rows' numbers asked for as int32 are those of int64, and those of ``np.unique``'s
    rows renumbered by first occurrence; blocks of a few rows, so that every thread has some."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)
    monkeypatch.setattr(weld, "_HASH_BLOCK", 7)
    rng = np.random.default_rng(8)
    points = rng.integers(0, 5, (3000, 3)).astype(np.float32) * 0.5
    first, inverse = weld.distinct_rows(points, np.int32)
    wide_first, wide_inverse = weld.distinct_rows(points)
    assert inverse.dtype == np.int32 and wide_inverse.dtype == np.int64
    np.testing.assert_array_equal(first, wide_first)
    np.testing.assert_array_equal(inverse, wide_inverse)
    _, expected_first, expected = np.unique(points, axis=0, return_index=True, return_inverse=True)
    by_first = np.argsort(np.argsort(expected_first))
    np.testing.assert_array_equal(inverse, by_first[expected.reshape(-1)])
    np.testing.assert_array_equal(first, np.sort(expected_first))
