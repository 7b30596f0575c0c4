"""Work split over threads (``blueprint.parallel``) and the setting of their number."""

import os
import threading

import numpy as np
import pytest

from blueprint import parallel, settings


def test_cuts_are_contiguous_blocks_of_at_least_the_minimum():
    assert parallel.cuts(10, min_block=3, threads=4) == [(0, 3), (3, 6), (6, 10)]
    assert parallel.cuts(10, min_block=1, threads=4) == [(0, 2), (2, 5), (5, 7), (7, 10)]
    assert parallel.cuts(5, min_block=8, threads=4) == [(0, 5)]
    assert parallel.cuts(0, min_block=8, threads=4) == [(0, 0)]
    assert parallel.cuts(100, min_block=1, threads=1) == [(0, 100)]


def test_run_gives_each_block_to_a_thread_and_the_results_in_order(monkeypatch):
    monkeypatch.setattr(settings, "THREADS", 4)
    names = {}

    def work(start, stop):
        names[start] = threading.current_thread().name
        return list(range(start, stop))

    results = parallel.run(work, 40, min_block=10)
    assert results == [list(range(k, k + 10)) for k in range(0, 40, 10)]
    assert all(name.startswith("blueprint") for name in names.values())


def test_stepped_work_goes_over_its_rows_a_step_at_a_time(monkeypatch):
    seen = []
    parallel.stepped(lambda lo, hi: seen.append((lo, hi)), step=4)(3, 13)
    assert seen == [(3, 7), (7, 11), (11, 13)]
    seen.clear()
    parallel.stepped(lambda lo, hi: seen.append((lo, hi)))(5, 5)
    assert seen == []
    monkeypatch.setattr(parallel, "STEP", 6)
    parallel.stepped(lambda lo, hi: seen.append((lo, hi)))(0, 13)
    assert seen == [(0, 6), (6, 12), (12, 13)]


def test_each_runs_every_item_on_the_pool_and_gives_the_results_in_order(monkeypatch):
    """``parallel.each`` hands items of uneven work to the pool's threads and returns their
    results in the items' order; with one thread, or inside one of the pool's, it runs them in
    the calling thread."""
    monkeypatch.setattr(settings, "THREADS", 3)
    items = [0.03, 0.0, 0.02, 0.0, 0.01, 0.0]  # the first ones finish last

    def work(wait):
        threading.Event().wait(wait)
        return wait, threading.current_thread().name

    found = parallel.each(work, items)
    assert [f[0] for f in found] == items
    assert all(name.startswith("blueprint") for _, name in found)
    # inside a thread of the pool: no waiting on the pool itself
    inner = parallel.each(lambda _: parallel.each(work, items[:2]), [0, 1])
    for pair in inner:
        assert len({name for _, name in pair}) == 1
    monkeypatch.setattr(settings, "THREADS", 1)
    assert {name for _, name in parallel.each(work, items)} == {threading.current_thread().name}


def test_begin_runs_work_beside_the_caller_and_waits_for_it_when_asked(monkeypatch):
    """``parallel.begin`` starts work on a thread of the pool while the caller goes on, its
    result (or its error) read when asked for; with one thread it runs at once in the caller."""
    monkeypatch.setattr(settings, "THREADS", 2)
    started, go_on = threading.Event(), threading.Event()

    def work(x):
        started.set()
        go_on.wait(5)
        return x * 2, threading.current_thread().name

    result = parallel.begin(work, 21)
    assert started.wait(5)  # running while the caller is here
    go_on.set()
    value, name = result()
    assert value == 42 and name.startswith("blueprint")
    failed = parallel.begin(lambda: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        failed()
    monkeypatch.setattr(settings, "THREADS", 1)
    assert parallel.begin(work, 1)()[1] == threading.current_thread().name


def test_run_within_a_thread_of_the_pool_runs_its_blocks_in_that_thread(monkeypatch):
    monkeypatch.setattr(settings, "THREADS", 2)

    def inner(start, stop):
        return threading.current_thread().name, start, stop

    def outer(start, stop):
        return parallel.run(inner, stop - start, min_block=1)

    found = parallel.run(outer, 4, min_block=2)
    for blocks in found:
        assert [b[1:] for b in blocks] == [(0, 1), (1, 2)]
        assert len({b[0] for b in blocks}) == 1  # one thread ran both blocks


@pytest.mark.parametrize("n", [0, 1, 99, 10_007])
@pytest.mark.parametrize("threads", [1, 2, 5])
def test_running_sums_maxima_and_found_positions_equal_numpys(n, threads, monkeypatch):
    """Blocks side by side, each raised by the sums (or compared with the maximum) of those
    before it: the same as one running sum or maximum, whatever the blocks."""
    monkeypatch.setattr(settings, "THREADS", threads)
    rng = np.random.default_rng(n + threads)
    flags = rng.random(n) < 0.3
    counts = rng.integers(0, 1000, n).astype(np.int64)
    for values, dtype, start in ((flags, np.int32, 0), (flags, np.int32, -1), (counts, np.int64, 7)):
        found = parallel.cumsum(values, dtype, start=start, min_block=10)
        assert found.dtype == dtype
        np.testing.assert_array_equal(found, start + np.cumsum(values, dtype=dtype))
    np.testing.assert_array_equal(parallel.flatnonzero(flags, min_block=10), np.flatnonzero(flags))
    for values in (counts, np.arange(n), np.sort(counts % 9), counts[::-1].copy()):
        rises = np.ones(n, bool)
        rises[1:] = values[1:] > np.maximum.accumulate(values)[:-1]
        np.testing.assert_array_equal(parallel.rises(values, min_block=10), rises)
    np.testing.assert_array_equal(
        parallel.flatnonzero(flags, negated=True, min_block=10), np.flatnonzero(~flags)
    )
    at = rng.integers(0, max(n, 1), 3 * n)  # repeated places, as a mesh's corners repeat vertices
    marked, expected = np.zeros(n, bool), np.zeros(n, bool)
    parallel.mark(marked, at, min_block=10)
    expected[at] = True
    np.testing.assert_array_equal(marked, expected)
    np.testing.assert_array_equal(parallel.chosen_at(flags, at, min_block=10), np.flatnonzero(flags[at]))


@pytest.mark.parametrize("dtype", [np.int64, np.uint64, np.int32, np.uint8])
@pytest.mark.parametrize("threads", [1, 2, 5])
def test_sort_equals_numpys(dtype, threads, monkeypatch):
    monkeypatch.setattr(settings, "THREADS", threads)
    info = np.iinfo(dtype)
    values = np.random.default_rng(threads).integers(info.min, info.max, 10_007, dtype=dtype, endpoint=True)
    values[::13] = values[0]  # ties
    expected = np.sort(values)
    parallel.sort(values, min_block=100)
    assert values.dtype == dtype
    np.testing.assert_array_equal(values, expected)


@pytest.mark.parametrize(("text", "expected"), [("3", 3), ("1", 1), (" 12 ", 12)])
def test_the_thread_count_is_set_by_the_environment(monkeypatch, text, expected):
    monkeypatch.setenv(settings.THREADS_ENV, text)
    assert settings.thread_count() == expected


@pytest.mark.parametrize("text", ["", "0", "-2", "many", "1.5"])
def test_a_thread_count_that_is_not_one_leaves_the_cores(monkeypatch, text):
    monkeypatch.setenv(settings.THREADS_ENV, text)
    assert settings.thread_count() == max(1, min(len(os.sched_getaffinity(0)), 64))


@pytest.mark.parametrize("threads", [1, 2])
def test_rows_taken_a_block_at_a_time_equal_one_take(threads, monkeypatch):
    """``take``: rows of a table by an index array (of rows too), blocks of a few rows on
    each thread, into an array of the table's type or cast into another's."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 5)
    rng = np.random.default_rng(4)
    table = rng.standard_normal((30, 3)).astype(np.float32)
    at = rng.integers(0, 30, 61).astype(np.int32)
    out = np.full((61, 3), np.nan, np.float32)
    parallel.take(table, at, out, min_block=4)
    np.testing.assert_array_equal(out, table[at])
    faces = rng.integers(0, 30, (23, 3))
    corners = np.full((23, 3), -1, np.int32)
    parallel.take(np.arange(30, dtype=np.int32)[::-1].copy(), faces, corners, min_block=4)
    np.testing.assert_array_equal(corners, 29 - faces)
    offsets = rng.integers(0, 2**31, 30)
    narrow = np.zeros(61, np.uint32)
    parallel.take(offsets, at, narrow, min_block=4)
    np.testing.assert_array_equal(narrow, offsets[at].astype(np.uint32))
    taken = parallel.taken(table, at, min_block=4)
    assert taken.dtype == np.float32 and taken.shape == (61, 3)
    np.testing.assert_array_equal(taken, table[at])
    np.testing.assert_array_equal(parallel.taken(offsets, at, np.int64, min_block=4), offsets[at])


@pytest.mark.parametrize("threads", [1, 3])
def test_rows_put_and_pieces_joined_a_block_a_thread_equal_numpys(threads, monkeypatch):
    """``put``: values into their places, a place repeated with one value; ``joined``: pieces
    (some empty) end to end, as ``np.concatenate`` puts them."""
    monkeypatch.setattr(settings, "THREADS", threads)
    rng = np.random.default_rng(6)
    at = rng.integers(0, 50, 200)
    values = at * 7 + 1  # one value a place
    out, expected = np.zeros(50, np.int64), np.zeros(50, np.int64)
    parallel.put(out, at, values, min_block=8)
    expected[at] = values
    np.testing.assert_array_equal(out, expected)
    pieces = [rng.integers(0, 9, n) for n in (5, 0, 17, 1, 0, 30)]
    np.testing.assert_array_equal(parallel.joined(pieces), np.concatenate(pieces))
    assert parallel.joined(pieces[:1]) is pieces[0]
