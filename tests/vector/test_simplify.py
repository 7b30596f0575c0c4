"""Douglas–Peucker over many polylines at once."""

import numpy as np
import pytest
from vector_helpers import point_segment_distance, segments_of

from blueprint.vector.simplify import douglas_peucker


def test_collinear_points_reduce_to_the_ends():
    line = np.stack([np.linspace(0, 10, 11), np.linspace(0, 5, 11)], axis=1)
    points, offsets, kept = douglas_peucker(line, np.array([0, 11]), 0.25)
    np.testing.assert_array_equal(points, line[[0, 10]])
    np.testing.assert_array_equal(offsets, [0, 2])
    assert kept.sum() == 2


def test_corners_above_the_tolerance_stay_and_below_go():
    zigzag = np.array([[0, 0], [1, 0.2], [2, 0], [3, 1.0], [4, 0]], float)
    points, _, _ = douglas_peucker(zigzag, np.array([0, 5]), 0.25)
    np.testing.assert_array_equal(points, zigzag[[0, 2, 3, 4]])


def test_many_polylines_keep_their_ends_and_stay_within_tolerance():
    rng = np.random.default_rng(3)
    lengths = rng.integers(1, 60, 200)
    offsets = np.r_[0, np.cumsum(lengths)]
    walk = np.cumsum(rng.normal(size=(offsets[-1], 2)), axis=0)
    tol = 0.4
    points, new_offsets, kept = douglas_peucker(walk, offsets, tol)
    assert len(new_offsets) == len(offsets)
    for i in range(len(lengths)):
        original = walk[offsets[i] : offsets[i + 1]]
        simple = points[new_offsets[i] : new_offsets[i + 1]]
        np.testing.assert_array_equal(simple[0], original[0])
        np.testing.assert_array_equal(simple[-1], original[-1])
        if len(simple) >= 2:
            gap = point_segment_distance(original, segments_of([simple])).min(axis=1)
            assert gap.max() <= tol + 1e-12
    assert kept.sum() == len(points) < len(walk)


def test_polylines_simplified_in_blocks_are_each_simplified_alone(monkeypatch):
    """The polylines' intervals split a block at a time on the pool (blocks of 16 over four
    threads here): each polyline comes out as it does simplified alone, bit for bit."""
    from blueprint import parallel, settings

    rng = np.random.default_rng(4)
    lengths = rng.integers(1, 40, 300)
    offsets = np.r_[0, np.cumsum(lengths)]
    walk = np.cumsum(rng.normal(size=(offsets[-1], 2)), axis=0)
    monkeypatch.setattr(settings, "THREADS", 4)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)
    points, new_offsets, kept = douglas_peucker(walk, offsets, 0.4)
    monkeypatch.setattr(settings, "THREADS", 1)
    for i in range(len(lengths)):
        alone, _, alone_kept = douglas_peucker(
            walk[offsets[i] : offsets[i + 1]], np.array([0, lengths[i]]), 0.4
        )
        assert points[new_offsets[i] : new_offsets[i + 1]].tobytes() == alone.tobytes()
        np.testing.assert_array_equal(kept[offsets[i] : offsets[i + 1]], alone_kept)
    assert len(points) < len(walk)


def test_closed_loop_and_bad_tolerance():
    t = np.linspace(0, 2 * np.pi, 65)
    circle = np.stack([np.cos(t), np.sin(t)], axis=1) * 50
    points, _, _ = douglas_peucker(circle, np.array([0, 65]), 0.25)
    assert 10 < len(points) < 65
    np.testing.assert_allclose(points[0], points[-1], atol=1e-9)
    with pytest.raises(ValueError):
        douglas_peucker(circle, np.array([0, 65]), -1.0)
