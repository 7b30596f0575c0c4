"""Archives of model files: a zip, and one model (or a tar of them) compressed as a gz, bz2 or
xz stream. Their members are expanded within the limits of ``blueprint.scene.archive`` and read
by trimesh; the first member's format gives the model its up axis and unit."""

from __future__ import annotations

from blueprint.scene.formats.base import Format

__all__ = ["BZ2", "GZ", "XZ", "ZIP"]

ZIP = Format("zip", ("zip",), container="zip", trimesh=False)
GZ = Format("gzip", ("gz",), container="stream", trimesh=False)
BZ2 = Format("bzip2", ("bz2",), container="stream", trimesh=False)
XZ = Format("xz", ("xz",), container="stream", trimesh=False)
