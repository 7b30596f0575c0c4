"""Samples that lie on another line of lower level, left out: a line drawn over another one
comes out once, at the lower level."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.columns import column_max, column_min, row_norm
from blueprint.gpu.tables import table_fits, table_texture
from blueprint.sorting import stable_argsort

from .samples import Samples

__all__ = ["suppress_coincident"]

COINCIDENT_COMP = "blueprint.vector:glsl/coincident.comp"
_GROUP = 64
# coincident.comp's tables, in the order of ``_gpu_drop``'s inputs after its storage buffers
_TABLES = ("u_steps", "u_units", "u_keys", "u_cells")
_MAX_GROUPS = 65535


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
    come out once, the longest whole. Left-out samples get level -1. With a ``renderer``
    (``LayerRenderer``) the search runs as a compute pass (coincident.comp), with the same
    arithmetic: the same samples are left out.
    """
    level = level.copy()
    live = np.flatnonzero(level >= 0)
    if len(live) < 2:
        return level
    search = _Search.of(samples, level, live)
    sin_limit = np.sin(np.radians(angle))
    if (
        renderer is not None
        and renderer.ctx.version_code >= 430
        and search.ranks < 2**31
        and table_fits(max(len(search.source), len(search.cell_count)), renderer.max_texture)
    ):
        drop = _gpu_drop(renderer, search, np.float32(distance * distance), _single_below(sin_limit))
    else:
        drop = _cpu_drop(search, distance, sin_limit)
    level[live[drop]] = -1
    return level


@dataclass(frozen=True)
class _Search:
    """What the search for coincident stretches reads: every sample's stretch to the next
    sample of its line (``forward``, its ``unit`` direction and ``inv_length2``, float32 as the
    compute pass has them), the samples' own directions, and the stretches that cover others
    (``source``) sorted by their cell of a dense grid of 1-pixel cells (``span`` cells across,
    one cell of margin all round), then by rank (level, then line); the live samples' cells
    (``key``) and ranks."""

    pixel32: np.ndarray
    direction: np.ndarray
    unit32: np.ndarray
    forward32: np.ndarray
    inv_length2: np.ndarray
    line: np.ndarray
    rank: np.ndarray
    ranks: int
    source: np.ndarray
    src_key: np.ndarray
    cell_start: np.ndarray
    cell_count: np.ndarray
    span: np.ndarray
    live: np.ndarray
    key: np.ndarray
    live_rank: np.ndarray

    @classmethod
    def of(cls, samples: Samples, level: np.ndarray, live: np.ndarray) -> _Search:
        pixel, line = samples.pixel, samples.line
        # every sample stands for the stretch to the next sample of its line
        has_next = np.r_[line[1:] == line[:-1], False]
        forward = np.zeros_like(pixel)
        forward[:-1] = np.where(has_next[:-1, None], np.diff(pixel, axis=0), 0.0)
        length = row_norm(forward)
        unit = forward / np.where(length > 0, length, 1.0)[:, None]
        # a stretch that is hidden deeper or left out covers nothing
        covers = has_next & (length > 0) & (level >= 0) & (np.r_[level[1:], -1] >= 0)
        rank = _run_ranks(level, line, length)
        # the direction of each sample's own line there (its last sample looks back)
        direction = np.where(has_next[:, None], unit, np.r_[unit[:1], unit[:-1]]).astype(np.float32)
        inv_length2 = np.divide(1.0, length**2, out=np.zeros_like(length), where=length > 0)
        origin = np.floor(column_min(pixel[live])).astype(np.int64) - 1
        span = np.floor(column_max(pixel[live])).astype(np.int64) - origin + 2
        source = np.flatnonzero(covers)

        def cell_of(rows):
            c = np.floor(pixel[rows]).astype(np.int64) - origin
            return np.clip(c[:, 1], 0, span[1] - 1) * span[0] + np.clip(c[:, 0], 0, span[0] - 1)

        # stretches by cell, then by rank: a sample's candidates in a cell are the run of
        # stretches ranked below its own at the cell's start, found by one search, so pairs that
        # the rank rules out are never made
        src_cell = cell_of(source)
        ranks = int(rank.max()) + 1  # ranks run 0 to R - 1 over the R runs: the keys fit
        src_key = src_cell * ranks + rank[source]
        order = stable_argsort(src_key)  # the order within a run of one key does not matter
        cell_count = np.bincount(src_cell, minlength=int(span[0] * span[1]))
        return cls(
            pixel.astype(np.float32),
            direction,
            unit.astype(np.float32),
            forward.astype(np.float32),
            inv_length2.astype(np.float32),
            line,
            rank,
            ranks,
            source[order],
            src_key[order],
            np.cumsum(cell_count) - cell_count,
            cell_count,
            span,
            live,
            cell_of(live),
            rank[live],
        )


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
    whose direction turns from theirs by a sine of at most ``sin_limit``, searched in NumPy."""
    s = search
    live, line, source = s.live, s.line, s.source
    drop = np.zeros(len(live), bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            probe = s.key + dy * s.span[0] + dx  # the margin keeps probes inside the grid
            lo = s.cell_start[probe]
            count = np.searchsorted(s.src_key, probe * s.ranks + s.live_rank) - lo
            for start in range(0, len(live), 1 << 16):
                c = count[start : start + (1 << 16)]
                total = int(c.sum())
                if total == 0:
                    continue
                index = np.repeat(np.arange(start, start + len(c)), c)
                within = np.arange(total) - np.repeat(np.cumsum(c) - c, c)
                other = np.take(source, np.repeat(lo[start : start + len(c)], c) + within)
                mine = np.take(live, index)
                ok = np.take(line, other) != np.take(line, mine)
                index, mine, other = index[ok], mine[ok], other[ok]
                # distance from the sample to the other stretch, and the angle between them
                rel = np.take(s.pixel32, mine, axis=0) - np.take(s.pixel32, other, axis=0)
                f = np.take(s.forward32, other, axis=0)
                t = np.clip((rel[:, 0] * f[:, 0] + rel[:, 1] * f[:, 1]) * np.take(s.inv_length2, other), 0, 1)
                gx, gy = rel[:, 0] - t * f[:, 0], rel[:, 1] - t * f[:, 1]
                d, u = np.take(s.direction, mine, axis=0), np.take(s.unit32, other, axis=0)
                turn = np.abs(d[:, 0] * u[:, 1] - d[:, 1] * u[:, 0])
                hit = (gx * gx + gy * gy <= distance * distance) & (turn <= sin_limit)
                drop[index[hit]] = True
    return drop


def _single_below(value: float) -> np.float32:
    """The largest single-precision number at most ``value``: comparing a single with it is
    comparing the single, widened, with ``value``."""
    single = np.float32(value)
    return np.nextafter(single, np.float32(-np.inf)) if single > value else single


def _gpu_drop(renderer, search: _Search, dist2: np.float32, sin_limit: np.float32) -> np.ndarray:
    """The drop flag of every live sample from coincident.comp, ``_cpu_drop``'s on the GPU
    (``dist2`` the distance squared): the search's arrays laid out as the shader's inputs, two
    storage buffers, then its tables (``_TABLES``)."""
    s, live, source = search, search.live, search.source
    inputs = [
        np.concatenate([s.pixel32[live], s.direction[live]], axis=1),
        np.stack([s.key, s.live_rank, s.line[live], np.zeros_like(s.key)], axis=1),
        np.concatenate([s.pixel32[source], s.forward32[source]], axis=1),
        np.stack(
            [
                s.unit32[source, 0],
                s.unit32[source, 1],
                s.inv_length2[source],
                np.zeros(len(source), np.float32),
            ],
            axis=1,
        ),
        np.stack([s.rank[source], s.line[source]], axis=1),
        np.stack([s.cell_start, s.cell_count], axis=1),
    ]
    count = len(live)
    renderer.make_current()
    ctx = renderer.ctx
    prog = renderer.compute(COINCIDENT_COMP)
    put = renderer.uniforms.set
    put(prog, "u_count", count)
    put(prog, "u_span", int(s.span[0]))
    put(prog, "u_distance2", float(dist2))
    put(prog, "u_sin_limit", float(sin_limit))
    singles = [
        np.ascontiguousarray(data, np.int32 if data.dtype.kind in "iu" else np.float32) for data in inputs
    ]
    buffers = [ctx.buffer(data) for data in singles[:2]]
    buffers.append(ctx.buffer(reserve=4 * count))
    tables = [table_texture(ctx, data) for data in singles[2:]]
    try:
        for binding, buffer in zip((0, 1, 2), buffers, strict=True):
            buffer.bind_to_storage_buffer(binding)
        for unit, (name, texture) in enumerate(zip(_TABLES, tables, strict=True)):
            texture.use(location=unit)
            put(prog, name, unit)
        groups = -(-count // _GROUP)
        gx = min(groups, _MAX_GROUPS)
        prog.run(gx, -(-groups // gx))
        ctx.memory_barrier()
        return np.frombuffer(buffers[-1].read(), np.int32) != 0
    finally:
        for buffer in buffers:
            buffer.release()
        for texture in tables:
            texture.release()
