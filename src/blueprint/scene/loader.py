"""Loading model files through trimesh, with validation that names the file and the problem."""

from __future__ import annotations

import logging
import os
import warnings
from pathlib import Path

import numpy as np

from blueprint.errors import InputError
from blueprint.scene.model import Model

log = logging.getLogger("blueprint")

# CAD and printing formats are Z-up by convention; glTF (by its spec), OBJ and scans are Y-up.
# Beyond this, view and projection matrices overflow the GPU's 32-bit floats.
MAX_COORDINATE = 1e18
_Z_UP = {"stl", "3mf", "3dxml", "step", "stp", "dae"}


def supported_formats() -> list[str]:
    """File extensions trimesh can load here, lower case without the dot."""
    import trimesh

    return sorted(trimesh.available_formats())


def load_model(path: str | os.PathLike, up: str | None = None) -> Model:
    """Load a model file as one part per mesh instance, node transforms applied.

    Parameters
    ----------
    path : str or PathLike
        OBJ, STL (ASCII or binary), PLY, OFF, GLB/glTF, 3MF or any other format trimesh loads.
    up : {"y", "z"} or None
        Up axis for the named views; ``None`` guesses from the format.

    Raises
    ------
    InputError
        The file is missing, unreadable, of an unknown format, or holds no usable triangles.
    """
    path = Path(path)
    name = str(path)
    if not path.exists():
        raise InputError(f"{name}: no such file")
    if path.is_dir():
        raise InputError(f"{name}: is a directory, not a model file")
    ext = path.suffix.lower().lstrip(".")
    formats = supported_formats()
    if ext not in formats:
        known = ", ".join(f for f in ("obj", "stl", "ply", "off", "glb", "gltf", "3mf") if f in formats)
        raise InputError(f"{name}: unknown model format '.{ext}' (supported: {known} and more)")
    if path.stat().st_size == 0:
        raise InputError(f"{name}: file is empty")
    if up is not None and up not in ("y", "z"):
        raise InputError(f"unknown up axis {up!r} (choose y or z)")

    scene = _load_scene(path)
    positions, faces, face_part, names = _flatten(scene, path.stem)
    if len(faces) == 0:
        raise InputError(f"{name}: no triangles in the file")
    bad = ~np.isfinite(positions).all(axis=1)
    if bad.any():
        raise InputError(f"{name}: {int(bad.sum())} vertices have NaN or infinite coordinates")
    if np.abs(positions).max() > MAX_COORDINATE:
        raise InputError(f"{name}: coordinates beyond {MAX_COORDINATE:g} cannot be drawn")
    if faces.min() < 0 or faces.max() >= len(positions):
        raise InputError(f"{name}: faces refer to vertices that do not exist")

    model = Model(
        np.ascontiguousarray(positions, np.float32),
        np.ascontiguousarray(faces, np.int32),
        np.ascontiguousarray(face_part, np.int32),
        tuple(names),
        up or ("z" if ext in _Z_UP else "y"),
        name,
    )
    degenerate = model.degenerate_faces()
    if degenerate.all():
        raise InputError(f"{name}: all {len(faces)} faces are degenerate (zero area)")
    if degenerate.any():
        log.warning("%s: dropped %d degenerate faces", name, int(degenerate.sum()))
    return model


def _load_scene(path: Path):
    import trimesh

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            logging.getLogger("trimesh").setLevel(logging.ERROR)
            return trimesh.load_scene(str(path), process=False)
    except MemoryError:
        raise InputError(f"{path}: too large to load into memory") from None
    except ImportError as exc:
        raise InputError(f"{path}: reading this file needs the Python package '{exc.name}'") from None
    except Exception as exc:  # trimesh raises many types for broken files
        detail = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{path}: cannot read as {path.suffix.lstrip('.').upper()}: {detail}") from None


def _flatten(scene, stem: str):
    """Concatenate every mesh instance of a trimesh Scene in graph order."""
    import trimesh

    positions, faces, parts, names = [], [], [], []
    offset = 0
    nodes = scene.graph.nodes_geometry
    for node in nodes:
        transform, geometry_name = scene.graph[node]
        mesh = scene.geometry.get(geometry_name)
        if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
            continue
        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        if not np.allclose(transform, np.eye(4)):
            vertices = vertices @ transform[:3, :3].T + transform[:3, 3]
        positions.append(vertices)
        faces.append(np.asarray(mesh.faces, dtype=np.int64) + offset)
        parts.append(np.full(len(mesh.faces), len(names), np.int32))
        names.append(stem if len(nodes) == 1 else _part_name(str(node), str(geometry_name), names))
        offset += len(vertices)
    if not faces:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros(0, np.int32), [stem]
    return np.concatenate(positions), np.concatenate(faces), np.concatenate(parts), names


def _part_name(node: str, geometry: str, taken: list[str]) -> str:
    """The node's name where it says more than its mesh's name (CAD instance paths), else the
    mesh's name, numbered from the second instance on, so patterns like ``Piston*`` match."""
    if node.startswith(geometry):
        return node
    name, k = geometry, 1
    while name in taken:
        k += 1
        name = f"{geometry}[{k}]"
    return name
