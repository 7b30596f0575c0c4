"""STL, binary and ASCII: Z-up by the convention of CAD and printing, no unit.

A binary file is read with NumPy alone, as trimesh reads it (three vertices a triangle, in
file order): trimesh, with the scipy and networkx it imports, takes most of a small drawing's
start. ASCII files, and binary files longer than their triangle count says, go to trimesh.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from blueprint import settings
from blueprint.errors import InputError
from blueprint.scene.formats.base import Format, Mesh
from blueprint.scene.headers import check_triangle_count
from blueprint.settings import open_file

__all__ = ["FORMAT", "read_stl"]

_RECORD = np.dtype([("normal", "<f4", 3), ("triangle", "<f4", (3, 3)), ("attribute", "<u2")])


def read_stl(path: Path, size: int) -> Mesh | None:
    """The triangles of a binary STL file, or None for trimesh (see the module's docstring).
    A binary file shorter than its count says is refused, as is a count over
    ``TRIANGLE_LIMIT``."""
    if size < 84:
        return None
    with open_file(path, settings.MODEL_FILE_LIMIT, "a model file") as fh:
        head = fh.read(84)
        count = int.from_bytes(head[80:84], "little")
        if size != 84 + _RECORD.itemsize * count:
            if size < 84 + _RECORD.itemsize * count and not _ascii_stl(head):
                raise InputError(
                    f"{path}: the header declares {count} triangles, more than the file's {size} bytes "
                    f"can hold ({84 + _RECORD.itemsize * count} bytes)"
                )
            return None
        check_triangle_count(path, count)
        records = np.frombuffer(fh.read(_RECORD.itemsize * count), dtype=_RECORD, count=count)
    triangles = records["triangle"]
    faces = np.arange(3 * count, dtype=np.int64).reshape(-1, 3)
    return Mesh(triangles.reshape(-1, 3), faces)


def _ascii_stl(head: bytes) -> bool:
    """Whether a file that begins with ``head`` can be ASCII STL: "solid", then text. Binary
    files may begin with "solid" too, but rarely go on in text for 84 bytes."""
    if not head.lstrip().lower().startswith(b"solid"):
        return False
    return all(32 <= b < 127 or b in (9, 10, 13) for b in head)


FORMAT = Format("STL", ("stl",), up="z", read=read_stl, common=True)
