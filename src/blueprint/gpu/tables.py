"""Tables for compute passes as textures: row ``i`` of an (N, C) array in texel
``(i % TABLE_WIDTH, i // TABLE_WIDTH)``, read with ``TABLE_ROW`` of ``table.glsl``. A
scattered read of a texture costs llvmpipe far less than one of a storage buffer (see
table.glsl); a GPU's own driver reads either as fast."""

from __future__ import annotations

import numpy as np

from blueprint import parallel

__all__ = ["TABLE_WIDTH", "table_fits", "table_of", "table_rows", "table_texture"]

# Rows a texture row (table.glsl's TABLE_WIDTH): a power of two, so that a shader finds the
# texel with a mask and a shift.
TABLE_WIDTH = 4096
_DTYPES = {"f": ("f4", np.float32), "i": ("i4", np.int32), "u": ("u4", np.uint32)}


def table_fits(rows: int, max_texture: int) -> bool:
    """Whether a table of ``rows`` rows fits a texture of at most ``max_texture`` a side."""
    return -(-rows // TABLE_WIDTH) <= max_texture


def table_rows(count: int, per_item: int = 1) -> int:
    """How many items of ``per_item`` rows each (a divisor of ``TABLE_WIDTH``), ``count`` or
    more, fill a table to the end of its last texture row: ``table_texture`` takes an array of
    that many rows as it is."""
    items = TABLE_WIDTH // per_item
    return max(-(-count // items), 1) * items


def table_texture(ctx, data: np.ndarray):
    """An (N,) or (N, C) array, C at most 4, as a texture of its rows (float32, int32 or
    uint32 by the array's kind; the last texture row padded with zeros). The caller releases it.
    N a multiple of ``TABLE_WIDTH`` (``table_rows``), of that type and contiguous, is not copied."""
    data = np.asarray(data)
    columns = 1 if data.ndim == 1 else data.shape[1]
    if not 1 <= columns <= 4 or data.ndim > 2:
        raise ValueError(f"a table has 1 to 4 columns, got an array of shape {data.shape}")
    dtype, kind = _DTYPES["i" if data.dtype.kind == "b" else data.dtype.kind]
    rows = max(-(-len(data) // TABLE_WIDTH), 1)
    # one copy at most (none where the caller laid the rows out whole), handed over as it is
    texels = data.reshape(len(data), columns)
    if len(data) != rows * TABLE_WIDTH or texels.dtype != kind or not texels.flags.c_contiguous:
        texels = np.empty((rows * TABLE_WIDTH, columns), kind)
        texels[: len(data)] = data.reshape(len(data), columns)
        texels[len(data) :] = 0
    texture = ctx.texture((TABLE_WIDTH, rows), columns, texels, dtype=dtype)
    texture.filter = (ctx.NEAREST, ctx.NEAREST)  # an integer texture filtered linearly reads as 0
    return texture


def table_of(data: np.ndarray, dtype) -> np.ndarray:
    """An (N,) or (N, C) array as ``dtype`` in an array of ``table_rows(N)`` rows, those past N
    zero: what ``table_texture`` takes as it is, so that a table cast from another type is
    written once, not cast and then copied into its texture's rows; a block of rows a thread."""
    table = np.empty((table_rows(len(data)), *data.shape[1:]), dtype)

    def copy(lo: int, hi: int) -> None:
        table[lo:hi] = data[lo:hi]

    parallel.run(copy, len(data))
    table[len(data) :] = 0
    return table
