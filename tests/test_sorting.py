"""The fast sorts, column reductions and cross products give NumPy's own answers; blocks of
groups by size hold each group once."""

import numpy as np
import pytest

from blueprint import parallel, settings
from blueprint.columns import (
    column_max,
    column_min,
    column_ptp,
    cross,
    face_cross,
    row_norm,
    runs,
    square_blocks,
)
from blueprint.sorting import (
    SortedKeys,
    _balanced,
    _bucket_order,
    dense_ranks,
    renumbered,
    sorted_with_order,
    stable_argsort,
    unique_first,
)


@pytest.mark.parametrize(
    ("count", "low", "high"),
    [
        (0, 0, 5),
        (1, 0, 5),
        (50, 0, 3),
        (20000, -500, 500),
        (2000, 0, 8000),
        (20000, 0, 2**40),
        (1000, 0, 2**51),
        (1000, 0, 2**53),
        (300, 0, 2**62),
        (65000, 0, 2**62),
        (200000, 0, 2**62),
        (300, 2**63, 2**64 - 1),
    ],
    ids=[
        "empty",
        "one",
        "few-values",
        "negative",
        "range-of-four-a-key",
        "wide",
        "widest-packed",
        "just-too-wide-to-pack",
        "too-wide-to-pack",
        "too-wide-to-pack-in-the-most-buckets",
        "too-wide-to-pack-in-the-fewest-buckets",
        "beyond-int64",
    ],
)
@pytest.mark.parametrize("threads", [1, 3])
def test_sorts_equal_numpys(count, low, high, threads, monkeypatch):
    # blocks of a few keys each, so that even small arrays are split over the threads
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)
    key = np.random.default_rng(count).integers(
        low, high, count, dtype=np.uint64 if low >= 2**63 else np.int64
    )
    np.testing.assert_array_equal(stable_argsort(key), np.argsort(key, kind="stable"))
    ordered, order = sorted_with_order(key)
    np.testing.assert_array_equal(order, np.argsort(key, kind="stable"))
    np.testing.assert_array_equal(ordered, np.sort(key).astype(np.int64))  # int64 by its contract
    assert ordered.dtype == order.dtype == np.int64
    for got, expected in zip(
        unique_first(key), np.unique(key, return_index=True, return_inverse=True), strict=True
    ):
        np.testing.assert_array_equal(got, expected.reshape(-1))
        assert got.dtype == expected.dtype
    if low < 2**63:
        # the sorted keys read by position, over slices and index arrays, packed or not
        expected_order = np.argsort(key, kind="stable")
        sorted_keys = SortedKeys(key.copy())
        assert sorted_keys.length == count
        everything = slice(0, count)
        np.testing.assert_array_equal(sorted_keys.order(everything), expected_order)
        np.testing.assert_array_equal(sorted_keys.keys(everything), key[expected_order])
        at = np.random.default_rng(1).integers(0, max(count, 1), min(count, 7))
        np.testing.assert_array_equal(sorted_keys.order(at), expected_order[at])
        np.testing.assert_array_equal(sorted_keys.keys(at), key[expected_order][at])


@pytest.mark.parametrize("parts", [1, 2, 3, 16])
def test_bucket_runs_share_the_keys_among_the_threads(parts):
    """The buckets sorted side by side are cut into runs of about as many keys each, however
    the keys lie: every bucket once, in order, at most ``parts`` runs, none holding more than a
    share and one bucket."""
    rng = np.random.default_rng(parts)
    for counts in (
        np.r_[rng.integers(900, 1100, 17), np.zeros(15, np.int64)],  # the top buckets empty
        np.r_[np.zeros(10, np.int64), 5000, rng.integers(0, 50, 21)],  # one bucket holds most
        rng.integers(0, 3, 64),
    ):
        runs = _balanced(counts, parts)
        assert runs[0][0] == 0 and runs[-1][1] == len(counts) and len(runs) <= parts
        assert all(a[1] == b[0] and a[0] < a[1] for a, b in zip(runs, runs[1:], strict=False))
        held = [int(counts[a:b].sum()) for a, b in runs]
        assert max(held) <= counts.sum() / parts + counts.max()


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.int64])
def test_column_reductions_equal_numpys(dtype):
    values = (np.random.default_rng(3).normal(0, 1e3, (5000, 3))).astype(dtype)
    for got, expected in (
        (column_min(values), values.min(axis=0)),
        (column_max(values), values.max(axis=0)),
        (column_ptp(values), np.ptp(values, axis=0)),
    ):
        assert got.dtype == expected.dtype
        np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("columns", [2, 3, 4])
def test_row_norm_equals_numpys(dtype, columns):
    values = np.random.default_rng(columns).normal(0, 1e2, (20000, columns)).astype(dtype)
    got, expected = row_norm(values), np.linalg.norm(values, axis=1)
    assert got.dtype == expected.dtype
    np.testing.assert_array_equal(got, expected)


def test_runs_hold_each_item_once_in_order_within_the_rows():
    """Consecutive items in runs whose rows before their last item come to less than
    ``most``: an item of more rows ends its run."""
    counts = np.random.default_rng(4).integers(1, 30, 500)
    counts[[7, 8, 200]] = 400
    blocks = runs(counts, 100)
    assert blocks[0][0] == 0 and blocks[-1][1] == len(counts)
    assert all(a[1] == b[0] for a, b in zip(blocks[:-1], blocks[1:], strict=True))
    for lo, hi in blocks:
        assert hi > lo and counts[lo : hi - 1].sum() < 100
        assert hi == len(counts) or counts[lo:hi].sum() >= 100
    ends = [hi for _, hi in blocks]
    assert 8 in ends and 9 in ends and 201 in ends and (8, 9) in blocks
    assert runs(np.zeros(0, np.int64), 10) == []


def test_square_blocks_hold_each_group_once_by_size():
    """Every group of a size up to ``most`` in exactly one block of groups of its size, a
    block of at most ``cells`` d x d cells (one group where a group alone passes that)."""
    sizes = np.random.default_rng(3).integers(1, 40, 5000)
    work = square_blocks(sizes, 1000, most=30)
    held = np.concatenate([chosen for _, chosen in work])
    assert np.array_equal(np.sort(held), np.flatnonzero(sizes <= 30))
    for d, chosen in work:
        assert (sizes[chosen] == d).all()
        assert len(chosen) * d * d <= 1000 or len(chosen) == 1
    assert [d for d, _ in square_blocks(np.array([70, 2]), 1000)] == [2, 70]


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_cross_products_equal_numpys(dtype):
    tri = np.random.default_rng(5).normal(0, 1e2, (20000, 3, 3)).astype(dtype)
    u, v = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    expected = np.cross(u, v)
    for got in (cross(u, v), face_cross(tri)):
        assert got.dtype == expected.dtype
        np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("threads", [1, 3])
def test_bucket_order_is_numpys_stable_argsort(threads, monkeypatch):
    """Each thread's block of bytes sorted and placed after the blocks before it: NumPy's
    stable order, with every value in every block and values some blocks lack."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)
    rng = np.random.default_rng(9)
    bucket = rng.integers(0, 6, 1000).astype(np.uint8)
    bucket[400:700] = 3
    per_block = np.array([np.bincount(bucket[lo:hi], minlength=8) for lo, hi in parallel.cuts(len(bucket))])
    for dtype in (np.int32, np.int64):
        order = _bucket_order(bucket, per_block, dtype)
        assert order.dtype == dtype
        np.testing.assert_array_equal(order, np.argsort(bucket, kind="stable"))


@pytest.mark.parametrize("dtype", [np.int16, np.int32, np.int64])
@pytest.mark.parametrize("threads", [1, 3])
def test_dense_keys_are_their_ranks_among_the_distinct_keys(dtype, threads, monkeypatch):
    # blocks of a few keys each: the table's marks, ranks and gathers split over the threads
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)
    rng = np.random.default_rng(6)
    key = (rng.integers(0, 50, 200) * 3 - 20).astype(dtype)
    dense = dense_ranks(key)
    assert dense.dtype == np.int32
    np.testing.assert_array_equal(dense, np.unique(key, return_inverse=True)[1].reshape(-1))
    sparse = key.astype(np.int64) * 1000  # a span beyond the table: numbered by a sort
    np.testing.assert_array_equal(dense_ranks(sparse), np.unique(sparse, return_inverse=True)[1].reshape(-1))


@pytest.mark.parametrize("spread", [1, 1000], ids=["table", "sort"])
@pytest.mark.parametrize("count", [0, 1, 300])
@pytest.mark.parametrize("threads", [1, 3])
def test_renumbered_keys_are_numpys_unique_and_inverse(spread, count, threads, monkeypatch):
    """Over a range a table holds (a part's own vertices) and past it (numbered by a sort)."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 16)
    key = (np.random.default_rng(7).integers(0, 80, count) * spread - 40).astype(np.int32)
    distinct, inverse = renumbered(key)
    expected, expected_inverse = np.unique(key, return_inverse=True)
    assert distinct.dtype == key.dtype
    np.testing.assert_array_equal(distinct, expected)
    np.testing.assert_array_equal(inverse, expected_inverse.reshape(-1))
    np.testing.assert_array_equal(distinct[inverse], key)
