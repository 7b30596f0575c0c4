"""Files written atomically get the permissions a file written in place would have; PNG bytes
decode to the pixels written."""

from __future__ import annotations

import io
import os
import zlib

import numpy as np
import pytest
from PIL import Image

from blueprint import settings
from blueprint.export import files
from blueprint.export.files import atomic_write, png_bytes, save_png


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_new_file_follows_the_umask_not_the_private_temporary(tmp_path):
    saved = os.umask(0o027)
    try:
        path = save_png(tmp_path / "new.png", np.zeros((4, 4, 4), np.uint8))
    finally:
        os.umask(saved)
    assert path.stat().st_mode & 0o777 == 0o640
    assert _umask() == saved


def test_replaced_file_keeps_its_permissions(tmp_path):
    path = tmp_path / "old.txt"
    path.write_text("old")
    path.chmod(0o604)
    atomic_write(path, lambda tmp: tmp.write_text("new"))
    assert path.read_text() == "new"
    assert path.stat().st_mode & 0o777 == 0o604
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.txt"]


@pytest.mark.parametrize("shape", [(5, 7), (5, 7, 1), (5, 7, 2), (5, 7, 3), (5, 7, 4), (1, 1, 4)])
def test_png_bytes_decode_to_the_same_pixels(tmp_path, shape):
    image = np.random.default_rng(3).integers(0, 256, size=shape, dtype=np.uint8)
    data = png_bytes(image)
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    # decoded by an independent reader, every chunk's CRC checked on the way
    decoded = Image.open(io.BytesIO(data))
    decoded.load()
    expected_mode = {1: "L", 2: "LA", 3: "RGB", 4: "RGBA"}[1 if len(shape) == 2 else shape[2]]
    assert decoded.mode == expected_mode
    np.testing.assert_array_equal(np.asarray(decoded).reshape(shape), image)
    assert save_png(tmp_path / "x.png", image).read_bytes() == data


@pytest.mark.parametrize("threads", [1, 3])
def test_png_rows_deflated_in_pieces_decode_to_the_same_pixels(monkeypatch, threads):
    """Rows of many pieces are deflated a piece at a time side by side, the pieces one zlib
    stream: an independent reader decodes the pixels, zlib checks the stream's checksum."""
    monkeypatch.setattr(files, "_PNG_PIECE", 1000)
    monkeypatch.setattr(settings, "THREADS", threads)
    image = np.random.default_rng(5).integers(0, 4, size=(90, 110, 4), dtype=np.uint8) * 60
    image[30:60] = 255  # runs that deflate back-references would reach across pieces for
    data = png_bytes(image)
    decoded = Image.open(io.BytesIO(data))
    decoded.load()
    np.testing.assert_array_equal(np.asarray(decoded), image)
    start = data.index(b"IDAT") + 4
    rows = zlib.decompress(data[start : start + int.from_bytes(data[start - 8 : start - 4], "big")])
    assert len(rows) == 90 * (1 + 110 * 4)


@pytest.mark.parametrize(
    "image", [np.zeros((4, 4, 3), np.float32), np.zeros((4, 4, 5), np.uint8), np.zeros((0, 4, 3), np.uint8)]
)
def test_png_bytes_refuses_what_png_cannot_hold(image):
    with pytest.raises(ValueError, match="a PNG image is"):
        png_bytes(image)
