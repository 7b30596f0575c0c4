"""Samples lying on a line of lower level are left out (occlusion/coincident.py): what the rule
keeps and drops, and the compute pass leaving out exactly the samples NumPy does."""

import numpy as np
import pytest

from blueprint.vector.lines import CREASE
from blueprint.vector.occlusion import Samples, suppress_coincident


def _samples(lines: list[np.ndarray]) -> Samples:
    """Samples at the given pixel points, one polyline per array."""
    pixel = np.concatenate(lines)
    line = np.repeat(np.arange(len(lines)), [len(p) for p in lines])
    vertex = np.zeros(len(pixel), bool)
    ends = np.cumsum([len(p) for p in lines])
    vertex[ends - 1] = vertex[ends - [len(p) for p in lines]] = True
    n = len(pixel)
    return Samples(
        np.zeros((n, 3)),
        pixel,
        np.full((n, 2), -1),
        np.full(n, CREASE, np.uint8),
        np.full(n, -1, np.int64),
        line,
        vertex,
        np.ones(n, bool),
    )


def _line(start, angle_deg: float, length: float = 40.0) -> np.ndarray:
    t = np.arange(0.0, length, 1.0)
    direction = np.array([np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))])
    return np.asarray(start, float) + t[:, None] * direction


@pytest.mark.parametrize("use_gpu", [False, True], ids=["numpy", "gpu"])
def test_a_line_under_a_lower_level_line_is_left_out_only_when_close_and_parallel(renderer, use_gpu):
    top = _line((10.2, 20.3), 0.0)
    cases = {
        "close": (_line((10.2, 20.6), 0.0), True),  # 0.3 px away, parallel: drawn once
        "apart": (_line((10.2, 21.1), 0.0), False),  # 0.8 px away
        "crossing": (_line((12.0, 14.0), 20.0), False),  # 20 degrees off: crosses, does not lie on
    }
    for name, (under, dropped) in cases.items():
        samples = _samples([top, under])
        level = np.r_[np.zeros(len(top), np.int32), np.ones(len(under), np.int32)]
        got = suppress_coincident(samples, level, renderer=renderer if use_gpu else None)
        assert (got[: len(top)] == 0).all(), name  # the visible line stays
        inner = got[len(top) + 2 : -2]  # away from the ends, where the top line stops
        if dropped:
            assert (inner == -1).all(), name
        elif name == "apart":
            assert (inner == 1).all(), name
        else:
            assert (got[len(top) :] == 1).sum() >= len(under) - 3, name


@pytest.mark.parametrize("seed", [4, 5])
def test_the_compute_pass_leaves_out_the_samples_numpy_does(renderer, seed):
    """Crowded lines at distances and angles on both sides of the thresholds, some samples
    already left out, levels 0 to 3: the same answer for every sample."""
    rng = np.random.default_rng(seed)
    lines = []
    for _ in range(150):
        start = rng.uniform(0, 120, 2)
        angle = rng.uniform(0, 360)
        lines.append(_line(start, angle, rng.uniform(3, 30)))
        for _ in range(2):  # neighbours near 0.5 px and near 10 degrees
            offset = rng.choice([0.45, 0.5, 0.55]) * np.array(
                [-np.sin(np.radians(angle)), np.cos(np.radians(angle))]
            )
            lines.append(
                _line(start + offset, angle + rng.choice([-11.0, -9.0, 0.0, 9.0, 11.0]), rng.uniform(3, 30))
            )
    samples = _samples(lines)
    level = np.repeat(rng.integers(0, 4, len(lines)), [len(p) for p in lines]).astype(np.int32)
    level[rng.random(len(level)) < 0.05] = -1
    expected = suppress_coincident(samples, level)
    assert 0 < (expected[level >= 0] == -1).sum() < (level >= 0).sum() // 2
    np.testing.assert_array_equal(suppress_coincident(samples, level, renderer=renderer), expected)


def test_the_compute_pass_runs_in_the_renderers_own_context(renderer):
    from blueprint.gpu.device import Device

    top, under = _line((10.2, 20.3), 0.0), _line((10.2, 20.6), 0.0)
    samples = _samples([top, under])
    level = np.r_[np.zeros(len(top), np.int32), np.ones(len(under), np.int32)]
    with Device() as other:
        other.make_current()
        got = suppress_coincident(samples, level, renderer=renderer)
    renderer.make_current()
    np.testing.assert_array_equal(got, suppress_coincident(samples, level))
