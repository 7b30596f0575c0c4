"""Model file formats by suffix: one line below a format, its ``Format`` record (name, suffixes,
up axis, unit, what reads it), and a module here for a format with checks or a reader of its
own, whose functions the record names with ``deferred``: the module is imported when a file of
the format is first checked or read, so that the registry costs a drawing of one STL no other
format's reader. A new format is a line in this file (and its module); the loader,
``blueprint batch``'s folder search and the messages that name formats ask ``FORMATS``.

COLLADA, XAML, DXF and XYZ are read by trimesh with nothing of blueprint's but the loader's
checks (DXF and XYZ hold no triangles to draw: the loader says so in one line); the archives'
members are expanded within the limits of ``blueprint.scene.archive`` and read by trimesh, the
first member's format giving the model its up axis and unit.
"""

from __future__ import annotations

from blueprint.scene.formats.base import (
    Converted,
    Format,
    Formats,
    Instance,
    Mesh,
    Placed,
    deferred,
    placed_of,
)

__all__ = ["FORMATS", "Converted", "Format", "Formats", "Instance", "Mesh", "Placed", "deferred", "placed_of"]

_GLTF_METRES = "glTF is in metres by its specification"

FORMATS = Formats()
FORMATS.add(
    Format(
        "OBJ",
        ("obj",),
        up="guess",
        check=deferred("obj", "check"),
        read=deferred("obj", "read_obj"),
        common=True,
    )
)
FORMATS.add(Format("STL", ("stl",), up="z", read=deferred("stl", "read_stl"), common=True))
FORMATS.add(
    Format(
        "PLY",
        ("ply",),
        up="guess",
        check=deferred("ply", "check"),
        read=deferred("ply", "read_ply"),
        common=True,
    )
)
FORMATS.add(
    Format(
        "OFF",
        ("off",),
        up="guess",
        check=deferred("off", "check"),
        read=deferred("off", "read_off"),
        common=True,
    )
)
FORMATS.add(
    Format(
        "glTF",
        ("glb",),
        unit="m",
        unit_reason=_GLTF_METRES,
        check=deferred("gltf", "check_glb"),
        read=deferred("gltf", "read"),
        read_data=deferred("gltf", "read_data"),
        common=True,
    )
)
FORMATS.add(
    Format(
        "glTF",
        ("gltf",),
        unit="m",
        unit_reason=_GLTF_METRES,
        check=deferred("gltf", "check_gltf"),
        common=True,
    )
)
FORMATS.add(
    Format(
        "3MF",
        ("3mf",),
        up="z",
        stated_unit=deferred("threemf", "stated_unit"),
        check=deferred("threemf", "check"),
        common=True,
    )
)
FORMATS.add(
    Format(
        "3DXML",
        ("3dxml",),
        up="z",
        check=deferred("dxml", "check"),
        common=True,
        needs=(("lxml", "lxml"), ("networkx", "networkx")),
    )
)
FORMATS.add(
    Format(
        "STEP",
        ("step", "stp"),
        up="z",
        unit="m",
        unit_reason="OpenCASCADE meshes STEP in metres",
        read=deferred("step", "read_step"),
        trimesh=False,
        common=True,
    )
)
FORMATS.add(Format("DAE", ("dae",), up="z", needs=(("collada", "pycollada"),)))
FORMATS.add(Format("XAML", ("xaml",)))
FORMATS.add(Format("DXF", ("dxf",)))
FORMATS.add(Format("XYZ", ("xyz",)))
FORMATS.add(Format("zip", ("zip",), container="zip", trimesh=False))
FORMATS.add(Format("gzip", ("gz",), container="stream", trimesh=False))
FORMATS.add(Format("bzip2", ("bz2",), container="stream", trimesh=False))
FORMATS.add(Format("xz", ("xz",), container="stream", trimesh=False))
