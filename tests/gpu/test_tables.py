"""Tables as textures (gpu/tables.py): a compute pass reads back every row as it was given."""

import numpy as np
import pytest

from blueprint.gpu.shaders import build_compute
from blueprint.gpu.tables import TABLE_WIDTH, table_fits, table_rows, table_texture

_READ = """
#include "table.glsl"
layout(local_size_x = 64) in;
uniform SAMPLER u_table;
uniform int u_count;
layout(std430, binding = 0) writeonly buffer Out { VEC out_rows[]; };
void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i < u_count) out_rows[i] = VEC(TABLE_ROW(u_table, i));
}
"""


@pytest.mark.parametrize(
    ("dtype", "sampler", "vec"),
    [
        (np.float32, "sampler2D", "vec4"),
        (np.int32, "isampler2D", "ivec4"),
        (np.uint32, "usampler2D", "uvec4"),
    ],
)
@pytest.mark.parametrize("rows", [TABLE_WIDTH + 37, table_rows(TABLE_WIDTH + 37)], ids=["padded", "whole"])
def test_rows_read_back(renderer, tmp_path, dtype, sampler, vec, rows):
    """Rows on either side of a texture row's end, and a table whose rows fill its texture
    (taken as it is)."""
    if renderer.ctx.version_code < 430:
        pytest.skip("no compute shaders")
    rng = np.random.default_rng(1)
    data = rng.integers(-(1 << 20), 1 << 20, (rows, 3)).astype(dtype)
    if dtype is np.float32:
        data += np.float32(0.125)
    source = tmp_path / "read.comp"
    source.write_text(_READ)
    ctx = renderer.ctx
    prog = build_compute(ctx, source, {"SAMPLER": sampler, "VEC": vec})
    texture = table_texture(ctx, data)
    out = ctx.buffer(reserve=16 * rows)
    try:
        texture.use(location=0)
        prog["u_table"].value = 0
        prog["u_count"].value = rows
        out.bind_to_storage_buffer(0)
        prog.run(-(-rows // 64))
        ctx.memory_barrier()
        got = np.frombuffer(out.read(), dtype).reshape(rows, 4)
    finally:
        out.release()
        texture.release()
    np.testing.assert_array_equal(got[:, :3], data)


def test_one_column_and_limits(renderer):
    texture = table_texture(renderer.ctx, np.arange(5, dtype=np.int32))
    try:
        assert texture.size == (TABLE_WIDTH, 1) and texture.components == 1
    finally:
        texture.release()
    assert table_rows(1, 8) == table_rows(TABLE_WIDTH // 8, 8) == TABLE_WIDTH // 8
    assert table_rows(TABLE_WIDTH // 8 + 1, 8) == TABLE_WIDTH // 4
    assert table_fits(TABLE_WIDTH * 16384, 16384) and not table_fits(TABLE_WIDTH * 16384 + 1, 16384)
    with pytest.raises(ValueError, match="1 to 4 columns"):
        table_texture(renderer.ctx, np.zeros((3, 5), np.float32))


@pytest.mark.parametrize("threads", [1, 3])
def test_a_table_cast_a_block_a_thread_is_the_rows_cast(threads, monkeypatch):
    """``table_of``: the rows cast to the table's type in their place, a block of rows a
    thread, the rows past them zero."""
    from blueprint import parallel, settings
    from blueprint.gpu.tables import table_of

    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 5)
    data = np.random.default_rng(3).normal(0, 1e3, (TABLE_WIDTH + 37, 3))
    table = table_of(data, np.float32)
    assert table.shape == (table_rows(len(data)), 3) and table.dtype == np.float32
    assert table[: len(data)].tobytes() == data.astype(np.float32).tobytes()
    assert not table[len(data) :].any()
