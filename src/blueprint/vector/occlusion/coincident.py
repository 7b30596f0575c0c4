"""Samples that lie on another line of lower level, left out: a line drawn over another one
comes out once, at the lower level."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint import parallel
from blueprint.columns import column_max, column_min, row_norm
from blueprint.gpu.device import run_over
from blueprint.gpu.tables import table_fits, table_of, table_rows, table_texture
from blueprint.sorting import sorted_with_order

from .samples import Samples

__all__ = ["suppress_coincident"]

COINCIDENT_COMP = "blueprint.vector:glsl/coincident.comp"
_GROUP = 64
# coincident.comp's tables, in the order of ``_gpu_drop``'s inputs after its storage buffers
_TABLES = ("u_steps", "u_units", "u_keys", "u_cells")
# Directions (modulo a half turn) fall in up to BINS bins, each a degree wider than the angle
# limit, so a sample's matches lie in its own bin and the two beside it: stretches of other
# directions crowding a cell are never looked at.
BINS = 15
# The stretches one sample looks at, at most: the answer is exact wherever a sample has fewer
# candidates or finds its match sooner (every drawing of a real model), and the search stays
# linear where thousands of stretches crowd a pixel.
BUDGET = 1024


def suppress_coincident(
    samples: Samples,
    level: np.ndarray,
    distance: float = 0.5,
    angle: float = 10.0,
    renderer=None,
) -> np.ndarray:
    """Leave out samples that lie on another line of lower level (or of the same level and
    a longer run of it, then an earlier polyline): within ``distance`` pixels across it and
    running within ``angle`` degrees of it. Hidden lines right under visible ones (the bottom
    outline of a plate under its top outline in a plan view) and lines drawn twice at one level
    come out once, the longest whole. A sample looks at ``BUDGET`` stretches at most (those of
    its own cell first, then of the cells beside it, then of the corners; each cell's by
    direction, then rank): where more crowd around it and none of those matches, it stays.
    Left-out samples get level -1. With a ``renderer`` (``LayerRenderer``) the search runs as a
    compute pass (coincident.comp), with the same arithmetic: the same samples are left out.
    """
    level = level.copy()
    live = np.flatnonzero(level >= 0)
    if len(live) < 2:
        return level
    search = _Search.of(samples, level, live, _bins(angle))
    sin_limit = np.sin(np.radians(angle))
    if (
        renderer is not None
        and renderer.ctx.version_code >= 430
        and search.ranks * search.bins < 2**31
        and table_fits(max(len(search.source), len(search.cell_count)), renderer.max_texture)
    ):
        drop = _gpu_drop(renderer, search, np.float32(distance * distance), _single_below(sin_limit))
    else:
        drop = _cpu_drop(search, distance, sin_limit)
    level[live[drop]] = -1
    return level


def _bins(angle: float) -> int:
    """How many bins of direction the search sorts stretches into for an ``angle`` limit in
    degrees: each a degree wider than the limit, so that its neighbours hold every match
    whatever the rounding; one where three would cover every direction anyway."""
    bins = int(min(BINS, 180.0 // (angle + 1.0)))
    return bins if bins > 3 else 1


def _direction_bin(unit: np.ndarray, bins: int) -> np.ndarray:
    """(N,) int64 bin of each (N, 2) direction's angle modulo a half turn."""
    turn = np.arctan2(unit[:, 1], unit[:, 0])
    np.degrees(turn, out=turn)
    np.remainder(turn, 180.0, out=turn)
    np.multiply(turn, bins / 180.0, out=turn)
    return np.minimum(turn.astype(np.int64), bins - 1)


@dataclass(frozen=True)
class _Search:
    """What the search for coincident stretches reads: the stretches that cover others (a live
    sample's stretch to the next sample of its line; ``source``, their samples) sorted by their
    cell of a dense grid of 1-pixel cells (``span`` cells across, one cell of margin all round),
    then by their direction's bin (of ``bins``), then by rank (level, then line; ``src_key``,
    cell, bin and rank in one number), and in that order their start and step (``stretch``:
    ``pixel32``, ``forward32``) and their direction and inverse squared length (``units``:
    ``unit32``, ``inv_length2``), float32 as the compute pass has them, laid out as its tables'
    rows; the live samples' pixels and directions (``looks``, the compute pass's rows), cells
    (``key``), ranks, and the first (``first_bin``) and count (``bin_count``) of the bins they
    look in: their own and the two beside it, every bin for a sample without a direction.
    Nothing is kept a sample that is neither live nor covering."""

    stretch: np.ndarray
    units: np.ndarray
    looks: np.ndarray
    line: np.ndarray
    ranks: int
    bins: int
    source: np.ndarray
    src_key: np.ndarray
    cell_start: np.ndarray
    cell_count: np.ndarray
    span: np.ndarray
    live: np.ndarray
    key: np.ndarray
    live_rank: np.ndarray
    first_bin: np.ndarray
    bin_count: np.ndarray

    @property
    def pixel32(self) -> np.ndarray:
        return self.stretch[: len(self.source), :2]

    @property
    def forward32(self) -> np.ndarray:
        return self.stretch[: len(self.source), 2:]

    @property
    def unit32(self) -> np.ndarray:
        return self.units[: len(self.source), :2]

    @property
    def inv_length2(self) -> np.ndarray:
        return self.units[: len(self.source), 2]

    @classmethod
    def of(cls, samples: Samples, level: np.ndarray, live: np.ndarray, bins: int = 1) -> _Search:
        pixel, line = samples.pixel, samples.line
        # every sample stands for the stretch to the next sample of its line
        has_next = np.r_[line[1:] == line[:-1], False]
        length, stretch, units = _stretches(pixel, has_next)
        # a stretch that is hidden deeper or left out covers nothing
        covers = has_next & (length > 0) & (level >= 0) & (np.r_[level[1:], -1] >= 0)
        rank = _run_ranks(level, line, length)
        del length
        # the direction of each sample's own line there (its last sample looks back)
        direction = np.ascontiguousarray(units[:, :2])
        back = np.flatnonzero(~has_next[1:]) + 1
        direction[back] = direction[back - 1]
        looks, live_bin, live_cell, first_bin, span = _live_rows(pixel, direction, live, bins)
        del direction
        # a covering stretch is a live sample's: its cell and bin (of its direction) are its own
        covering = covers[live]
        source = live[covering]
        src_cell = live_cell[covering]

        # stretches by cell, bin and rank: a sample's candidates in a cell and bin are the run
        # of stretches ranked below its own at the run's start, found by one search, so pairs
        # that the rank rules out are never made
        ranks = int(rank.max()) + 1  # ranks run 0 to R - 1 over the R runs: the keys fit
        src_key = (src_cell * bins + live_bin[covering]) * ranks + rank[source]
        src_key, order = sorted_with_order(src_key, overwrite=True)
        source = source[order]
        del order
        cell_count = np.bincount(src_cell, minlength=int(span[0] * span[1]))
        aimless = (looks[:, 2] == 0) & (looks[:, 3] == 0)
        side = 1 if bins > 1 else 0
        return cls(
            _table_rows(stretch, source),
            _table_rows(units, source),
            looks,
            line,
            ranks,
            bins,
            source,
            src_key,
            np.cumsum(cell_count) - cell_count,
            cell_count,
            span,
            live,
            live_cell,
            rank[live],
            first_bin,
            np.where(aimless, bins, 1 + 2 * side),
        )


def _stretches(pixel: np.ndarray, has_next: np.ndarray):
    """(S,) float64 length of every sample's stretch to the next sample of its line (0 where
    none), and ``_Search``'s ``stretch`` and ``units`` rows, a block of samples a thread."""
    n = len(pixel)
    length = np.empty(n)
    stretch = np.empty((n, 4), np.float32)
    units = np.zeros((n, 4), np.float32)

    def block(lo: int, hi: int) -> None:
        forward = np.zeros((hi - lo, 2))
        ahead = min(hi, n - 1)
        np.subtract(pixel[lo + 1 : ahead + 1], pixel[lo:ahead], out=forward[: ahead - lo])
        forward[~has_next[lo:hi]] = 0.0
        step = length[lo:hi]
        step[:] = row_norm(forward)
        stretch[lo:hi, :2] = pixel[lo:hi]
        stretch[lo:hi, 2:] = forward
        moves = step > 0
        # divided in double precision, rounded once as written
        np.divide(forward, np.where(moves, step, 1.0)[:, None], out=units[lo:hi, :2])
        np.divide(1.0, step**2, out=units[lo:hi, 2], where=moves)

    parallel.run(block, n)
    return length, stretch, units


def _live_rows(pixel: np.ndarray, direction: np.ndarray, live: np.ndarray, bins: int):
    """``_Search``'s rows of the live samples: ``looks``, their directions' bins, their cells
    in a grid of one cell of margin all round their pixels, and the first bins they look in;
    and the grid's ``span``. A block of live samples a thread, twice: the grid's corners come
    from every block's pixels."""
    count = len(live)
    looks = np.empty((count, 4), np.float32)
    live_pixel = np.empty((count, 2))
    live_bin = np.empty(count, np.int64)

    def gather(lo: int, hi: int):
        rows = live[lo:hi]
        mine = direction[rows]
        live_bin[lo:hi] = _direction_bin(mine, bins)
        looks[lo:hi, 2:] = mine
        at = live_pixel[lo:hi]
        np.take(pixel, rows, axis=0, out=at)
        looks[lo:hi, :2] = at
        return column_min(at), column_max(at)

    corners = parallel.run(gather, count)
    origin = np.floor(np.min([low for low, _ in corners], axis=0)).astype(np.int64) - 1
    span = np.floor(np.max([high for _, high in corners], axis=0)).astype(np.int64) - origin + 2
    live_cell = np.empty(count, np.int64)
    first_bin = np.empty(count, np.int64)
    side = 1 if bins > 1 else 0

    def place(lo: int, hi: int) -> None:
        # the margin keeps every live sample's cell inside the grid; columns and rows as whole
        # numbers in double precision, combined exactly
        x, y = np.floor(live_pixel[lo:hi, 0]), np.floor(live_pixel[lo:hi, 1])
        y -= origin[1]
        y *= span[0]
        y += x
        y -= origin[0]
        live_cell[lo:hi] = y
        first = first_bin[lo:hi]
        np.subtract(live_bin[lo:hi], side, out=first)
        wraps = first < 0
        first[wraps] %= bins
        mine = looks[lo:hi, 2:]
        first[(mine[:, 0] == 0) & (mine[:, 1] == 0)] = 0

    parallel.run(place, count)
    return looks, live_bin, live_cell, first_bin, span


def _run_ranks(level: np.ndarray, line: np.ndarray, step: np.ndarray) -> np.ndarray:
    """(S,) int64 rank of every sample's run (its polyline's consecutive samples of one level):
    by level, then the longest run first, then by polyline and place, so that of two lines drawn
    over each other at one level the one in longer pieces stays whole (the top edge of a wall
    seen edge-on, not the wall's own short mesh edges along it); ``step`` the pixels from each
    sample to the next of its line (0 at a line's last sample)."""
    new_run = np.r_[True, (line[1:] != line[:-1]) | (level[1:] != level[:-1])]
    start = np.flatnonzero(new_run)
    run = np.cumsum(new_run) - 1
    # a run's pixels: its steps but the last, which leads into the next run
    length = np.bincount(run, weights=step, minlength=len(start)) - step[np.r_[start[1:], len(level)] - 1]
    order = np.lexsort((start, -length, level[start]))
    rank = np.empty(len(start), np.int64)
    rank[order] = np.arange(len(start))
    return rank[run]


def _cpu_drop(search: _Search, distance: float, sin_limit: float) -> np.ndarray:
    """(L,) bool: the live samples within ``distance`` pixels of a stretch ranked below them
    whose direction turns from theirs by a sine of at most ``sin_limit``, searched in NumPy
    among the ``BUDGET`` candidates each that the compute pass looks at."""
    s = search
    live = s.live
    drop = np.zeros(len(live), bool)
    used = np.zeros(len(live), np.int64)
    for dy, dx in _NEIGHBOURS:
        probe = s.key + dy * s.span[0] + dx  # the margin keeps probes inside the grid
        for step in range(int(s.bin_count.max())):
            rows = np.flatnonzero((step < s.bin_count) & (used < BUDGET) & ~drop)
            run = (probe[rows] * s.bins + (s.first_bin[rows] + step) % s.bins) * s.ranks
            lo = np.searchsorted(s.src_key, run)
            count = np.searchsorted(s.src_key, run + s.live_rank[rows]) - lo
            count = np.minimum(count, BUDGET - used[rows])
            used[rows] += count
            _test_pairs(s, rows, lo, count, distance, sin_limit, drop)
    return drop


# the cells a sample looks in, its own first, then those beside it, then the corners
_NEIGHBOURS = ((0, 0), (-1, 0), (0, -1), (0, 1), (1, 0), (-1, -1), (-1, 1), (1, -1), (1, 1))


def _test_pairs(s: _Search, rows, lo, count, distance: float, sin_limit: float, drop) -> None:
    """Set ``drop`` of the live samples ``rows`` that lie on one of their ``count`` candidate
    stretches from ``lo`` on (in the search's order), in chunks of bounded memory."""
    for start in range(0, len(rows), 1 << 16):
        c = count[start : start + (1 << 16)]
        total = int(c.sum())
        if total == 0:
            continue
        index = np.repeat(rows[start : start + len(c)], c)
        within = np.arange(total) - np.repeat(np.cumsum(c) - c, c)
        # the other stretch's place in the search's order, and its sample
        place = np.repeat(lo[start : start + len(c)], c) + within
        other = np.take(s.source, place)
        mine = np.take(s.live, index)
        ok = np.take(s.line, other) != np.take(s.line, mine)
        index, place = index[ok], place[ok]
        # distance from the sample to the other stretch, and the angle between them
        look = np.take(s.looks, index, axis=0)
        rel = look[:, :2] - np.take(s.pixel32, place, axis=0)
        f = np.take(s.forward32, place, axis=0)
        t = np.clip((rel[:, 0] * f[:, 0] + rel[:, 1] * f[:, 1]) * np.take(s.inv_length2, place), 0, 1)
        gx, gy = rel[:, 0] - t * f[:, 0], rel[:, 1] - t * f[:, 1]
        d, u = look[:, 2:], np.take(s.unit32, place, axis=0)
        turn = np.abs(d[:, 0] * u[:, 1] - d[:, 1] * u[:, 0])
        hit = (gx * gx + gy * gy <= distance * distance) & (turn <= sin_limit)
        drop[index[hit]] = True


def _single_below(value: float) -> np.float32:
    """The largest single-precision number at most ``value``: comparing a single with it is
    comparing the single, widened, with ``value``."""
    single = np.float32(value)
    return np.nextafter(single, np.float32(-np.inf)) if single > value else single


def _gpu_drop(renderer, search: _Search, dist2: np.float32, sin_limit: np.float32) -> np.ndarray:
    """The drop flag of every live sample from coincident.comp, ``_cpu_drop``'s on the GPU
    (``dist2`` the distance squared): the search's arrays laid out as the shader's inputs, two
    storage buffers, then its tables (``_TABLES``), each input made and uploaded in turn, so
    that no two of the host's copies are held at once."""
    s, live, source = search, search.live, search.source
    inputs = (
        lambda: s.looks,
        lambda: _columns(np.int32, s.key, s.live_rank, s.line[live], s.first_bin + 256 * s.bin_count),
        lambda: s.stretch,
        lambda: s.units,
        lambda: table_of(_columns(np.int32, s.src_key % (s.bins * s.ranks), s.line[source]), np.int32),
        lambda: table_of(_columns(np.int32, s.cell_start, s.cell_count), np.int32),
    )
    count = len(live)
    renderer.make_current()
    ctx = renderer.ctx
    prog = renderer.compute(COINCIDENT_COMP)
    put = renderer.uniforms.set
    put(prog, "u_count", count)
    put(prog, "u_span", int(s.span[0]))
    put(prog, "u_ranks", s.ranks)
    put(prog, "u_bins", s.bins)
    put(prog, "u_budget", BUDGET)
    put(prog, "u_distance2", float(dist2))
    put(prog, "u_sin_limit", float(sin_limit))
    buffers, tables = [], []
    try:
        for made in inputs[:2]:
            buffers.append(ctx.buffer(made()))
        buffers.append(ctx.buffer(reserve=4 * count))
        for made in inputs[2:]:
            tables.append(table_texture(ctx, made()))
        for binding, buffer in zip((0, 1, 2), buffers, strict=True):
            buffer.bind_to_storage_buffer(binding)
        for unit, (name, texture) in enumerate(zip(_TABLES, tables, strict=True)):
            texture.use(location=unit)
            put(prog, name, unit)
        run_over(prog, count, _GROUP)
        ctx.memory_barrier()
        return np.frombuffer(buffers[-1].read(), np.int32) != 0
    finally:
        for buffer in buffers:
            buffer.release()
        for texture in tables:
            texture.release()


def _table_rows(array: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Rows ``rows`` of a 2-D ``array`` gathered straight into a table's rows (``table_of``), a
    block of rows a thread."""
    table = np.empty((table_rows(len(rows)), array.shape[1]), array.dtype)

    def gather(lo: int, hi: int) -> None:
        np.take(array, rows[lo:hi], axis=0, out=table[lo:hi])

    parallel.run(gather, len(rows))
    table[len(rows) :] = 0
    return table


def _columns(dtype, *columns) -> np.ndarray:
    """(N, K) array of ``dtype`` whose columns are ``columns`` side by side (each (N,), (N, k)
    or a scalar), each cast as it is written: one array, no wider copy first."""
    rows = next(len(c) for c in columns if np.ndim(c))
    width = sum(1 if np.ndim(c) < 2 else c.shape[1] for c in columns)
    out = np.empty((rows, width), dtype)
    at = 0
    for column in columns:
        k = 1 if np.ndim(column) < 2 else column.shape[1]
        out[:, at : at + k] = column if np.ndim(column) == 2 else np.reshape(column, (-1, 1))
        at += k
    return out
