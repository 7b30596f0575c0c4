"""Files written atomically get the permissions a file written in place would have."""

from __future__ import annotations

import os

import numpy as np

from blueprint.export.files import atomic_write, save_png


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
