"""Formats trimesh reads with nothing of blueprint's but the loader's checks: COLLADA (Z-up,
needs pycollada), XAML meshes, and DXF and XYZ, which hold no triangles to draw (the loader
says so in one line)."""

from __future__ import annotations

from blueprint.scene.formats.base import Format

__all__ = ["DAE", "DXF", "XAML", "XYZ"]

DAE = Format("DAE", ("dae",), up="z", needs=(("collada", "pycollada"),))
XAML = Format("XAML", ("xaml",))
DXF = Format("DXF", ("dxf",))
XYZ = Format("XYZ", ("xyz",))
