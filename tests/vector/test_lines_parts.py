"""The broad phase between parts: the triangles that meet another part's box, on scenes of one
to many parts, against a brute-force reference, either way of testing (part by part or by words
of 64 parts), and in memory that follows the parts, not their square."""

import itertools
import tracemalloc

import numpy as np
import pytest

from blueprint.vector import lines
from blueprint.vector.lines import _by_words, _candidate_triangles


def _reference(lo, hi, part, parts, slack):
    """Triangle by part, every pair: the triangles whose box meets another part's widened box."""
    box_lo, box_hi = np.full((parts, 3), np.inf), np.full((parts, 3), -np.inf)
    np.minimum.at(box_lo, part, lo)
    np.maximum.at(box_hi, part, hi)
    meets = np.all((lo[:, None] <= box_hi[None] + slack) & (hi[:, None] >= box_lo[None] - slack), axis=2)
    meets[np.arange(len(lo)), part] = False
    return np.flatnonzero(meets.any(axis=1))


def _scene(rng, parts, n, kind):
    """Triangle boxes (lo, hi) of ``n`` triangles in ``parts`` parts (some left empty) and a slack:
    parts about places of their own, on a grid of whole numbers (boxes that touch exactly,
    gaps of exactly the slack), or one large part among small ones."""
    part = rng.integers(0, parts, n)
    if kind == "grid":
        corner = rng.integers(0, max(2, round(parts ** (1 / 3))), (parts, 3)).astype(float)
        lo = corner[part] + rng.integers(0, 2, (n, 3)) * 0.5
        hi = lo + rng.integers(0, 2, (n, 3)) * 0.5
        return lo, hi, part, float(rng.choice([0.0, 0.5]))
    centre = rng.uniform(0, 1.5 * parts ** (1 / 3), (parts, 3))[part] + rng.normal(0, 0.3, (n, 3))
    size = rng.uniform(0.0, 0.2, (n, 3))
    if kind == "large":
        wide = part == 0
        centre[wide] = rng.uniform(0, 1.5 * parts ** (1 / 3), (int(wide.sum()), 3))
        size[wide] = 0.0
    return centre - size, centre + size, part, float(rng.choice([0.0, 0.01, 0.05]))


@pytest.mark.parametrize("kind", ["places", "grid", "large"])
def test_candidate_triangles_match_every_pair_either_way(kind, monkeypatch):
    rng = np.random.default_rng({"places": 11, "grid": 12, "large": 13}[kind])
    for parts in (1, 2, 3, 17, 64, 65, 130, 300, 520):
        n = int(rng.integers(max(2, parts), 4 * parts + 200))
        lo, hi, part, slack = _scene(rng, parts, n, kind)
        extra = int(rng.integers(0, 3))  # parts that hold no triangle
        want = _reference(lo, hi, part, parts + extra, slack)
        found = []
        # the parts' pairs from the grid and all at once; every part tested part by part, every
        # part by words (in blocks of one, three and 64 words), and as the cost chooses
        for pairs, cost, block in itertools.product(
            (0, lines._DENSE_PAIRS), (10**9, -64, lines._WORD_SEARCHES), (1, 3, lines._BLOCK_WORDS)
        ):
            monkeypatch.setattr(lines, "_DENSE_PAIRS", pairs)
            monkeypatch.setattr(lines, "_WORD_SEARCHES", cost)
            monkeypatch.setattr(lines, "_BLOCK_WORDS", block)
            found.append(_candidate_triangles(lo, hi, part, parts + extra, slack).tolist())
        assert found == [want.tolist()] * 18, (kind, parts)


def test_candidate_triangles_of_touching_boxes_and_gaps_of_the_slack():
    # four unit boxes in a row, one part each: the first two touch, the next gap is 0.25
    lo = np.array([[0, 0, 0], [1, 0, 0], [2.25, 0, 0], [4, 0, 0]], float)
    hi = lo + 1.0
    part = np.arange(4)
    assert _candidate_triangles(lo, hi, part, 4, 0.0).tolist() == [0, 1]
    assert _candidate_triangles(lo, hi, part, 4, 0.25).tolist() == [0, 1, 2]
    assert _candidate_triangles(lo, hi, part, 4, 0.75).tolist() == [0, 1, 2, 3]


def test_the_cost_sends_parts_of_many_partners_a_word_to_words():
    # a word costs a test against a box, plus six tests a triangle for its searches
    partners, words = np.array([3, 7, 8, 64, 40, 40]), np.array([1, 1, 1, 1, 33, 34])
    assert _by_words(partners, words).tolist() == [False, False, True, True, True, False]


def test_candidate_triangles_of_many_parts_take_memory_by_parts_not_their_square():
    # 3 * 10^4 parts of two triangles in a row, each box overlapping its neighbours': a parts x
    # parts matrix of booleans alone would be 900 MB
    count = 30_000
    start = np.repeat(np.arange(count) * 0.9, 2)
    lo = np.stack([start, np.zeros_like(start), np.zeros_like(start)], axis=1)
    hi = lo + 1.0
    part = np.repeat(np.arange(count), 2)
    tracemalloc.start()
    got = _candidate_triangles(lo, hi, part, count, 0.0)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert got.tolist() == list(range(2 * count))
    assert peak < 40 * 2**20
