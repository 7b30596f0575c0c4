"""Work on large arrays split over threads: NumPy releases the GIL in its sorts, ufuncs, takes
and copies of large arrays, so the blocks of one array's work run side by side, one a core.

Every split is by rows into contiguous blocks, each written by one thread to its own rows, and
no sum runs across blocks: the results are the same, bit for bit, whatever the thread count
(``settings.THREADS``; 1 runs everything in the calling thread).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

import numpy as np

from blueprint import settings
from blueprint.allocator import one_arena

if TYPE_CHECKING:
    from concurrent.futures import ThreadPoolExecutor

__all__ = [
    "MIN_BLOCK",
    "STEP",
    "begin",
    "chosen_at",
    "cumsum",
    "cuts",
    "each",
    "flatnonzero",
    "joined",
    "mark",
    "put",
    "rises",
    "run",
    "sort",
    "stepped",
    "take",
    "taken",
]

T = TypeVar("T")
U = TypeVar("U")

# Rows below which a block is not split off for a thread of its own: handing it over costs
# more than the work.
MIN_BLOCK = 1 << 16
# Rows a ``stepped`` work takes at a time: its temporaries stay a few megabytes.
STEP = 1 << 16

# set by the command line (blueprint.cli.main): its process may serve every thread from one
# arena; a program that calls the library keeps its allocator as it set it
ONE_ARENA_ENV = "BLUEPRINT_ONE_ARENA"

_lock = threading.Lock()
# the pool and the process that made it: a forked child makes its own (its parent's threads
# are not in it)
_pool: tuple[int, ThreadPoolExecutor] | None = None
_worker = threading.local()


def _executor() -> ThreadPoolExecutor:
    global _pool
    with _lock:
        if _pool is None or _pool[0] != os.getpid():
            if os.environ.get(ONE_ARENA_ENV) == "1":
                one_arena()
            # loaded with the first pool: a drawing of a small model never makes one
            from concurrent.futures import ThreadPoolExecutor

            _pool = (
                os.getpid(),
                ThreadPoolExecutor(settings.THREADS, "blueprint", initializer=_mark_worker),
            )
        return _pool[1]


def _mark_worker() -> None:
    _worker.busy = True


def cuts(n: int, min_block: int | None = None, threads: int | None = None) -> list[tuple[int, int]]:
    """``[0, n)`` cut into at most ``threads`` (default ``settings.THREADS``) contiguous blocks
    of about equal size, each of at least ``min_block`` rows (default ``MIN_BLOCK``; one block
    where ``n`` is smaller), as ``(start, stop)`` pairs in order."""
    threads = settings.THREADS if threads is None else threads
    min_block = MIN_BLOCK if min_block is None else min_block
    count = max(1, min(threads, n // max(min_block, 1)))
    edges = [n * k // count for k in range(count + 1)]
    return list(zip(edges[:-1], edges[1:], strict=True))


def run(work: Callable[[int, int], T], n: int, min_block: int | None = None) -> list[T]:
    """``work(start, stop)`` for the blocks of ``cuts(n, min_block)``, side by side on the
    pool's threads, and their results in the blocks' order. Called from one of the pool's own
    threads, the blocks run one after another in that thread (a pool waiting on itself could
    wait for ever)."""
    blocks = cuts(n, min_block)
    if len(blocks) == 1 or getattr(_worker, "busy", False):
        return [work(start, stop) for start, stop in blocks]
    return list(_executor().map(lambda block: work(*block), blocks))


def stepped(work: Callable[[int, int], None], step: int | None = None) -> Callable[[int, int], None]:
    """``work`` made to go over its rows ``step`` (``STEP``) at a time: a block's temporaries are
    then those of a step, not of the block (a thread's share of millions of rows)."""

    def steps(start: int, stop: int) -> None:
        rows = STEP if step is None else step
        for lo in range(start, stop, rows):
            work(lo, min(lo + rows, stop))

    return steps


def begin(work: Callable[..., T], *args) -> Callable[[], T]:
    """Start ``work(*args)`` on one of the pool's threads, beside what the caller does next,
    and return a function that waits for its result (raising what it raised). Where there is
    one thread, or called from one of the pool's own, the work runs at once in the calling
    thread."""
    if settings.THREADS == 1 or getattr(_worker, "busy", False):
        result = work(*args)
        return lambda: result
    return _executor().submit(work, *args).result


def each(work: Callable[[T], U], items: list[T]) -> list[U]:
    """``work(item)`` for every one of ``items``, side by side on the pool's threads, and their
    results in the items' order: for pieces of work of their own sizes (a mesh's block of
    instances each), where ``run``'s equal blocks of rows do not fit. In the calling thread
    where there is one thread or one item, or where it is one of the pool's own."""
    if settings.THREADS == 1 or len(items) < 2 or getattr(_worker, "busy", False):
        return [work(item) for item in items]
    return list(_executor().map(work, items))


def cumsum(values: np.ndarray, dtype, start: int = 0, min_block: int | None = None) -> np.ndarray:
    """``start + np.cumsum(values, dtype=dtype)`` of 1-D bool or integer ``values``: each
    block's own running sums side by side, then each block raised by the sums of the blocks
    before it (integers: the same as one running sum)."""
    out = np.empty(len(values), dtype)
    blocks = cuts(len(values), min_block)
    each(lambda block: np.cumsum(values[slice(*block)], dtype=dtype, out=out[slice(*block)]), blocks)
    ends = np.array([out[hi - 1] for _, hi in blocks if hi > 0], dtype)
    raised = start + np.r_[0, np.cumsum(ends[:-1], dtype=dtype)].astype(dtype)

    def add(k: int) -> None:
        if raised[k]:
            out[slice(*blocks[k])] += raised[k]

    each(add, range(len(blocks)))
    return out


def flatnonzero(values: np.ndarray, negated: bool = False, min_block: int | None = None) -> np.ndarray:
    """``np.flatnonzero(values)`` of a 1-D array (of ``~values`` where ``negated``), each
    block's found side by side."""

    def found_in(lo: int, hi: int) -> np.ndarray:
        block = values[lo:hi]
        return np.flatnonzero(~block if negated else block) + lo

    return joined(run(found_in, len(values), min_block))


def chosen_at(chosen: np.ndarray, at: np.ndarray, min_block: int | None = None) -> np.ndarray:
    """``np.flatnonzero(chosen[at])``: the places of ``at`` (1-D, in range) whose entry of the
    bool table ``chosen`` is set, each block's found side by side, no table of them all."""

    def found_in(lo: int, hi: int) -> np.ndarray:
        return np.flatnonzero(chosen[at[lo:hi]]) + lo

    return joined(run(found_in, len(at), min_block))


def joined(pieces: list[np.ndarray]) -> np.ndarray:
    """``np.concatenate(pieces)`` of 1-D arrays of one type, each piece copied into its place by
    a thread of its own."""
    if len(pieces) == 1:
        return pieces[0]
    ends = np.cumsum([len(piece) for piece in pieces])
    out = np.empty(int(ends[-1]), pieces[0].dtype)

    def placed(k: int) -> None:
        out[ends[k] - len(pieces[k]) : ends[k]] = pieces[k]

    each(placed, list(range(len(pieces))))
    return out


def mark(flags: np.ndarray, at: np.ndarray, min_block: int | None = None) -> None:
    """``flags[at] = True``, a block of ``at`` a thread: only True is written, so the flags do
    not depend on the blocks' order."""

    def marked(lo: int, hi: int) -> None:
        flags[at[lo:hi]] = True

    run(marked, len(at), min_block)


def take(table: np.ndarray, at: np.ndarray, out: np.ndarray, min_block: int | None = None) -> None:
    """``out[:] = table[at]``: the rows ``at`` (in range) of ``table``, a block of ``at`` a
    thread, ``MIN_BLOCK`` rows at a time; cast where ``out`` is of another type. Taken with
    ``mode="clip"``: "raise" takes into a copy of ``out`` first."""
    same = out.dtype == table.dtype

    def taken(lo: int, hi: int) -> None:
        for start in range(lo, hi, MIN_BLOCK):
            stop = min(start + MIN_BLOCK, hi)
            if same:
                np.take(table, at[start:stop], axis=0, out=out[start:stop], mode="clip")
            else:
                out[start:stop] = np.take(table, at[start:stop], axis=0, mode="clip")

    run(taken, len(at), min_block)


def taken(table: np.ndarray, at: np.ndarray, dtype=None, min_block: int | None = None) -> np.ndarray:
    """``table[at]`` (as ``dtype`` where given), taken by ``take`` into a new array."""
    out = np.empty((len(at), *table.shape[1:]), table.dtype if dtype is None else dtype)
    take(table, at, out, min_block)
    return out


def put(out: np.ndarray, at: np.ndarray, values: np.ndarray, min_block: int | None = None) -> None:
    """``out[at] = values``, a block of ``at`` a thread: a place of ``at`` that repeats ends
    with one of its values, whichever thread writes last (where they differ, not always the
    last of them)."""

    def placed(lo: int, hi: int) -> None:
        out[at[lo:hi]] = values[lo:hi]

    run(placed, len(at), min_block)


def rises(values: np.ndarray, min_block: int | None = None) -> np.ndarray:
    """(n,) bool of 1-D integer ``values``: each is greater than every one before it (the
    first is): each block's running maximum side by side, then each block's values compared
    with it and with the largest of the blocks before."""
    out = np.empty(len(values), bool)
    if len(values) == 0:
        return out
    blocks = cuts(len(values), min_block)
    highest = each(lambda block: np.maximum.accumulate(values[slice(*block)]), blocks)
    before = [None] + list(np.maximum.accumulate([block[-1] for block in highest[:-1]]))

    def compare(k: int) -> None:
        lo, hi = blocks[k]
        block, high = values[lo:hi], highest[k]
        np.greater(block[1:], high[:-1], out=out[lo + 1 : hi])
        if before[k] is None:
            out[lo] = True
        else:
            out[lo] = block[0] > before[k]
            out[lo + 1 : hi] &= block[1:] > before[k]

    each(compare, range(len(blocks)))
    return out


def sort(values: np.ndarray, min_block: int | None = None) -> None:
    """Sort the 1-D integer array ``values`` in place, as ``values.sort()`` does: blocks of it
    sorted side by side; then cut by value at the blocks' quantiles into as many ranges, the
    pieces of each range from every block merged by a stable sort (which finds their sorted
    runs and merges them), the ranges side by side."""
    blocks = cuts(len(values), min_block)
    if len(blocks) == 1:
        values.sort()
        return
    run(lambda start, stop: values[start:stop].sort(), len(values), min_block)
    count = len(blocks)
    picks = np.concatenate(
        [
            values[start:stop][np.linspace(0, stop - start - 1, 4 * count).astype(np.int64)]
            for start, stop in blocks
        ]
    )
    picks.sort()
    splitters = picks[np.linspace(0, len(picks) - 1, count + 1)[1:-1].astype(np.int64)]
    # where each range begins and ends in each block: values up to a splitter go before it
    bounds = np.array(
        [
            np.r_[start, start + np.searchsorted(values[start:stop], splitters, side="right"), stop]
            for start, stop in blocks
        ]
    )
    sizes = (bounds[:, 1:] - bounds[:, :-1]).sum(axis=0)
    offsets = np.r_[0, np.cumsum(sizes)]
    merged = np.empty_like(values)

    def merge(first: int, last: int) -> None:
        # each range's pieces gathered where they end up, and sorted there: no copy of them
        for k in range(first, last):
            piece = merged[offsets[k] : offsets[k + 1]]
            np.concatenate([values[b[k] : b[k + 1]] for b in bounds], out=piece)
            piece.sort(kind="stable")

    run(merge, count, min_block=1)

    def copy(start: int, stop: int) -> None:
        values[start:stop] = merged[start:stop]

    run(copy, len(values), min_block)
