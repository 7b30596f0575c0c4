"""The pairs of triangles that may cut through each other, found on the GPU: the broad phase's
pairs (triangle_pairs.comp) and the narrow phase's test (triangle_cuts.comp) in two compute
passes, only the pairs that may cut read back, for ``lines._triangle_pairs_cut`` to cut with
NumPy. Two passes, not one: most partners in a cell fail the box test, and a narrow phase
inside that loop would run with most of a SIMD vector's lanes idle."""

from __future__ import annotations

import numpy as np

from blueprint.gpu.device import run_over
from blueprint.gpu.tables import table_fits, table_rows, table_texture

__all__ = ["gpu_cut_pairs"]

TRIANGLE_PAIRS_COMP = "blueprint.vector:glsl/triangle_pairs.comp"
TRIANGLE_CUTS_COMP = "blueprint.vector:glsl/triangle_cuts.comp"
_GROUP = 64
# The narrow phase's thresholds are loosened by this fraction of the touch tolerance, plus
# this fraction of the largest coordinate (rounding grows with it): the shader's doubles and
# NumPy's differ by less than 1e-14 of the largest coordinate.
_TOL_OF_EPS = 1e-3
_TOL_OF_COORD = 1e-12
# On a software rasteriser, partners in the grid per triangle from which the passes are used:
# below it they gain too little to pay for compiling them once a process.
SOFTWARE_MIN_PARTNERS = 40


def gpu_cut_pairs(renderer, grid, tri, normal, has_normal, hi, eps: float):
    """Pairs (i, j) of the boxes in ``grid`` (``lines.cell_grid`` of triangles ``tri`` (n, 3, 3)
    float64, ``hi`` their boxes' high corners with the slack added) that may cut through each
    other: every pair that ``lines._candidate_pairs`` finds and ``lines._triangle_pairs_cut``
    cuts, in ``_candidate_pairs``' order, and a few that it does not cut. ``normal`` (n, 3) and
    ``has_normal`` (n,) from ``lines._unit_normals``; ``eps`` the touch tolerance. None where
    the renderer runs no compute shaders, the grid does not fit its storage buffers, or (on a
    software rasteriser) NumPy is as fast: fewer than ``SOFTWARE_MIN_PARTNERS`` a triangle."""
    n, entries_n = len(tri), len(grid.owner)
    limit = int(renderer.ctx.info.get("GL_MAX_SHADER_STORAGE_BLOCK_SIZE", 0))
    if (
        renderer.ctx.version_code < 430
        or 16 * entries_n > limit
        or not table_fits(max(8 * n, entries_n), renderer.max_texture)
    ):
        return None
    partners = grid.cell_end - grid.group_end
    if renderer.software and int(partners.sum()) < SOFTWARE_MIN_PARTNERS * n:
        return None
    busy = np.flatnonzero(partners)
    empty = np.zeros(0, np.int64)
    if len(busy) == 0:
        return empty, empty
    # laid out whole for the table (8 texels a triangle), so that the texture takes it uncopied
    packed = np.zeros((table_rows(n, 8), 4, 4))
    packed[:n, :3, :3] = tri
    packed[:n, :3, 3] = hi
    packed[:n, 3, :3] = normal
    packed[:n, 3, 3] = has_normal
    # boxes in single precision, rounded outwards so that they overlap where the exact ones do
    lo = np.minimum(np.minimum(tri[:, 0], tri[:, 1]), tri[:, 2])
    rough = np.zeros((n, 2, 4), np.float32)
    rough[:, 0, :3] = _rounded(lo, -np.inf)
    rough[:, 1, :3] = _rounded(hi, np.inf)
    firsts = np.zeros((n, 4), np.int32)
    firsts[:, :3] = grid.first
    entries = np.zeros((len(busy), 4), np.int32)
    entries[:, 0] = busy
    entries[:, 1] = grid.group_end[busy]
    entries[:, 2] = grid.cell_end[busy]
    cells = np.zeros((len(busy), 4), np.int32)
    cells[:, :3] = grid.cells(busy)

    renderer.make_current()  # the first GL work of a drawing: another context may be current
    ctx = renderer.ctx
    tables = {
        # the doubles' bits, two a texel (triangles.glsl)
        "u_tris": packed.reshape(-1, 16).view(np.uint32).reshape(-1, 4),
        "u_owners": grid.owner.astype(np.int32),
        "u_boxes": rough.reshape(2 * n, 4),
        "u_firsts": firsts,
    }
    textures = {name: table_texture(ctx, data) for name, data in tables.items()}
    buffers = {
        binding: ctx.buffer(np.ascontiguousarray(data)) for binding, data in ((3, entries), (4, cells))
    }
    try:
        for unit, texture in enumerate(textures.values()):
            texture.use(location=unit)
        for binding, buffer in buffers.items():
            buffer.bind_to_storage_buffer(binding)
        prog = renderer.compute(TRIANGLE_PAIRS_COMP)
        _bind_tables(renderer, prog, textures)
        pairs_n, buffers[6] = _gathered(renderer, prog, len(busy), 6, max(4096, 8 * n))
        if pairs_n == 0:
            return empty, empty
        prog = renderer.compute(TRIANGLE_CUTS_COMP)
        _bind_tables(renderer, prog, textures)
        reach = max(-float(lo.min()), float(hi.max()), 0.0)
        tol = _TOL_OF_EPS * eps + _TOL_OF_COORD * reach
        for name, value in (("u_eps", eps), ("u_tol", tol), ("u_tol_span", tol)):
            renderer.uniforms.set(prog, name, float(value))
        found_n, buffers[7] = _gathered(renderer, prog, pairs_n, 7, max(4096, pairs_n // 4))
        data = buffers[7].read(size=8 * found_n, offset=8) if found_n else b""
    finally:
        for buffer in buffers.values():
            buffer.release()
        for texture in textures.values():
            texture.release()
    found = np.frombuffer(data, np.uint32).reshape(-1, 2).astype(np.int64)
    order = np.lexsort((found[:, 1], found[:, 0]))
    return grid.owner[found[order, 0]], grid.owner[found[order, 1]]


def _bind_tables(renderer, prog, textures: dict) -> None:
    """Point the program's table samplers at the units ``gpu_cut_pairs`` bound them to."""
    for unit, name in enumerate(textures):
        renderer.uniforms.set(prog, name, unit)


def _gathered(renderer, prog, count: int, binding: int, capacity: int):
    """Run ``prog`` over ``count`` invocations, each appending what it finds to the buffer at
    ``binding`` (a count, a word unused, then the items), grown and run again where it was too
    small: (items found, the buffer)."""
    ctx = renderer.ctx
    renderer.uniforms.set(prog, "u_count", count)
    while True:
        out = ctx.buffer(reserve=8 + 8 * capacity)
        out.write(np.zeros(2, np.uint32).tobytes())
        out.bind_to_storage_buffer(binding)
        renderer.uniforms.set(prog, "u_capacity", capacity)
        run_over(prog, count, _GROUP)
        ctx.memory_barrier()
        found = int(np.frombuffer(out.read(size=4), np.uint32)[0])
        if found <= capacity:
            return found, out
        out.release()
        capacity = found


def _rounded(values: np.ndarray, towards: float) -> np.ndarray:
    """float64 values as float32, rounded towards ``towards`` (-inf or inf) where not exact."""
    single = values.astype(np.float32)
    off = single < values if towards > 0 else single > values
    return np.where(off, np.nextafter(single, np.float32(towards)), single)
