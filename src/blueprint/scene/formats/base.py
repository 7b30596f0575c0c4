"""The record of a model file format, what its reader gives back, and the registry by suffix.

A format is one ``Format`` record: its suffixes, the up axis and length unit its specification
states, the checks of its header that run before any reader believes them, and its reader: a
NumPy reader of the common file, which answers None to leave the rest to trimesh. The loader
(``blueprint.scene.loader``) asks the registry, never the suffix itself. A record names the
functions of its format's module with ``deferred``: the module is imported when a file of the
format is first checked or read, not with the registry.
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from blueprint.errors import InputError

__all__ = ["Converted", "Format", "Formats", "Instance", "Mesh", "Placed", "deferred", "placed_of"]


# The reader's records are plain classes with slots: built at every import of the registry and
# made once a file, they need neither the generated methods nor a frozen dataclass's cost.
class Mesh:
    """One mesh read from a file, one part named after the file: ``positions`` (V, 3) float32
    or float64, ``faces`` (F, 3) integer indices into them; ``soup`` where the file lists
    every face's corners apart and ``positions`` are its distinct corners (``Model.soup``)."""

    __slots__ = ("positions", "faces", "soup")

    def __init__(self, positions: np.ndarray, faces: np.ndarray, soup: bool = False) -> None:
        self.positions, self.faces, self.soup = positions, faces, soup


class Instance:
    """One mesh placed in a scene: ``vertices`` (V, 3) and ``faces`` (F, 3) of its mesh
    (None where it is not a triangle mesh), ``transform`` (4, 4) float64 from the mesh to the
    scene (None: the identity), the names of its node and mesh (``node`` None: a frame with
    no name of its own, named after its mesh)."""

    __slots__ = ("node", "geometry", "vertices", "faces", "transform")

    def __init__(
        self,
        node: str | None,
        geometry: str,
        vertices: np.ndarray | None,
        faces: np.ndarray | None,
        transform: np.ndarray | None,
    ) -> None:
        self.node, self.geometry, self.vertices, self.faces = node, geometry, vertices, faces
        self.transform = transform


class Placed:
    """A scene read as columns: its meshes one after another, each once, and every instance
    of them in the scene's order. A reader of a scene of 10^5 parts makes these arrays, not
    10^5 records of arrays.

    vertices : (V, 3) float32 or float64, every mesh's vertices, mesh after mesh
    faces : (F, 3) int64, every mesh's faces, each numbering its own mesh's vertices from 0
    vertex_start, face_start : (M + 1,) int64, where mesh ``m``'s vertices and faces start
        (the last entry: their count); a mesh of no faces is not drawn
    mesh : (N,) int64, the mesh each instance draws
    transform : (N, 4, 4) float64, each instance's transform from its mesh to the scene
    moved : (N,) bool, False where the instance is its mesh as it is (no transform: the
        identity in ``transform``)
    node, geometry : lists of N names, each instance's node (None: a frame with no name of
        its own, named after its mesh) and mesh
    """

    __slots__ = (
        "vertices",
        "faces",
        "vertex_start",
        "face_start",
        "mesh",
        "transform",
        "moved",
        "node",
        "geometry",
    )

    def __init__(self, vertices, faces, vertex_start, face_start, mesh, transform, moved, node, geometry):
        self.vertices, self.faces = vertices, faces
        self.vertex_start, self.face_start = vertex_start, face_start
        self.mesh, self.transform, self.moved = mesh, transform, moved
        self.node, self.geometry = node, geometry

    def __len__(self) -> int:
        return len(self.mesh)


def placed_of(instances: list[Instance], label: str) -> Placed:
    """``instances`` as columns (``Placed``): the instances that share their vertex and face
    arrays share one mesh, kept once in the order of first use; an instance of no triangles
    (not a triangle mesh, or an empty one) draws a mesh of none. Vertices that are not rows
    of x, y and z (trimesh's OBJ reader cuts rows short on a broken file) are refused naming
    ``label`` and the mesh."""
    seen: dict[tuple[int, int] | None, int] = {}
    vertices, faces = [], []
    mesh = np.empty(len(instances), np.int64)
    for k, instance in enumerate(instances):
        drawn = instance.faces is not None and len(instance.faces) > 0
        key = (id(instance.vertices), id(instance.faces)) if drawn else None
        if key not in seen:
            seen[key] = len(vertices)
            if drawn:
                rows = np.asarray(instance.vertices, dtype=np.float64)
                if rows.ndim != 2 or rows.shape[1] != 3:
                    raise InputError(f"{label}: the vertices of mesh {instance.geometry!r} are not x, y, z")
                vertices.append(rows)
                faces.append(np.asarray(instance.faces, dtype=np.int64).reshape(-1, 3))
            else:
                vertices.append(np.zeros((0, 3)))
                faces.append(np.zeros((0, 3), np.int64))
        mesh[k] = seen[key]
    moved = np.array([i.transform is not None for i in instances], bool)
    transform = np.broadcast_to(np.eye(4), (len(instances), 4, 4)).copy()
    if moved.any():
        transform[moved] = np.array([i.transform for i in instances if i.transform is not None], np.float64)
    return Placed(
        np.concatenate(vertices) if vertices else np.zeros((0, 3)),
        np.concatenate(faces) if faces else np.zeros((0, 3), np.int64),
        np.r_[0, np.cumsum([len(v) for v in vertices], dtype=np.int64)],
        np.r_[0, np.cumsum([len(f) for f in faces], dtype=np.int64)],
        mesh,
        transform,
        moved,
        [i.node for i in instances],
        [i.geometry for i in instances],
    )


class Converted:
    """A file turned into the bytes ``data`` of another format ``ext`` (STEP meshed into GLB),
    which that format's reader reads; ``failure`` is the message where trimesh cannot."""

    __slots__ = ("data", "ext", "failure")

    def __init__(self, data: bytes, ext: str, failure: str) -> None:
        self.data, self.ext, self.failure = data, ext, failure


#: What a reader gives back: one mesh, a scene's meshes and their instances, the file
#: converted to another format, or None where trimesh reads the file.
Read = Mesh | Placed | Converted | None


class _Deferred:
    """A function of a module of ``blueprint.scene.formats``, imported at the first call."""

    __slots__ = ("_function", "module", "name")

    def __init__(self, module: str, name: str) -> None:
        self.module, self.name, self._function = module, name, None

    def __call__(self, *args, **kwargs):
        if self._function is None:
            self._function = getattr(importlib.import_module(self.module), self.name)
        return self._function(*args, **kwargs)

    def __repr__(self) -> str:
        return f"deferred({self.module.rsplit('.', 1)[-1]!r}, {self.name!r})"


def deferred(module: str, name: str) -> Callable:
    """The function ``name`` of ``blueprint.scene.formats.<module>``, which is imported when the
    function is first called: every format is registered, few are read in one process.

    Parameters
    ----------
    module : str
        The format's module in ``blueprint.scene.formats`` ("stl").
    name : str
        A function of it ("read_stl").
    """
    return _Deferred(f"{__package__}.{module}", name)


def _no_unit(fmt: Format, name: str, stated: str | None) -> tuple[str | None, str]:
    return fmt.unit, fmt.unit_reason or f"{fmt.name} files carry no unit"


# compared and hashed by identity: each format is one registered record
@dataclass(frozen=True, eq=False)
class Format:
    """A model file format.

    Parameters
    ----------
    name : str
        What messages call it ("STL").
    suffixes : tuple of str
        File suffixes, lower case without the dot; the first names the format to trimesh.
    up : {"y", "z", "guess"}
        The up axis its files have by convention, or "guess": none, the shape decides
        (``blueprint.scene.up``).
    unit, unit_reason : str or None, str
        The length unit its specification states (a name of ``blueprint.scene.units.UNITS_MM``)
        and where that comes from; None where files carry none.
    stated_unit : callable, optional
        ``stated_unit(name, stated) -> (unit, reason)``: the unit of a file of the format named
        ``name`` that states ``stated`` (as trimesh reports it), for formats whose files state
        their own (3MF).
    check : callable, optional
        ``check(path, size, data)``: raises ``InputError`` where the header declares more than
        ``size`` bytes can hold, or a graph that is hostile; run before trimesh reads a file
        (``data``: its bytes where they are in memory, a member of an archive).
    read : callable, optional
        ``read(path, size) -> Mesh | Placed | Converted | None``: the fast reader of a
        file of ``size`` bytes; None leaves the file to trimesh.
    read_data : callable, optional
        ``read_data(path, data) -> Mesh | Placed | None``: the same of the bytes
        ``data`` in memory (a file another format's reader converted to this one).
    trimesh : bool
        Whether trimesh reads what ``read`` leaves (and the members of archives of the format).
    container : {"zip", "stream"} or None
        An archive of model files: a zip, or one compressed stream (gz, bz2, xz).
    common : bool
        Named in messages and searched for in folders (``blueprint batch``).
    needs : tuple of (str, str)
        Optional packages trimesh's reader of the format imports, as (module, package to
        install): a file of the format is refused in one line where one is missing.
    """

    name: str
    suffixes: tuple[str, ...]
    up: str = "y"
    unit: str | None = None
    unit_reason: str = ""
    stated_unit: Callable[[str, str | None], tuple[str | None, str]] | None = None
    check: Callable[[Path, int, bytes | None], None] | None = None
    read: Callable[[Path, int], Read] | None = None
    read_data: Callable[[Path, bytes], Read] | None = None
    trimesh: bool = True
    container: str | None = None
    common: bool = False
    needs: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        if self.up not in ("y", "z", "guess"):
            raise ValueError(f"up must be 'y', 'z' or 'guess', got {self.up!r}")
        if not self.suffixes or any(s != s.lower() or s.startswith(".") for s in self.suffixes):
            raise ValueError(f"suffixes are lower case without the dot, got {self.suffixes!r}")

    def unit_of(self, name: str, stated: str | None = None) -> tuple[str | None, str]:
        """The length unit of a model read from the file ``name`` of this format, and where it
        comes from; ``stated``: the unit the file states, where the format lets it."""
        if self.stated_unit is not None:
            return self.stated_unit(name, stated)
        return _no_unit(self, name, stated)

    def check_header(self, path: Path, size: int, data: bytes | None = None) -> None:
        """Run ``check`` where the format has one, after refusing a file whose reader needs a
        package that is not installed."""
        for module, package in self.needs:
            if importlib.util.find_spec(module) is None:
                raise InputError(f"{path}: reading this file needs the Python package '{package}'")
        if self.check is not None:
            self.check(path, size, data)


class Formats:
    """Formats by suffix, in the order registered (the order messages name them in)."""

    def __init__(self) -> None:
        self._formats: list[Format] = []
        self._by_suffix: dict[str, Format] = {}

    def add(self, fmt: Format) -> Format:
        """Register ``fmt`` under each of its suffixes."""
        taken = [s for s in fmt.suffixes if s in self._by_suffix]
        if taken:
            raise ValueError(f"suffix {taken[0]!r} is registered already")
        self._formats.append(fmt)
        self._by_suffix.update(dict.fromkeys(fmt.suffixes, fmt))
        return fmt

    def __iter__(self) -> Iterator[Format]:
        return iter(self._formats)

    def find(self, suffix: str) -> Format | None:
        """The format of files ending in ``suffix`` (any case, with or without the dot)."""
        return self._by_suffix.get(suffix.lower().lstrip("."))

    def suffixes(self) -> list[str]:
        """Every suffix registered, sorted."""
        return sorted(self._by_suffix)

    def common_suffixes(self) -> tuple[str, ...]:
        """The suffixes of the common model formats, in the order registered."""
        return tuple(s for f in self._formats if f.common for s in f.suffixes)

    def choose(self, path: Path) -> tuple[str, Format]:
        """The suffix of ``path`` (lower case, no dot) and its format, or ``InputError`` in one
        line naming the common formats and the archives."""
        ext = path.suffix.lower().lstrip(".")
        fmt = self.find(ext)
        if fmt is None:
            common = ", ".join(self.common_suffixes())
            archives = ", ".join(s for f in self._formats if f.container for s in f.suffixes)
            raise InputError(
                f"{path}: unknown model format '.{ext}' (supported: {common} and more; {archives} of them)"
            )
        return ext, fmt

    def unit(self, name: str, ext: str, stated: str | None = None) -> tuple[str | None, str]:
        """The length unit of a model read from the file ``name`` of format ``ext`` (its
        suffix) that states ``stated``, and where it comes from (``Format.unit_of``)."""
        fmt = self.find(ext)
        if fmt is None:
            return None, f"{ext.upper()} files carry no unit"
        return fmt.unit_of(name, stated)
