"""Sorting integer keys the fast way with NumPy's answers.

``np.unique(..., return_index=True)`` and ``np.argsort(kind="stable")`` merge-sort; a sort of
distinct keys (each key shifted left, its position in the low bits) is faster and orders them
the same way, where those keys fit in 63 bits; sorting them as values, the positions read back
from their low bits, is faster again than an argsort (NumPy sorts integers with SIMD, and their
argsort without, short of AVX-512). Keys of a range not much wider than their count (vertex
ids, component ids) need no sort at all for ``unique_first``: a table over the range marks
them, faster again.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from blueprint import parallel, settings

__all__ = [
    "SortedKeys",
    "bucketed",
    "dense_ranks",
    "grouped",
    "row_numbers",
    "sorted_ranks",
    "sorted_with_order",
    "stable_argsort",
    "unique_first",
]

# Indices packed into keys at a time (``sorted_with_order``).
_BLOCK = 1 << 20
# Buckets ``_by_buckets`` cuts the keys into, at most (a byte's values), and at least.
_MAX_BUCKETS = 256
_FEWEST_BUCKETS = 32
# unique_first counts over the keys' range, not sorting, up to this many times their number.
_TABLE_PER_KEY = 4


def stable_argsort(key: np.ndarray) -> np.ndarray:
    """``np.argsort(key, kind="stable")`` of a 1-D integer array."""
    n = len(key)
    if n == 0:
        return np.zeros(0, np.int64)
    low, high = int(key.min()), int(key.max())
    if high - low < 1 << 16:
        # keys of 16 bits or fewer: NumPy's stable argsort of them is a radix sort, linear
        narrow = np.uint8 if high - low < 1 << 8 else np.uint16
        return np.argsort((key - low).astype(narrow), kind="stable")
    bits = n.bit_length()
    if (float(high) - float(low) + 1.0) * 2.0**bits < 2.0**62 and high < 1 << 63:
        packed = _packed(key, low, bits, np.empty(n, np.int64))
        parallel.sort(packed)
        parallel.run(partial(_positions, packed, bits), n)
        return packed
    found = _by_buckets(key, low, high)
    return np.argsort(key, kind="stable") if found is None else found[1]


def sorted_with_order(key: np.ndarray, overwrite: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``(key[order], order)`` with ``order = stable_argsort(key)`` of a 1-D integer array, as
    int64 arrays: both read off one sort of packed keys where they fit, without a gather.
    ``overwrite`` lets an int64 ``key`` hold the packed keys."""
    n = len(key)
    if n == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    low, high = int(key.min()), int(key.max())
    bits = n.bit_length()
    if (float(high) - float(low) + 1.0) * 2.0**bits < 2.0**62 and high < 1 << 63:
        packed = _packed(
            key, low, bits, key if overwrite and key.dtype == np.int64 else np.empty(n, np.int64)
        )
        parallel.sort(packed)
        ordered = np.empty(n, np.int64)

        def unpack(lo: int, hi: int) -> None:
            np.right_shift(packed[lo:hi], bits, out=ordered[lo:hi])
            ordered[lo:hi] += low
            _positions(packed, bits, lo, hi)

        parallel.run(unpack, n)
        return ordered, packed
    found = _by_buckets(key, low, high)
    if found is not None:
        return found
    order = np.argsort(key, kind="stable")
    return key[order].astype(np.int64), order


def _packed(key: np.ndarray, low: int, bits: int, out: np.ndarray) -> np.ndarray:
    """``out`` (int64, may be ``key`` itself): each key less ``low`` shifted left by ``bits``,
    its position in the low bits (keys that sort as the keys do, in a stable order), a block
    a thread."""
    copied = out is not key

    def pack(lo: int, hi: int) -> None:
        block = out[lo:hi]
        if copied:
            block[:] = key[lo:hi]
        block -= low
        block <<= bits
        for start in range(lo, hi, _BLOCK):
            out[start : min(start + _BLOCK, hi)] |= np.arange(start, min(start + _BLOCK, hi))

    parallel.run(pack, len(key))
    return out


def _positions(packed: np.ndarray, bits: int, lo: int, hi: int) -> None:
    """``packed[lo:hi]`` (``_packed``) to the positions in their low ``bits``, in place."""
    packed[lo:hi] &= (1 << bits) - 1


class SortedKeys:
    """The keys of a 1-D int64 array in stable order, read by position: ``keys(at)`` the
    sorted keys at positions ``at`` (an index array or a slice), ``order(at)`` where they were
    (``stable_argsort``). Held in one array where the keys packed with their positions fit in
    63 bits (the keys' own array, sorted in place: the caller's array is then this one's),
    else as the keys and their order: never the sorted keys beside both."""

    def __init__(self, key: np.ndarray) -> None:
        key = np.asarray(key, np.int64)
        n = len(key)
        self.length = n
        self._packed = self._key = self._order = None
        if n == 0:
            self._key, self._order = key, np.zeros(0, np.int64)
            return
        low, high = int(key.min()), int(key.max())
        bits = n.bit_length()
        if (float(high) - float(low) + 1.0) * 2.0**bits < 2.0**62 and high < 1 << 63:
            self._low, self._bits = low, bits
            parallel.sort(_packed(key, low, bits, key))
            self._packed = key
            return
        found = _by_buckets(key, low, high, keys=False)
        self._key = key
        self._order = np.argsort(key, kind="stable") if found is None else found[1]

    def order(self, at) -> np.ndarray:
        """(N,) int64: where the sorted keys at ``at`` were in the keys."""
        if self._packed is None:
            return self._order[at]
        return self._packed[at] & ((1 << self._bits) - 1)

    def keys(self, at) -> np.ndarray:
        """(N,) int64: the sorted keys at ``at``."""
        if self._packed is None:
            return self._key[self._order[at]]
        found = self._packed[at] >> self._bits
        found += self._low
        return found


def _by_buckets(
    key: np.ndarray, low: int, high: int, keys: bool = True
) -> tuple[np.ndarray | None, np.ndarray] | None:
    """``sorted_with_order`` of keys too wide to sort packed with their positions: the keys
    split by the top bits of ``key - low`` into at most ``_MAX_BUCKETS`` buckets (a stable
    counting sort), then each bucket's keys, less those bits, packed with their positions in
    it and sorted, the buckets side by side; where a bucket's still do not fit, each bucket's
    keys sorted by a stable argsort (None on one thread). Without ``keys``, the order alone
    (the sorted keys None)."""
    n = len(key)
    span = (high - low).bit_length()
    if span > 62 or high >= 1 << 63:
        return None  # not held by int64 keys
    # some four buckets a thread, and at least ``_FEWEST_BUCKETS``: a bucket's sort holds
    # temporaries of its keys
    fewest = max(
        _FEWEST_BUCKETS.bit_length() - 1,
        -(-(span + n.bit_length() - 62) // 2),
        (4 * settings.THREADS - 1).bit_length(),
    )
    for power in range(fewest, _MAX_BUCKETS.bit_length()):
        shift = max(span - power, 0)
        bucket, per_block = _counted(key, low, shift, 1 << power)
        counts = per_block.sum(axis=0)
        bits = int(counts.max()).bit_length()
        if shift + bits <= 62:
            break
    else:
        if settings.THREADS == 1:
            return None  # one stable sort of them all
        # too wide to pack with their positions in the most buckets: each bucket's keys are
        # sorted as they are, the buckets still side by side
        if fewest >= _MAX_BUCKETS.bit_length():  # (else the loop's last count is of the most)
            shift = max(span - (_MAX_BUCKETS.bit_length() - 1), 0)
            bucket, per_block = _counted(key, low, shift, _MAX_BUCKETS)
            counts = per_block.sum(axis=0)
        bits = None
    # held through the buckets' sorts
    order = _bucket_order(bucket, per_block, _positions_type(n))
    del bucket
    ends = np.cumsum(counts)
    ordered, positions = np.empty(n, np.int64) if keys else None, np.empty(n, np.int64)

    def sort_buckets(first: int, last: int) -> None:
        for b in range(first, last):
            start, stop = int(ends[b] - counts[b]), int(ends[b])
            at = order[start:stop]
            packed = np.asarray(key[at], np.int64)
            if bits is None:
                by_key = np.argsort(packed, kind="stable")
                positions[start:stop] = at[by_key]
                if keys:
                    ordered[start:stop] = packed[by_key]
                continue
            packed -= low + (b << shift)
            packed <<= bits
            packed |= np.arange(stop - start)
            packed.sort()
            positions[start:stop] = at[packed & ((1 << bits) - 1)]
            if keys:
                packed >>= bits
                packed += low + (b << shift)
                ordered[start:stop] = packed

    parallel.each(lambda run: sort_buckets(*run), _balanced(counts, settings.THREADS))
    return ordered, positions


def _balanced(counts: np.ndarray, parts: int) -> list[tuple[int, int]]:
    """Runs of consecutive buckets of ``counts`` keys each holding about as many keys, at most
    ``parts`` of them: keys spread over less than their buckets' range (the top buckets of a
    power of two empty) would leave the threads of the top buckets idle."""
    ends = np.cumsum(counts)
    marks = np.searchsorted(ends, ends[-1] * np.arange(1, parts) // parts, side="right")
    edges = np.unique(np.concatenate([[0], marks, [len(counts)]]))
    return list(zip(edges[:-1].tolist(), edges[1:].tolist(), strict=True))


def bucketed(key: np.ndarray, shift: int, buckets: int) -> tuple[np.ndarray, np.ndarray]:
    """The stable order of the non-negative integer ``key`` by ``key >> shift``, which takes
    ``buckets`` values, at most 256 (int32 where that holds the positions), and where each
    bucket's run ends in it: a stable counting sort, a block a thread."""
    bucket, per_block = _counted(key, 0, shift, buckets)
    return _bucket_order(bucket, per_block, _positions_type(len(key))), np.cumsum(per_block.sum(axis=0))


def _counted(key: np.ndarray, low: int, shift: int, values: int) -> tuple[np.ndarray, np.ndarray]:
    """Each key's bucket ``(key - low) >> shift`` as a byte, and each block's count of each of
    the ``values`` buckets (blocks, values), a block a thread (``_bucket_of``)."""
    bucket = np.empty(len(key), np.uint8)
    return bucket, np.array(parallel.run(partial(_bucket_of, key, low, shift, values, bucket), len(key)))


def _positions_type(n: int) -> type:
    """The integer type of ``n`` keys' positions: int32 where it holds them, half as wide."""
    return np.int32 if n <= np.iinfo(np.int32).max else np.int64


def _bucket_order(bucket: np.ndarray, per_block: np.ndarray, dtype) -> np.ndarray:
    """``np.argsort(bucket, kind="stable")`` as ``dtype``, of bytes whose counts by value in
    each block of ``parallel.cuts`` are ``per_block`` (blocks, values): each block sorted (a
    radix sort of bytes), then each block's run of each value written where the blocks
    before it leave off."""
    blocks = parallel.cuts(len(bucket))
    if len(blocks) == 1:
        return np.argsort(bucket, kind="stable").astype(dtype)

    def local(lo: int, hi: int) -> np.ndarray:
        at = np.argsort(bucket[lo:hi], kind="stable").astype(dtype)
        at += lo
        return at

    found = parallel.run(local, len(bucket))
    counts = per_block.sum(axis=0)
    # where block t's run of value b starts: after every smaller value's, and block t's
    # predecessors' run of b
    starts = np.cumsum(counts) - counts + np.cumsum(per_block, axis=0) - per_block
    order = np.empty(len(bucket), dtype)

    def place(t: int) -> None:
        at, held = found[t], per_block[t]
        taken = np.cumsum(held) - held
        for b in np.flatnonzero(held).tolist():
            order[starts[t, b] : starts[t, b] + held[b]] = at[taken[b] : taken[b] + held[b]]

    parallel.each(place, list(range(len(blocks))))
    return order


def _bucket_of(
    key: np.ndarray, low: int, shift: int, values: int, out: np.ndarray, lo: int, hi: int
) -> np.ndarray:
    """``out[lo:hi]``: ``(key - low) >> shift`` of ``key[lo:hi]``, as bytes, a piece at a
    time; returns how many of each of ``values`` the block has."""
    for start in range(lo, hi, _BLOCK):
        stop = min(start + _BLOCK, hi)
        piece = key[start:stop].astype(np.int64)
        piece -= low
        piece >>= shift
        out[start:stop] = piece
    return np.bincount(out[lo:hi], minlength=values)


def unique_first(key: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``np.unique(key, return_index=True, return_inverse=True)`` of a 1-D integer array: the
    distinct keys, the index of each one's first occurrence, and each entry's distinct key."""
    numbered = _numbered(key, np.int64)
    if numbered is None:
        return _sorted_unique(key)
    low, at, present, inverse = numbered
    first = np.full(len(present), len(key), np.int64)
    np.minimum.at(first, at, np.arange(len(key)))
    return (np.flatnonzero(present) + low).astype(key.dtype), first[present], inverse


def renumbered(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(key, return_inverse=True)`` of a 1-D integer array: the distinct keys and each
    entry's number among them, as ``unique_first`` finds them but without the first
    occurrences (a vertex list's own vertices, its corners numbered over them)."""
    numbered = _numbered(key, np.int64)
    if numbered is None:
        distinct, _, inverse = _sorted_unique(key)
        return distinct, inverse
    low, _, present, inverse = numbered
    return (np.flatnonzero(present) + low).astype(key.dtype), inverse


def row_numbers(rows: np.ndarray) -> np.ndarray:
    """(N,) int64: each of the integer ``rows`` (N, K) numbered among the distinct rows in
    their order, first column first (``np.unique(rows, axis=0, return_inverse=True)``'s
    inverse): the last columns' numbers and the one before packed into one key, a column at a
    time, each key below N squared."""
    if len(rows) == 0:
        return np.zeros(0, np.int64)
    number = renumbered(rows[:, -1])[1]
    for k in range(rows.shape[1] - 2, -1, -1):
        number = renumbered(renumbered(rows[:, k])[1] * (int(number.max()) + 1) + number)[1]
    return number


def _sorted_unique(key: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``unique_first`` by one stable sort of the keys."""
    order = stable_argsort(key)
    ordered = key[order]
    new = _run_starts(ordered)
    return ordered[new], order[new], _scattered_ranks(new, order)


def sorted_ranks(ordered: np.ndarray, order: np.ndarray) -> np.ndarray:
    """(N,) int64: each key's rank among the distinct keys (``np.unique``'s inverse), from the
    keys sorted, ``ordered``, and where each came from, ``order``."""
    return _scattered_ranks(_run_starts(ordered), order)


def _run_starts(ordered: np.ndarray) -> np.ndarray:
    """(N,) bool: where a run of equal sorted keys begins (the first key's), a block a thread."""
    new = np.empty(len(ordered), bool)

    def changes(lo: int, hi: int) -> None:
        np.not_equal(ordered[lo + 1 : hi], ordered[lo : hi - 1], out=new[lo + 1 : hi])
        new[lo] = lo == 0 or ordered[lo] != ordered[lo - 1]

    if len(ordered):
        parallel.run(changes, len(ordered))
    return new


def _scattered_ranks(new: np.ndarray, order: np.ndarray) -> np.ndarray:
    """The runs' numbers (``_run_starts`` ``new``) of the sorted keys, put where each came from."""
    ranks = np.empty(len(new), np.int64)
    parallel.put(ranks, order, parallel.cumsum(new, np.int64, start=-1))
    return ranks


def dense_ranks(key: np.ndarray) -> np.ndarray:
    """(N,) int32 where a table over the keys' range numbers them, else int64: each of the
    integer ``key`` (N,) numbered among the distinct ones, in order (``unique_first``'s inverse,
    without the first occurrences)."""
    if len(key) == 0:
        return np.zeros(0, np.int32)
    # ranks below the span, at most _TABLE_PER_KEY times the keys: int32 for any mesh it indexes
    numbered = _numbered(key, np.int32)
    return unique_first(key)[2] if numbered is None else numbered[3]


def _numbered(key: np.ndarray, dtype) -> tuple[int, np.ndarray, np.ndarray, np.ndarray] | None:
    """The keys numbered through a table over their range where it spans at most
    ``_TABLE_PER_KEY`` times their number (None elsewhere, and for no keys): the lowest key,
    each key's place in the table, whether each value is present, and each key's rank among
    the values present (``dtype``, or int64 where the range is wider); on the thread pool."""
    n = len(key)
    if n == 0:
        return None
    low = int(key.min())
    span = int(key.max()) - low + 1
    if span > _TABLE_PER_KEY * n:
        return None
    if span > np.iinfo(dtype).max:
        dtype = np.int64
    # below the span, a few times the keys: in the keys' own type where it is a word or more
    at = np.empty(n, key.dtype if key.dtype.itemsize >= 4 else np.int32)
    parallel.run(partial(_less, key, low, at), n)
    present = np.zeros(span, bool)
    parallel.mark(present, at)
    rank = parallel.cumsum(present, dtype, start=-1)
    ranks = np.empty(n, rank.dtype)
    parallel.take(rank, at, ranks)
    return low, at, present, ranks


def _less(key: np.ndarray, low: int, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]``: ``key[lo:hi] - low``."""
    np.subtract(key[lo:hi], low, out=out[lo:hi])


def grouped(values: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """(value, the indices holding it, ascending) for every distinct value of ``values`` (N,)
    int, by value."""
    if len(values) == 0:
        return []
    order = stable_argsort(values)
    ordered = values[order]
    cuts = np.flatnonzero(np.r_[True, ordered[1:] != ordered[:-1], True]).tolist()
    return [(int(ordered[lo]), order[lo:hi]) for lo, hi in zip(cuts[:-1], cuts[1:], strict=True)]
