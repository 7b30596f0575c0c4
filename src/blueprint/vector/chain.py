"""Chaining pieces of line end to end: the graph walk shared by 3D segments (``lines``) and by
the 2D pieces of one occlusion level (``chain_pieces``).

A piece ``s`` has two half-ends, ``2 s`` (its start) and ``2 s + 1`` (its end). Half-ends at
one node are paired: two at a node always, and at a junction of more the straightest pairs
first. A chain walks from piece to piece through paired half-ends.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from blueprint import parallel
from blueprint.sorting import renumbered, row_numbers, stable_argsort

__all__ = ["chain_order", "chain_pieces", "pair_ends", "walked"]


def pair_ends(
    node: np.ndarray,
    leaving: np.ndarray | Callable[[np.ndarray], np.ndarray],
    min_cos: float,
    order: np.ndarray | None = None,
) -> np.ndarray:
    """Partner of every half-end (-1 where the chain stops there).

    Parameters
    ----------
    node : (2 n,) int64
        Node of each half-end; half-ends at one node meet there.
    leaving : (2 n, d) float64, or a function of (K,) half-ends giving their (K, d) rows
        Unit direction in which each piece leaves its node through that half-end (only those
        at junctions are read).
    min_cos : float
        At junctions of three or more, two half-ends pair only if the line turns between them
        by an angle whose cosine is at least this (1: straight on only, -1: any turn).
    order : (2 n,) int64, optional
        ``stable_argsort(node)``, where the caller has it already.

    Returns
    -------
    (2 n,) int64
    """
    partner = np.full(len(node), -1, np.int64)
    if len(node) == 0:
        return partner
    degree = np.bincount(node)
    if order is None:
        order = stable_argsort(node)
    starts = np.cumsum(degree) - degree
    # the half-ends at nodes of two, paired: gathered and put a block a thread (most of them)
    first = parallel.taken(starts, parallel.flatnonzero(degree == 2))
    a = parallel.taken(order, first)
    first += 1
    b = parallel.taken(order, first)
    del first
    parallel.put(partner, a, b)
    parallel.put(partner, b, a)
    junction = np.flatnonzero(degree > 2)
    if len(junction) == 0:
        return partner
    size = degree[junction]
    # every pair (i < j) of half-ends at every junction
    first_i, first_j = [], []
    # the sizes present, from a count (np.unique without indices imports numpy.ma, slow to import)
    for k in np.flatnonzero(np.bincount(size)).tolist():
        i, j = np.triu_indices(k, 1)
        base = starts[junction[size == k]]
        first_i.append((base[:, None] + i[None]).reshape(-1))
        first_j.append((base[:, None] + j[None]).reshape(-1))
    ha, hb = order[np.concatenate(first_i)], order[np.concatenate(first_j)]
    # straight on: the two pieces leave the node in opposite directions
    direction = leaving if callable(leaving) else leaving.__getitem__
    straight = np.empty(len(ha))

    def turns(lo: int, hi: int) -> None:
        straight[lo:hi] = -np.einsum("ij,ij->i", direction(ha[lo:hi]), direction(hb[lo:hi]))

    parallel.run(parallel.stepped(turns), len(ha))
    ok = straight >= min_cos
    rank = np.argsort(-straight[ok], kind="stable")
    x, y = ha[ok][rank], hb[ok][rank]
    # the straightest pairs first: a pair is taken where it is the first left at both its
    # half-ends, the pairs at those half-ends dropped, round after round (the pairs a walk
    # through them in order takes)
    first = np.empty(len(node), np.int64)
    while len(x):
        at = np.arange(len(x))
        first[x] = first[y] = len(x)
        np.minimum.at(first, x, at)
        np.minimum.at(first, y, at)
        taken = (first[x] == at) & (first[y] == at)
        partner[x[taken]], partner[y[taken]] = y[taken], x[taken]
        free = (partner[x] < 0) & (partner[y] < 0)
        x, y = x[free], y[free]
    return partner


# Walkers left when the rest of their walks is taken a step at a time in Python: a round of
# array operations costs microseconds however few walk on, a step in Python a fraction of one.
_FEW = 64


def chain_order(partner: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Walk the pieces into chains: pieces paired at neither end first, then open chains from
    their free ends, then closed loops.

    Returns
    -------
    piece : (n,) int64
        Pieces in walking order.
    reverse : (n,) bool
        Whether each piece is walked from its end to its start.
    lengths : (C,) int64
        Pieces per chain, in order.
    """
    # pieces paired at neither end are chains of their own, found without walking
    alone = (partner[0::2] < 0) & (partner[1::2] < 0)
    # entering a piece through half-end h, the walk leaves it through h ^ 1 for that one's partner
    onward = partner.reshape(-1, 2)[:, ::-1].reshape(-1)
    # an open chain from the lower of its two free half-ends to the other: walked from both,
    # the walk kept where it ends at the higher one
    free = np.flatnonzero((partner < 0) & ~np.repeat(alone, 2))
    walked, lengths = _walks(free, onward, closed=False)
    kept = free < (walked[np.cumsum(lengths) - 1] ^ 1)
    opened, open_lengths = walked[np.repeat(kept, lengths)], lengths[kept]
    # what is left lies on closed loops, each walked from its lowest piece's start: the least
    # half-end of its loop, and less than the least of the loop walked the other way
    off = alone.copy()
    off[opened >> 1] = True
    starts = _loop_starts(onward, np.flatnonzero(np.repeat(~off, 2)))
    loops, loop_lengths = _walks(starts, onward, closed=True)
    flat = np.concatenate([opened, loops])
    single = np.flatnonzero(alone)
    return (
        np.concatenate([single, flat >> 1]),
        np.concatenate([np.zeros(len(single), bool), (flat & 1).astype(bool)]),
        np.concatenate([np.ones(len(single), np.int64), open_lengths, loop_lengths]),
    )


def _loop_starts(onward: np.ndarray, looped: np.ndarray) -> np.ndarray:
    """The least half-end of each loop of ``looped`` (ascending half-ends that lie on loops of
    ``onward``, both ways round) that is less than the least of its loop walked the other way,
    ascending. Each one's least by doubling: after k rounds, every half-end holds the least of
    the next 2^k on its loop; once a round changes nothing, the least of the whole loop."""
    number = np.empty(len(onward), np.int64)
    number[looped] = np.arange(len(looped))  # ascending: numbers order as half-ends do
    least, ahead = np.arange(len(looped)), number[onward[looped]]
    while True:
        lower = parallel.taken(least, ahead)
        np.minimum(lower, least, out=lower)
        if np.array_equal(lower, least):
            break
        least, ahead = lower, parallel.taken(ahead, ahead)
    own = least == np.arange(len(looped))
    return looped[own & (least < least[number[looped ^ 1]])]


def _walks(starts: np.ndarray, onward: np.ndarray, closed: bool) -> tuple[np.ndarray, np.ndarray]:
    """The half-ends walked from each of ``starts`` along ``onward`` to where it gives -1, or
    with ``closed`` back to the start: (half-ends, walk after walk in the order of ``starts``;
    each walk's length). Every walk takes a step a round, as arrays, until few are left."""
    lengths = np.zeros(len(starts), np.int64)
    rounds = []
    active, at = np.arange(len(starts)), starts
    while len(active) > _FEW:
        rounds.append((active, at))
        lengths[active] += 1
        at = onward[at]
        on = at != starts[active] if closed else at >= 0
        active, at = active[on], at[on]
    tails = []
    step = onward.item
    for walker, h in zip(active.tolist(), at.tolist(), strict=True):
        first, tail = int(starts[walker]), []
        while h >= 0 and not (closed and h == first and tail):
            tail.append(h)
            h = step(h)
        lengths[walker] += len(tail)
        tails.append((walker, tail))
    offsets = np.cumsum(lengths) - lengths
    out = np.empty(int(lengths.sum()), np.int64)
    for r, (ids, at) in enumerate(rounds):
        out[offsets[ids] + r] = at
    for walker, tail in tails:
        end = offsets[walker] + lengths[walker]
        out[end - len(tail) : end] = tail
    return out, lengths


def chain_pieces(
    points: np.ndarray, offsets: np.ndarray, key: np.ndarray, quantum: float = 1e-3
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Chain 2D polylines of one key (part and occlusion level) that meet end to end.

    Pieces of one level on lines that meet at a corner or a junction of the model's edges become
    one polyline, turning there (at a junction the straightest pairs continue): a corner is
    drawn as a join, not as two line ends, and no short edge between two junctions stands
    alone. Ends meet when they round to the same multiple of ``quantum`` (pixels).

    Parameters
    ----------
    points : (N, 2) float64
    offsets : (P + 1,) int64
        Polyline ``i`` is ``points[offsets[i]:offsets[i + 1]]``, at least two points each.
    key : (P,) int64
        Only polylines of one key chain.

    Returns
    -------
    points, offsets : the chained polylines.
    piece : (P,) int64
        The pieces in walking order, chain after chain (a chain has its first piece's key).
    reverse : (P,) bool
        Whether each piece is walked from its end to its start.
    lengths : (C,) int64
        Pieces per chain.
    """
    count = len(offsets) - 1
    if count < 2:
        return points, offsets, np.arange(count), np.zeros(count, bool), np.ones(count, np.int64)
    first_point, last_point = offsets[:-1], offsets[1:] - 1
    ends = np.stack([points[first_point], points[last_point]], axis=1).reshape(-1, 2)
    cell = np.round(ends / quantum).astype(np.int64)
    rows = np.column_stack([np.repeat(key, 2), cell])
    low = rows.min(axis=0)
    span = rows.max(axis=0) - low + 1
    if float(span[0]) * float(span[1]) * float(span[2]) < 2.0**62:
        # the rows packed in their order into one integer: a 1-D unique, numbered alike
        packed = ((rows[:, 0] - low[0]) * span[1] + (rows[:, 1] - low[1])) * span[2] + (rows[:, 2] - low[2])
        node = renumbered(packed)[1]
    else:
        node = row_numbers(rows)
    inward = np.stack([points[first_point + 1], points[last_point - 1]], axis=1).reshape(-1, 2)
    leaving = inward - ends
    leaving /= np.maximum(np.linalg.norm(leaving, axis=1), 1e-300)[:, None]
    piece, reverse, lengths = chain_order(pair_ends(node, leaving, -1.0))
    # each piece's points in walking order; a piece after the first drops its first point,
    # which is the previous piece's last
    index, size, within = walked(offsets, piece, reverse)
    chain_start = np.cumsum(lengths) - lengths
    is_first = np.zeros(len(piece), bool)
    is_first[chain_start] = True
    keep = (within > 0) | np.repeat(is_first, size)
    out = points[index[keep]]
    kept_per_piece = size - (~is_first).astype(np.int64)
    per_chain = np.add.reduceat(kept_per_piece, chain_start) if len(piece) else np.zeros(0, np.int64)
    return out, np.r_[0, np.cumsum(per_chain)].astype(np.int64), piece, reverse, lengths


def walked(offsets: np.ndarray, piece: np.ndarray, reverse: np.ndarray):
    """The rows of runs ``piece`` (run ``i`` is rows ``offsets[i]:offsets[i + 1]``), each
    walked backwards where ``reverse``, one after another: (rows, each walked run's size, each
    row's place within its run)."""
    size = np.diff(offsets)[piece]
    within = np.arange(int(size.sum())) - np.repeat(np.cumsum(size) - size, size)
    index = np.where(
        np.repeat(reverse, size),
        np.repeat(offsets[1:][piece] - 1, size) - within,
        np.repeat(offsets[:-1][piece], size) + within,
    )
    return index, size, within
