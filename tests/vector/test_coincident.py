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


def _brute_force_drop(samples: Samples, level: np.ndarray) -> np.ndarray:
    """The rule without bins or budget: every live sample against every covering stretch of
    another line ranked below it that starts in its pixel or one beside it, in the search's
    single-precision arithmetic."""
    from blueprint.vector.occlusion.coincident import _Search

    live = np.flatnonzero(level >= 0)
    s = _Search.of(samples, level, live)
    source = s.source
    # the live samples' pixels and directions (``looks``), the covering stretches in the
    # search's order, their ranks from their keys
    rel = s.looks[:, None, :2] - s.pixel32[None]
    f = s.forward32[None]
    t = np.clip((rel[..., 0] * f[..., 0] + rel[..., 1] * f[..., 1]) * s.inv_length2[None], 0, 1)
    gx, gy = rel[..., 0] - t * f[..., 0], rel[..., 1] - t * f[..., 1]
    d, u = s.looks[:, None, 2:], s.unit32[None]
    turn = np.abs(d[..., 0] * u[..., 1] - d[..., 1] * u[..., 0])
    sin_limit = np.sin(np.radians(10.0))
    hit = (gx * gx + gy * gy <= np.float32(0.25)) & (turn <= sin_limit)
    source_rank = s.src_key % s.ranks
    hit &= (source_rank[None] < s.live_rank[:, None]) & (s.line[source][None] != s.line[live][:, None])
    cells = np.floor(samples.pixel).astype(np.int64)
    hit &= (np.abs(cells[live][:, None] - cells[source][None]) <= 1).all(axis=2)
    out = level.copy()
    out[live[hit.any(axis=1)]] = -1
    return out


@pytest.mark.parametrize("use_gpu", [False, True], ids=["numpy", "gpu"])
def test_the_bounded_search_leaves_out_what_every_pair_tested_does(renderer, use_gpu):
    """Crowded lines at all angles, near the distance and angle limits: the search by cell,
    direction and budget gives the answer of testing every pair."""
    rng = np.random.default_rng(7)
    lines = []
    for _ in range(120):
        start, angle = rng.uniform(0, 60, 2), rng.uniform(0, 360)
        lines.append(_line(start, angle, rng.uniform(2, 20)))
        normal = np.array([-np.sin(np.radians(angle)), np.cos(np.radians(angle))])
        for _ in range(2):
            turned = angle + rng.choice([-10.5, -9.5, 0.0, 9.5, 10.5, 179.0])
            lines.append(_line(start + rng.choice([0.3, 0.49, 0.51]) * normal, turned, rng.uniform(2, 20)))
    samples = _samples(lines)
    level = np.repeat(rng.integers(0, 3, len(lines)), [len(p) for p in lines]).astype(np.int32)
    expected = _brute_force_drop(samples, level)
    assert 0 < (expected[level >= 0] == -1).sum() < (level >= 0).sum() // 2
    got = suppress_coincident(samples, level, renderer=renderer if use_gpu else None)
    np.testing.assert_array_equal(got, expected)


def test_a_crowded_pixel_costs_a_sample_its_budget_and_no_more(renderer):
    """More stretches of its direction in a sample's own pixel than its budget, none of them
    within reach, and the one that reaches it in the pixel beside: the sample looks at its
    budget's worth and stays, where testing every pair leaves it out; NumPy and the compute pass
    agree, and nothing is left out that every pair tested keeps."""
    from blueprint.vector.occlusion.coincident import BUDGET

    crowd = [np.array([[10.55 + 0.3 * k / BUDGET, 20.9], [10.85, 20.9]]) for k in range(BUDGET + 100)]
    reach = np.array([[9.2, 20.25], [9.95, 20.25]])  # 0.2 px above the sample, the pixel before
    sample = np.array([[10.05, 20.05], [10.3, 20.05]])
    lines = [*crowd, reach, sample]
    samples = _samples(lines)
    level = np.r_[np.zeros(2 * len(crowd) + 2, np.int32), np.ones(2, np.int32)]
    exact = _brute_force_drop(samples, level)
    assert (exact[-2:] == -1).all()
    cpu = suppress_coincident(samples, level)
    np.testing.assert_array_equal(suppress_coincident(samples, level, renderer=renderer), cpu)
    assert cpu[-2] == 1  # the budget spent in its own crowded pixel
    assert ((cpu == -1) <= (exact == -1)).all()
