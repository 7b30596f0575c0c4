"""Model file formats by suffix: one module a format, holding its ``Format`` record (suffixes,
up axis, unit, header checks, reader), and one line below to register it. A new format is a
module here and a line in this file; the loader, ``blueprint batch``'s folder search and the
messages that name formats ask ``FORMATS``.
"""

from __future__ import annotations

from blueprint.scene.formats import archives, dxml, gltf, obj, off, other, ply, step, stl, threemf
from blueprint.scene.formats.base import Converted, Format, Formats, Instance, Mesh

__all__ = ["FORMATS", "Converted", "Format", "Formats", "Instance", "Mesh"]

FORMATS = Formats()
FORMATS.add(obj.FORMAT)
FORMATS.add(stl.FORMAT)
FORMATS.add(ply.FORMAT)
FORMATS.add(off.FORMAT)
FORMATS.add(gltf.GLB)
FORMATS.add(gltf.GLTF)
FORMATS.add(threemf.FORMAT)
FORMATS.add(dxml.FORMAT)
FORMATS.add(step.FORMAT)
FORMATS.add(other.DAE)
FORMATS.add(other.XAML)
FORMATS.add(other.DXF)
FORMATS.add(other.XYZ)
FORMATS.add(archives.ZIP)
FORMATS.add(archives.GZ)
FORMATS.add(archives.BZ2)
FORMATS.add(archives.XZ)
