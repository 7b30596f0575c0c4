"""Chains walked from paired half-ends (``chain.chain_order``): the order of a walk, half-end
by half-end, against a walk in plain Python."""

import numpy as np
import pytest

from blueprint.vector.chain import chain_order


def _walked(partner: np.ndarray) -> tuple[list[int], list[bool], list[int]]:
    """The reference: pieces paired at neither end, then every open chain from its lower free
    half-end, then every loop from the start of its lowest piece, a step at a time."""
    count = len(partner) // 2
    alone = [partner[2 * s] < 0 and partner[2 * s + 1] < 0 for s in range(count)]
    visited = list(alone)
    piece = [s for s in range(count) if alone[s]]
    reverse = [False] * len(piece)
    lengths = [1] * len(piece)

    def walk(h: int) -> None:
        steps = 0
        while h >= 0 and not visited[h >> 1]:
            visited[h >> 1] = True
            piece.append(h >> 1)
            reverse.append(bool(h & 1))
            steps += 1
            h = int(partner[h ^ 1])
        lengths.append(steps)

    for h in range(2 * count):
        if partner[h] < 0 and not alone[h >> 1] and not visited[h >> 1]:
            walk(h)
    for s in range(count):
        if not visited[s]:
            walk(2 * s)
    return piece, reverse, lengths


def _paired(rng, count: int, fraction: float) -> np.ndarray:
    """Random half-ends paired: open chains, loops, pieces paired with themselves."""
    ends = rng.permutation(2 * count)
    pairs = int(fraction * count)
    partner = np.full(2 * count, -1, np.int64)
    a, b = ends[:pairs], ends[pairs : 2 * pairs]
    partner[a], partner[b] = b, a
    return partner


@pytest.mark.parametrize("fraction", [0.0, 0.3, 0.8, 1.0])
def test_chains_are_walked_as_one_step_at_a_time(fraction):
    rng = np.random.default_rng(7)
    loops = opens = 0
    for _ in range(60):
        partner = _paired(rng, int(rng.integers(1, 80)), fraction)
        piece, reverse, lengths = chain_order(partner)
        want = _walked(partner)
        assert piece.tolist() == want[0]
        assert reverse.tolist() == want[1]
        assert lengths.tolist() == want[2]
        assert piece.dtype == lengths.dtype == np.int64 and reverse.dtype == bool
        closed = partner[2 * piece[np.cumsum(lengths) - lengths]] >= 0
        loops += int(closed.sum())
        opens += int((~closed & (lengths > 1)).sum())
    # every half-end paired leaves loops alone
    assert fraction == 0.0 or (loops > 0 if fraction == 1.0 else opens > 0)


def test_long_chains_and_a_long_loop():
    """One open chain of 5 000 pieces walked from its free end (some pieces backwards) and a
    loop of 5 000 from its lowest piece."""
    count = 5_000
    partner = np.full(4 * count, -1, np.int64)
    # open chain: piece s's end meets piece s + 1's end (every other piece walked backwards)
    s = np.arange(count - 1)
    a = np.where(s % 2 == 0, 2 * s + 1, 2 * s)
    b = np.where(s % 2 == 0, 2 * s + 3, 2 * s + 2)
    partner[a], partner[b] = b, a
    # a loop through pieces count .. 2 count - 1 in a shuffled order
    ring = np.random.default_rng(3).permutation(np.arange(count, 2 * count))
    nxt = np.roll(ring, -1)
    partner[2 * ring + 1], partner[2 * nxt] = 2 * nxt, 2 * ring + 1
    piece, reverse, lengths = chain_order(partner)
    want = _walked(partner)
    assert lengths.tolist() == want[2] == [count, count]
    assert piece.tolist() == want[0] and reverse.tolist() == want[1]
    assert piece[count] == count and not reverse[count]
