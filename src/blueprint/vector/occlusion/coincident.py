"""Samples that lie on another line of lower level, left out: a line drawn over another one
comes out once, at the lower level."""

from __future__ import annotations

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
    """Leave out samples that lie on another line of lower level (or of the same level and an
    earlier polyline): within ``distance`` pixels across it and running within ``angle`` degrees
    of it. Hidden lines right under visible ones (the bottom outline of a plate under its top
    outline in a plan view) and lines drawn twice at one level come out once. Left-out samples
    get level -1. With a ``renderer`` (``LayerRenderer``) the search runs as a compute pass
    (coincident.comp), with the same arithmetic: the same samples are left out.
    """
    level = level.copy()
    live = np.flatnonzero(level >= 0)
    if len(live) < 2:
        return level
    pixel, line = samples.pixel, samples.line
    # every sample stands for the stretch to the next sample of its line
    has_next = np.r_[line[1:] == line[:-1], False]
    forward = np.zeros_like(pixel)
    forward[:-1] = np.where(has_next[:-1, None], np.diff(pixel, axis=0), 0.0)
    length = row_norm(forward)
    unit = forward / np.where(length > 0, length, 1.0)[:, None]
    # a stretch that is hidden deeper or left out covers nothing
    covers = has_next & (length > 0) & (level >= 0) & (np.r_[level[1:], -1] >= 0)
    sin_limit = np.sin(np.radians(angle))
    rank = level.astype(np.int64) * (int(line.max()) + 1) + line
    # the direction of each sample's own line there (its last sample looks back)
    direction = np.where(has_next[:, None], unit, np.r_[unit[:1], unit[:-1]]).astype(np.float32)
    unit32, forward32 = unit.astype(np.float32), forward.astype(np.float32)
    inv_length2 = np.divide(1.0, length**2, out=np.zeros_like(length), where=length > 0).astype(np.float32)
    pixel32 = pixel.astype(np.float32)
    # a dense grid of 1-pixel cells, one cell of margin all round; the stretches sorted by cell
    origin = np.floor(column_min(pixel[live])).astype(np.int64) - 1
    span = np.floor(column_max(pixel[live])).astype(np.int64) - origin + 2
    source = np.flatnonzero(covers)

    def cell_of(rows):
        c = np.floor(pixel[rows]).astype(np.int64) - origin
        return np.clip(c[:, 1], 0, span[1] - 1) * span[0] + np.clip(c[:, 0], 0, span[0] - 1)

    # stretches by cell, then by rank: a sample's candidates in a cell are the run of stretches
    # ranked below its own at the cell's start, found by one search, so pairs that the rank
    # rules out are never made
    src_cell = cell_of(source)
    ranks = int(rank.max()) + 1
    if float(span[0]) * float(span[1]) * ranks >= 2.0**62:  # keys would overflow: ranks in order only
        rank = np.unique(rank, return_inverse=True)[1].reshape(-1)
        ranks = int(rank.max()) + 1
    src_key = src_cell * ranks + rank[source]
    order = stable_argsort(src_key)  # the order within a run of one key does not matter
    source, src_key = source[order], src_key[order]
    cell_count = np.bincount(src_cell, minlength=int(span[0] * span[1]))
    cell_start = np.cumsum(cell_count) - cell_count
    key = cell_of(live)
    live_rank = rank[live]
    if (
        renderer is not None
        and renderer.ctx.version_code >= 430
        and ranks < 2**31
        and table_fits(max(len(source), len(cell_count)), renderer.max_texture)
    ):
        drop = _gpu_drop(
            renderer,
            [
                np.concatenate([pixel32[live], direction[live]], axis=1),
                np.stack([key, live_rank, line[live], np.zeros_like(key)], axis=1),
                np.concatenate([pixel32[source], forward32[source]], axis=1),
                np.stack(
                    [
                        unit32[source, 0],
                        unit32[source, 1],
                        inv_length2[source],
                        np.zeros(len(source), np.float32),
                    ],
                    axis=1,
                ),
                np.stack([rank[source], line[source]], axis=1),
                np.stack([cell_start, cell_count], axis=1),
            ],
            int(span[0]),
            np.float32(distance * distance),
            _single_below(sin_limit),
        )
        level[live[drop]] = -1
        return level
    drop = np.zeros(len(live), bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            probe = key + dy * span[0] + dx  # the margin keeps probes inside the grid
            lo = cell_start[probe]
            count = np.searchsorted(src_key, probe * ranks + live_rank) - lo
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
                rel = np.take(pixel32, mine, axis=0) - np.take(pixel32, other, axis=0)
                f = np.take(forward32, other, axis=0)
                t = np.clip((rel[:, 0] * f[:, 0] + rel[:, 1] * f[:, 1]) * np.take(inv_length2, other), 0, 1)
                gx, gy = rel[:, 0] - t * f[:, 0], rel[:, 1] - t * f[:, 1]
                d, u = np.take(direction, mine, axis=0), np.take(unit32, other, axis=0)
                turn = np.abs(d[:, 0] * u[:, 1] - d[:, 1] * u[:, 0])
                hit = (gx * gx + gy * gy <= distance * distance) & (turn <= sin_limit)
                drop[index[hit]] = True
    level[live[drop]] = -1
    return level


def _single_below(value: float) -> np.float32:
    """The largest single-precision number at most ``value``: comparing a single with it is
    comparing the single, widened, with ``value``."""
    single = np.float32(value)
    return np.nextafter(single, np.float32(-np.inf)) if single > value else single


def _gpu_drop(renderer, inputs, span: int, dist2, sin_limit) -> np.ndarray:
    """The drop flag of every live sample from coincident.comp, from the search's arrays in
    ``suppress_coincident`` laid out as the shader's inputs (``inputs``): two storage buffers,
    then its tables (``_TABLES``)."""
    count = len(inputs[0])
    renderer.make_current()
    ctx = renderer.ctx
    prog = renderer.compute(COINCIDENT_COMP)
    put = renderer.uniforms.set
    put(prog, "u_count", count)
    put(prog, "u_span", span)
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
