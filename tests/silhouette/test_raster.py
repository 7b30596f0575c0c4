"""Anti-aliased segment drawing: exact coverage on hand-placed lines."""

import numpy as np
import pytest

import blueprint.silhouette.raster as raster
from blueprint.silhouette import draw_segments


def brute_force(segments, width, height, line_width=1.0):
    """Distance from every pixel centre to every segment, no clipping, chunking or pieces."""
    ys, xs = np.mgrid[0:height, 0:width] + 0.5
    centres = np.stack([xs, ys], axis=-1)[:, :, None, :]
    a, d = segments[:, 0], segments[:, 1] - segments[:, 0]
    t = np.clip(((centres - a) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-300), 0, 1)
    dist = np.linalg.norm(centres - a - t[..., None] * d, axis=-1)
    return np.clip(line_width / 2 + 0.5 - dist, 0, 1).max(axis=-1, initial=0.0)


def test_horizontal_line_on_pixel_centres():
    image = draw_segments(np.array([[[5.0, 10.5], [30.0, 10.5]]]), 40, 20)
    assert image.shape == (20, 40) and image.dtype == np.float32
    np.testing.assert_array_equal(image[10, 5:30], 1.0)
    np.testing.assert_array_equal(image[[8, 9, 11, 12], 5:30], 0.0)
    # Round end caps: the pixel centred at x = 4.5 is half a pixel from the start point.
    assert image[10, 4] == 0.5 and image[10, 3] == 0.0


def test_line_between_rows_splits_evenly_and_wide_lines_are_solid():
    image = draw_segments(np.array([[[5.0, 10.0], [30.0, 10.0]]]), 40, 20)
    np.testing.assert_array_equal(image[[9, 10], 15], [0.5, 0.5])
    np.testing.assert_array_equal(image[[8, 11], 15], [0.0, 0.0])
    image = draw_segments(np.array([[[5.0, 10.75], [30.0, 10.75]]]), 40, 20)
    np.testing.assert_array_equal(image[9:13, 15], [0.0, 0.75, 0.25, 0.0])
    wide = draw_segments(np.array([[[5.0, 10.5], [30.0, 10.5]]]), 40, 20, line_width=3.0)
    np.testing.assert_array_equal(wide[8:13, 15], [0.0, 1.0, 1.0, 1.0, 0.0])


def test_drawing_is_mirror_symmetric_and_direction_free():
    rng = np.random.default_rng(1)
    segments = rng.uniform([0, 0], [64, 48], size=(40, 2, 2))
    image = draw_segments(segments, 64, 48, line_width=1.5)
    mirrored = segments * [-1, 1] + [64, 0]
    np.testing.assert_allclose(draw_segments(mirrored, 64, 48, 1.5), image[:, ::-1], atol=1e-6)
    np.testing.assert_allclose(draw_segments(segments[:, ::-1], 64, 48, 1.5), image, atol=1e-6)


def test_diagonal_ink_is_length_times_width_plus_round_caps():
    segment = np.array([[[10.3, 12.1], [80.7, 71.9]]])
    length = np.linalg.norm(segment[0, 1] - segment[0, 0])
    for line_width, caps in [(1.0, np.pi / 3), (3.0, 2 * np.pi * (0.5 + 2 / 3))]:
        # caps: one disc's worth of the radial coverage profile, integrated.
        ink = draw_segments(segment, 100, 100, line_width).sum(dtype=np.float64)
        assert abs(ink - (length * line_width + caps)) < 0.01 * length * line_width


def test_matches_brute_force_with_clipping_and_chunking(monkeypatch):
    rng = np.random.default_rng(2)
    segments = rng.uniform([-30, -30], [90, 70], size=(60, 2, 2))
    segments[0] = [[-1e6, 20.25], [1e6, 20.25]]  # far beyond the image on both sides
    segments[1] = [[12.5, 7.5], [12.5, 7.5]]  # a single point
    expected = brute_force(segments, 64, 48, line_width=2.0)
    np.testing.assert_allclose(draw_segments(segments, 64, 48, 2.0), expected, atol=1e-6)
    monkeypatch.setattr(raster, "_CHUNK_PIXELS", 97)
    np.testing.assert_allclose(draw_segments(segments, 64, 48, 2.0), expected, atol=1e-6)


def test_overlaps_take_the_maximum_and_intensity_scales():
    cross = np.array([[[0.0, 10.5], [20.0, 10.5]], [[10.5, 0.0], [10.5, 20.0]]])
    image = draw_segments(cross, 20, 20, intensity=np.array([1.0, 0.25]))
    assert image[10, 10] == 1.0
    assert image[2, 10] == 0.25
    assert draw_segments(cross, 20, 20, intensity=0.5).max() == 0.5


def test_empty_and_outside_segments_give_a_blank_image():
    assert not draw_segments(np.zeros((0, 2, 2)), 8, 6).any()
    assert not draw_segments(np.array([[[-5.0, -5.0], [-1.1, 20.0]]]), 8, 6).any()


@pytest.mark.parametrize(
    ("segments", "kwargs"),
    [
        (np.zeros((3, 2, 3)), {}),
        (np.array([[[0.0, np.inf], [1.0, 1.0]]]), {}),
        (np.zeros((1, 2, 2)), {"width": 0}),
        (np.zeros((1, 2, 2)), {"line_width": 0.0}),
        (np.zeros((1, 2, 2)), {"intensity": 1.5}),
        (np.zeros((2, 2, 2)), {"intensity": np.ones(3)}),
    ],
)
def test_rejects_bad_arguments(segments, kwargs):
    with pytest.raises(ValueError):
        draw_segments(segments, **({"width": 8, "height": 6} | kwargs))
