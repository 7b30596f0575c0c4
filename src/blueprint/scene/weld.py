"""Vertex welding: vertices closer than a tolerance merged into one, as triangle soups need.

Smoothing normals (``blueprint.scene.normals``) and the object-space silhouette method
(``blueprint.silhouette``) both start from it; it depends on the geometry only.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from blueprint import parallel, settings
from blueprint.columns import column_max, column_min, ranges
from blueprint.sorting import dense_ranks, sorted_with_order, unique_first

__all__ = [
    "check_mesh",
    "connected_components_of",
    "default_tolerance",
    "distinct_rows",
    "weld",
    "weld_groups",
]

# Default weld tolerance, relative to the bounding-box diagonal.
_REL_TOL = 1e-6
# The cell itself and the 13 lexicographically positive offsets: together they pair every
# cell with each of its 26 neighbours once.
_FORWARD_OFFSETS = np.array(
    [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)], dtype=np.int64
)[13:]
# The direction of the sweep for close pairs (``_close_pairs``), and the candidates a point it
# may give on average before the grid takes over.
_SWEEP_DIRECTION = np.array([1.0, np.sqrt(2.0), np.sqrt(3.0)]) / np.sqrt(6.0)
_SWEEP_CANDIDATES = 16
# Integer steps a sweep window holds (``_sweep_order``): a step or two past the window is read,
# some tenth more candidates.
_SWEEP_STEPS = 16
# Candidates of the sweep checked at a time.
_SWEEP_BLOCK = 1 << 22
# Rows hashed, and rows compared, at a time by a thread.
_HASH_BLOCK = 1 << 16
# Odd multipliers that mix a position's three 64-bit patterns into one key (wrapping).
_BITS_HASH = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], dtype=np.uint64)
# Large odd multipliers for a spatial hash of integer cell coordinates (Teschner et al. 2003).
_HASH = np.array([73856093, 19349663, 83492791], dtype=np.int64)


def check_mesh(positions: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``positions`` as float32 or float64 and ``faces`` as integers, checked: shapes, indices
    in range, finite positions (ValueError)."""
    positions = np.asarray(positions)
    if positions.dtype != np.float32:
        positions = positions.astype(np.float64, copy=False)
    faces = np.asarray(faces)
    if positions.ndim != 2 or positions.shape[1] != 3:
        raise ValueError(f"positions must have shape (V, 3), got {positions.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"faces must have shape (F, 3), got {faces.shape}")
    if not np.issubdtype(faces.dtype, np.integer):
        if faces.size:
            raise ValueError(f"faces must hold integers, got dtype {faces.dtype}")
        faces = faces.astype(np.int64)
    if faces.size and (faces.min() < 0 or faces.max() >= len(positions)):
        raise ValueError(f"face indices must lie in [0, {len(positions)})")
    if not np.isfinite(positions).all():
        raise ValueError("positions must be finite")
    return positions, faces


def _close_pairs(points: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of distinct points with ``|p_i - p_j| <= tol`` (each pair once, in either order).

    Points within ``tol`` of each other project within ``tol`` of each other on any unit
    vector, so the candidates are the neighbours in one sort along a direction that no axis
    or diagonal of a CAD model follows: one sort and one search, where probing a grid's 14
    cells costs 14. Points spread evenly have a fraction of a neighbour each there (a few on
    millions of points); where many share a projection (over ``_SWEEP_CANDIDATES`` a point:
    points laid out along that very direction), the grid finds them (``_grid_pairs``). The
    candidates are checked in blocks side by side; the pairs come in the blocks' order, the
    same whatever the threads.
    """
    n = len(points)
    projected = points @ _SWEEP_DIRECTION
    # the dot products round: widen the window by their error so no pair within tol is lost
    window = tol * (1.0 + 1e-9) + 8.0 * np.finfo(np.float64).eps * float(np.abs(projected).max(initial=0.0))
    order, along, window = _sweep_order(projected, window)
    count = np.empty(n, np.int64)
    parallel.run(partial(_candidates, along, window, count), n)
    total = int(count.sum())
    if total > _SWEEP_CANDIDATES * n:
        return _grid_pairs(points, tol)
    # the candidates of a block of points at a time, read from the points in sweep order: a
    # candidate lies a few places on, where its row is at hand
    ordered = np.take(points, order, axis=0)
    x = np.ascontiguousarray(ordered[:, 0])
    ends = np.cumsum(count)
    step = max(min(_SWEEP_BLOCK, -(-total // settings.THREADS)), 1)
    cuts = np.r_[0, np.searchsorted(ends, np.arange(step, total, step)), n].tolist()
    check = partial(_sweep_block, ordered, x, order, count, tol)
    found = parallel.each(check, list(zip(cuts[:-1], cuts[1:], strict=True)))
    return np.concatenate([i for i, _ in found]), np.concatenate([j for _, j in found])


def _sweep_order(projected: np.ndarray, window: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(order, along, reach): the points in sweep order, the sorted values the candidates are
    found in, and how far along them a point's candidates reach (``window`` of ``projected``).

    Where they fit in 63 bits with the points' positions, the values are the projections in
    integer steps of ``_SWEEP_STEPS`` to the window, sorted by the thread pool's integer sort
    (``sorted_with_order``), the window a step wider for the rounding down: a float argsort
    runs on one thread. Else the projections themselves."""
    n = len(projected)
    step = window / _SWEEP_STEPS
    if n and step > 0:
        low = float(projected.min())
        if (float(projected.max()) - low) / step * 2.0 ** n.bit_length() < 2.0**62:
            steps = np.empty(n, np.int64)
            parallel.run(partial(_in_steps, projected, low, step, steps), n)
            along, order = sorted_with_order(steps, overwrite=True)
            return order, along, _SWEEP_STEPS + 1
    order = np.argsort(projected)
    return order, projected[order], window


def _in_steps(projected: np.ndarray, low: float, step: float, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]``: ``projected`` from ``low`` in whole ``step``s, rounded down."""
    for start in range(lo, hi, _HASH_BLOCK):
        stop = min(start + _HASH_BLOCK, hi)
        out[start:stop] = np.floor((projected[start:stop] - low) / step)


def _candidates(along: np.ndarray, window: float, count: np.ndarray, lo: int, hi: int) -> None:
    """``count[lo:hi]``: the points after each in sweep order within ``window`` along it."""
    reach = np.searchsorted(along, along[lo:hi] + window, side="right")
    np.subtract(reach, np.arange(lo + 1, hi + 1), out=count[lo:hi])


def _sweep_block(
    ordered: np.ndarray,
    x: np.ndarray,
    order: np.ndarray,
    count: np.ndarray,
    tol: float,
    block: tuple[int, int],
) -> tuple[np.ndarray, np.ndarray]:
    """The close pairs among the candidates of points ``block`` (start, stop) in sweep order
    (``_close_pairs``), as indices of the points."""
    lo, hi = block
    counts = count[lo:hi]
    first = np.repeat(np.arange(lo, hi), counts)
    second = first + 1 + (np.arange(len(first)) - np.repeat(np.cumsum(counts) - counts, counts))
    # the squared difference in x is at most the squared distance, as computed: it rules
    # most candidates out before their rows are read
    dx = x[first] - x[second]
    near = dx * dx <= tol * tol
    first, second = first[near], second[near]
    diff = np.take(ordered, first, axis=0) - np.take(ordered, second, axis=0)
    keep = np.einsum("ij,ij->i", diff, diff) <= tol * tol
    return order[first[keep]], order[second[keep]]


def _grid_pairs(points: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of distinct points with ``|p_i - p_j| <= tol``, found through a grid hash.

    With cells slightly larger than `tol`, two points within `tol` lie in the same or in
    adjacent cells whichever side of a cell boundary they fall, so probing each point's cell
    and its neighbours finds every pair. Cells are bucketed by a wrapping integer hash: a
    collision only merges two buckets, adding candidates that the distance test rejects.
    """
    scaled = (points - column_min(points)) / (tol * (1.0 + 1e-9))
    if scaled.max(initial=0.0) >= 2.0**52:
        raise ValueError("weld tolerance is too small relative to the mesh extent")
    cells = np.floor(scaled).astype(np.int64)

    order = np.argsort(cells @ _HASH, kind="stable")
    bucket_hash, bucket_start, bucket_count = np.unique(
        (cells @ _HASH)[order], return_index=True, return_counts=True
    )
    firsts, seconds = [], []
    for offset in _FORWARD_OFFSETS:
        probe = (cells + offset) @ _HASH
        target = np.minimum(np.searchsorted(bucket_hash, probe), len(bucket_hash) - 1)
        found = bucket_hash[target] == probe
        if not offset.any():
            # Within its own cell a point only needs probing if it is not alone there.
            found &= bucket_count[target] > 1
        i, target = np.flatnonzero(found), target[found]
        # Each probing point against every point of its target bucket, without a loop.
        count = bucket_count[target]
        rank = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        i = np.repeat(i, count)
        j = order[np.repeat(bucket_start[target], count) + rank]
        diff = points[i] - points[j]
        keep = (i != j) & (np.einsum("ij,ij->i", diff, diff) <= tol * tol)
        firsts.append(i[keep])
        seconds.append(j[keep])
    return np.concatenate(firsts), np.concatenate(seconds)


def connected_components_of(label: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Connected components of the graph whose edges are the pairs (i, j): each vertex gets the
    smallest vertex index of its component. Clusters of near-duplicates are a few vertices
    across, so this takes a few rounds; in numpy, so that drawing does not load scipy.
    Returns component numbers 0 to C-1."""
    while True:
        low = np.minimum(label[i], label[j])
        before = label.copy()
        np.minimum.at(label, i, low)
        np.minimum.at(label, j, low)
        # pointer jumping: follow labels to their roots
        while True:
            jumped = label[label]
            if np.array_equal(jumped, label):
                break
            label = jumped
        if np.array_equal(label, before):
            return dense_ranks(label).astype(np.int64, copy=False)


def _exact_groups(positions: np.ndarray, dtype=np.int64) -> tuple[np.ndarray, np.ndarray]:
    """Each row of ``positions`` (V, 3) numbered among the distinct rows in the order of their
    first occurrence (as ``dtype``), and the index of each distinct row's first occurrence:
    ``(inverse, first)``, ``positions[first][inverse]`` equal to ``positions`` (-0.0 equal to
    0.0).

    Rows are sorted by a hash of their bits with their index in its low bits, one sort of
    values: rows that share the rest of their hash are one row, or a collision (the more rows,
    the fewer bits the hash keeps: some hundred among 16 M corners), whose runs alone are
    sorted by their values."""
    n = len(positions)
    if n == 0:
        return np.zeros(0, dtype), np.zeros(0, np.int64)
    bits = max(1, (n - 1).bit_length())
    low = np.uint64((1 << bits) - 1)
    key = np.empty(n, np.uint64)
    parallel.run(partial(_hashed, positions, low, key), n)
    parallel.sort(key)
    # equal above the index bits: their exclusive or is below them
    same_hash = np.empty(n - 1, bool)
    parallel.run(partial(_same_hash, key, low, same_hash), n - 1)
    parallel.run(partial(_unpacked, key, low), n)
    order = key.view(np.int64)
    del key
    differs = _row_changes(positions, order)
    collided = same_hash & differs
    if collided.any():
        # the rows of the runs with a collision, sorted by value (stably: each one's first
        # occurrence stays first)
        sub, run = _runs_holding(same_hash, np.flatnonzero(collided))
        picked = order[sub]
        # each run sorted apart: sorted together, a value's rows could straddle a run between
        order[sub] = picked[np.lexsort([*(positions[picked, k] for k in (2, 1, 0)), run])]
        # only the neighbours of the rows moved can change
        moved = np.union1d(sub[sub > 0] - 1, sub[sub < n - 1])
        one, other = (np.take(positions, order[moved + k], axis=0) for k in (0, 1))
        differs[moved] = (one != other).any(axis=1)
    del same_hash, collided
    new = np.empty(n, bool)
    new[0] = True
    new[1:] = differs
    del differs
    group = parallel.cumsum(new, np.int32, start=-1)
    # within a row's run its indices rise: the run's first is the row's first occurrence
    firsts = np.empty(int(group[-1]) + 1, np.int64)
    parallel.run(partial(_firsts, order, new, group, firsts), n)
    del new
    seen = np.zeros(n, bool)
    parallel.mark(seen, firsts)
    ranks = parallel.cumsum(seen, np.int32, start=-1)
    rank = np.empty(len(firsts), np.int32)
    parallel.take(ranks, firsts, rank)
    del ranks
    parallel.run(partial(_ranked, rank, group), n)
    inverse = np.empty(n, dtype)
    parallel.run(partial(_scattered, inverse, order, group), n)
    return inverse, np.flatnonzero(seen)


def _runs_holding(same: np.ndarray, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The positions, ascending, of the runs that hold positions ``at`` (ascending), and the
    number of each one's run among them, where a run is positions ``i`` to ``j`` with ``same``
    true from ``i`` to ``j - 1`` (``same[i]``: positions ``i`` and ``i + 1`` share a hash):
    found from the breaks around each, not by numbering every position's run."""
    breaks = parallel.flatnonzero(same, negated=True)
    k = np.searchsorted(breaks, at)
    # a run ends at the first break at or after a position, else at the last position, and
    # starts after the break before it, else at 0
    ends = np.append(breaks, len(same))
    last = ends[k]
    first = np.where(k > 0, ends[k - 1] + 1, 0)
    first, last = np.unique(np.stack([first, last]), axis=1)
    counts = last - first + 1
    return ranges(first, counts), np.repeat(np.arange(len(counts)), counts)


def _hashed(positions: np.ndarray, low: np.uint64, key: np.ndarray, lo: int, hi: int) -> None:
    """``key[lo:hi]`` (uint64): the hash of rows ``lo`` to ``hi`` of ``positions`` above the
    bits of ``low``, each row's index in them."""
    unsigned = np.uint32 if positions.dtype == np.float32 else np.uint64
    for start in range(lo, hi, _HASH_BLOCK):
        rows = slice(start, min(start + _HASH_BLOCK, hi))
        block = key[rows]
        block[:] = 0
        for k, multiplier in enumerate(_BITS_HASH):
            # adding 0.0 turns -0.0 into 0.0, which would hash apart by its bits
            column = (positions[rows, k] + positions.dtype.type(0.0)).view(unsigned).astype(np.uint64)
            column *= multiplier
            block += column
        block &= ~low
        block |= np.arange(rows.start, rows.stop, dtype=np.uint64)


def _same_hash(key: np.ndarray, low: np.uint64, out: np.ndarray, lo: int, hi: int) -> None:
    """``out[lo:hi]``: sorted keys ``i`` and ``i + 1`` are equal above the bits of ``low``."""
    for start in range(lo, hi, _HASH_BLOCK):
        stop = min(start + _HASH_BLOCK, hi)
        np.less_equal(np.bitwise_xor(key[start + 1 : stop + 1], key[start:stop]), low, out=out[start:stop])


def _firsts(order: np.ndarray, new: np.ndarray, group: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    """The rows of ``order[lo:hi]`` that begin a group (``new``) into ``out``, at their
    groups' numbers (``group``, from 0)."""
    picked = order[lo:hi][new[lo:hi]]
    at = int(group[lo - 1]) + 1 if lo else 0
    out[at : at + len(picked)] = picked


def _unpacked(key: np.ndarray, low: np.uint64, lo: int, hi: int) -> None:
    key[lo:hi] &= low


def _ranked(rank: np.ndarray, group: np.ndarray, lo: int, hi: int) -> None:
    """``group[lo:hi]`` (int32) replaced by its entries of ``rank``, a block at a time: no
    copy of every entry as a wide index, nor of the output (``mode="raise"`` makes one)."""
    for start in range(lo, hi, _HASH_BLOCK):
        block = group[start : min(start + _HASH_BLOCK, hi)]
        np.take(rank, block, out=block, mode="clip")


def _scattered(out: np.ndarray, at: np.ndarray, values: np.ndarray, lo: int, hi: int) -> None:
    out[at[lo:hi]] = values[lo:hi]


def _row_changes(positions: np.ndarray, order: np.ndarray) -> np.ndarray:
    """(V - 1,) bool: row ``order[i + 1]`` of ``positions`` differs from row ``order[i]`` (as
    values: -0.0 equals 0.0)."""
    changes = np.empty(max(len(order) - 1, 0), bool)
    parallel.run(partial(_changes, positions, order, changes), len(changes))
    return changes


def _changes(positions: np.ndarray, order: np.ndarray, out: np.ndarray, lo: int, hi: int) -> None:
    for start in range(lo, hi, _HASH_BLOCK):
        stop = min(start + _HASH_BLOCK, hi)
        # NumPy takes rows faster than it indexes them
        rows = np.take(positions, order[start : stop + 1], axis=0)
        block = out[start:stop]
        np.not_equal(rows[1:, 0], rows[:-1, 0], out=block)
        for k in (1, 2):
            block |= rows[1:, k] != rows[:-1, k]


def distinct_rows(positions: np.ndarray, dtype=np.int64) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``positions`` (V, 3) float, as values (-0.0 equal to 0.0), in the
    order of their first occurrence.

    Parameters
    ----------
    positions : (V, 3) float
    dtype : integer dtype
        Of ``inverse``: int32 where the rows fit, so that no int64 copy is made to narrow.

    Returns
    -------
    first : (D,) int64
        The index of each distinct row's first occurrence, ascending.
    inverse : (V,) ``dtype``
        Each row's number among them: ``positions[first][inverse]`` equals ``positions``.
    """
    inverse, first = _exact_groups(positions, dtype)
    return first, inverse


def _exact_duplicates(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct rows of ``positions`` and each row's number among them, as
    ``np.unique(axis=0, return_inverse=True)`` gives them but in the order of their first
    occurrence."""
    inverse, first = _exact_groups(positions)
    return positions[first], inverse


def weld(positions: np.ndarray, faces: np.ndarray, tol: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices that lie within `tol` of each other.

    Merging is transitive: chains of vertices each within `tol` of the next collapse into one.
    A merged vertex takes the position of its lowest-index member, and welded vertices keep
    the order of their first occurrence. The cost grows with the square of the number of
    vertices per `tol`-sized cell, so `tol` should stay well below the mesh's edge lengths.

    Parameters
    ----------
    positions : np.ndarray
        (V, 3) float vertex positions.
    faces : np.ndarray
        (F, 3) integer vertex indices.
    tol : float, optional
        Euclidean merge distance. Defaults to 1e-6 times the bounding-box diagonal; 0 merges
        exact duplicates only.

    Returns
    -------
    positions : np.ndarray
        (V', 3) float64 welded positions, V' <= V.
    faces : np.ndarray
        (F, 3) int64 faces remapped to the welded positions.
    """
    positions, faces = check_mesh(positions, faces)
    if len(positions) == 0:
        return positions.astype(np.float64), faces.astype(np.int64)
    if tol is None:
        tol = default_tolerance(positions)
    elif not (np.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol must be a finite non-negative number, got {tol}")
    group, first = weld_groups(positions, tol)
    return positions[first].astype(np.float64), group[faces]


def default_tolerance(positions: np.ndarray) -> float:
    """``weld``'s default tolerance for the points ``positions`` (V, 3): ``_REL_TOL`` times
    their bounding box's diagonal (in float64, whatever their type)."""
    extent = column_max(positions).astype(np.float64) - column_min(positions).astype(np.float64)
    return _REL_TOL * float(np.linalg.norm(extent))


def weld_groups(positions: np.ndarray, tol: float, distinct: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The welded vertex of every vertex of ``weld``, and the first vertex of every welded one.

    Parameters
    ----------
    positions : (V, 3) float32 or float64
        Finite positions.
    tol : float
        Euclidean merge distance (non-negative).
    distinct : bool
        The positions are distinct already (a soup's, ``Model.soup``): the pass that groups
        exact duplicates is skipped. The result is the same either way where ``tol`` > 0, for
        the sweep pairs equal positions too; the pass only keeps its neighbourhoods small.

    Returns
    -------
    group : (V,) int64
        Welded vertex of each vertex, numbered in the order of their first vertices.
    first : (V',) int64
        The lowest vertex of each welded vertex, ascending.
    """
    # Exact duplicates first: triangle soups repeat every vertex several times, and collapsing
    # them keeps the sweep's and the grid's neighbourhoods nearly empty.
    if distinct and tol > 0:
        inverse = first = np.arange(len(positions))
    else:
        inverse, first = _exact_groups(positions)
    if tol > 0 and len(first) > 1:
        i, j = _close_pairs(positions[first].astype(np.float64), tol)
        if len(i):
            label = connected_components_of(
                np.arange(len(first)), np.asarray(i, np.int64), np.asarray(j, np.int64)
            )
            # components are numbered by their lowest member, and members by first vertex
            first = first[unique_first(label)[1]]
            inverse = label[inverse]
    return inverse, first
