"""SVG path text built as bytes (``svg._number_table``) against the plain way of writing it:
each number's shortest decimal string, joined and shortened."""

from __future__ import annotations

import numpy as np
import pytest

from blueprint.vector import svg


def plain_path(points: np.ndarray, offsets: np.ndarray, factor: float, decimals: int) -> str:
    """M x y, then relative steps, each number through ``format_numbers``; snapped and
    thinned as ``path_data`` does."""
    unit = 10.0**decimals
    grid = np.rint(points * factor * unit).astype(np.int64)
    out = []
    for a, b in zip(offsets[:-1], offsets[1:], strict=True):
        kept = [grid[a]]
        for row in grid[a + 1 : b]:
            if (row != kept[-1]).any():
                kept.append(row)
        if len(kept) < 2:
            continue
        kept = np.array(kept)
        values = np.r_[kept[0], np.diff(kept, axis=0).reshape(-1)] / unit
        numbers = svg.format_numbers(values, decimals)
        out.append(f"M{numbers[0]} {numbers[1]}l" + " ".join(numbers[2:]))
    text = "".join(out)
    return text.replace(" -", "-").replace("-0.", "-.").replace(" 0.", " .").replace("l0.", "l.")


@pytest.mark.parametrize("decimals", [0, 1, 2, 3, 4, 5])
@pytest.mark.parametrize("spread", [0.05, 5.0, 500.0])
def test_path_text_equals_the_plain_text(decimals, spread):
    rng = np.random.default_rng(int(spread * 10) + decimals)
    for _ in range(20):
        n = int(rng.integers(2, 600))
        points = rng.normal(0, spread, (n, 2)) + rng.normal(0, 3)
        points[::3] = np.round(points[::3], 1)  # repeated and round numbers too
        points[5::7] = points[4::7][: len(points[5::7])]
        offsets = np.unique(np.r_[0, rng.integers(0, n, int(rng.integers(0, 12))), n])
        for factor in (1.0, 0.2645):
            assert svg.path_data(points, offsets, factor, decimals) == plain_path(
                points, offsets, factor, decimals
            )


def test_known_text():
    """Half a tick rounds to even (12.5 to 12); only a start after M keeps its zero."""
    points = np.array([[0.5, 0.0], [0.0, 1.25], [-3.0, 1.25], [10.0, 0.0]])
    assert svg.path_data(points, np.array([0, 4]), 1.0, 1) == "M0.5 0l-.5 1.2-3 0 13-1.2"
    assert svg.path_data(points, np.array([0, 4]), 1.0, 2) == "M0.5 0l-.5 1.25-3 0 13-1.25"


@pytest.mark.parametrize("decimals", [0, 2, 5])
def test_paths_of_groups_are_each_groups_own_path(decimals):
    """One pass over runs of polylines writes each run as ``plain_path`` writes it alone:
    runs that lose every polyline, runs of none and runs of many."""
    rng = np.random.default_rng(decimals)
    n = 900
    points = rng.normal(0, 20.0, (n, 2))
    points[100:130] = points[100]  # polylines that shrink to a point
    offsets = np.unique(np.r_[0, rng.integers(0, n, 120), 100, 110, 120, 130, n])
    polylines = len(offsets) - 1
    groups = np.unique(np.r_[0, rng.integers(0, polylines, 30), polylines])
    groups = np.sort(np.r_[groups, groups[3]])  # a run of no polylines
    got = svg.paths_data(points, offsets, groups, 1.0, decimals)
    assert len(got) == len(groups) - 1
    for text, a, b in zip(got, groups[:-1], groups[1:], strict=True):
        sub = offsets[a : b + 1]
        assert text == plain_path(points[sub[0] : sub[-1]], sub - sub[0], 1.0, decimals)
    assert "" in got


@pytest.mark.parametrize("decimals", [0, 1, 2, 3, 4])
def test_byte_text_equals_string_text_on_few_numbers(decimals):
    """``_number_table`` directly, on few numbers."""
    rng = np.random.default_rng(decimals)
    ticks = rng.integers(-(10**6), 10**6, 40) // rng.integers(1, 10**4, 40)
    lead = np.frombuffer(b"M l" + b" " * 37, np.uint8).copy()
    strings = svg.format_numbers(ticks / 10.0**decimals, decimals)
    plain = svg._shorten("".join(chr(c) + t for c, t in zip(lead.tolist(), strings, strict=True)))
    table, mask = svg._number_table(ticks, lead, decimals)
    assert table[mask].tobytes().decode("ascii") == plain
