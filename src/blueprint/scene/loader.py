"""Loading model files: the reader their format's record names (``blueprint.scene.formats``),
else trimesh, with validation that names the file and the problem."""

from __future__ import annotations

import functools
import io
import logging
import os
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from blueprint import parallel, settings
from blueprint.columns import ranges, runs
from blueprint.errors import InputError, out_of_memory
from blueprint.scene.environment import PartGlobs, choose_parts
from blueprint.scene.formats import FORMATS, Converted, Format, Instance, Mesh, Placed, placed_of
from blueprint.scene.headers import check_instance_count, check_triangle_count
from blueprint.scene.model import Model
from blueprint.scene.order import MIN_FACES, reordered_faces
from blueprint.scene.units import object_unit
from blueprint.scene.up import up_of
from blueprint.settings import MODEL_FILE_LIMIT, check_file, open_file, read_file
from blueprint.sorting import grouped

if TYPE_CHECKING:
    from blueprint.scene.instances import Instances

log = logging.getLogger("blueprint")

# The instances' modules and the archives' are imported by the files that need them: a drawing
# of one mesh (STL, OBJ, PLY, OFF) loads none of them.

# Beyond this, view and projection matrices overflow the GPU's 32-bit floats.
MAX_COORDINATE = settings.COORDINATE_LIMIT


def supported_formats() -> list[str]:
    """File extensions of the model formats read here, lower case without the dot."""
    return FORMATS.suffixes()


def load_model(
    path: str | os.PathLike, up: str | None = None, include: PartGlobs = None, exclude: PartGlobs = None
) -> Model:
    """Load a model file as one part per mesh instance, node transforms applied.

    Parameters
    ----------
    path : str or PathLike
        OBJ, STL (ASCII or binary), PLY, OFF, GLB/glTF, 3MF or any other format trimesh loads.
    up : {"y", "z"} or None
        Up axis for the named views; ``None`` guesses from the format.
    include, exclude : str or sequence of str and int, optional
        Parts to keep, and parts to leave out (name globs or indices); without ``include``,
        environment meshes (skyboxes, domes, huge ground planes) are left out, with a warning
        (see ``blueprint.scene.environment``).

    A mesh's faces keep the file's order, unless it holds ``scene.order.MIN_FACES`` faces or
    more and scatters them over the mesh: then they are put in an order that keeps neighbours
    together, which draws faster (each mesh of a scene on its own, its parts whole), and the
    triangle IDs of layers and lines index the model's ``faces`` in that order.

    Raises
    ------
    InputError
        The file is missing, unreadable, of an unknown format, or holds no usable triangles.
    """
    with out_of_memory(str(path), "the model is too large for this machine's memory"):
        return _load_model(Path(path), up, include, exclude)


def _load_model(path: Path, up: str | None, include: PartGlobs, exclude: PartGlobs) -> Model:
    name = str(path)
    info = check_file(path, MODEL_FILE_LIMIT, "a model file")
    if up is not None and up not in ("y", "z"):
        raise InputError(f"unknown up axis {up!r} (choose y or z)")
    ext, fmt = FORMATS.choose(path)
    if info.st_size == 0:
        raise InputError(f"{name}: file is empty")
    if fmt.container is not None:
        scene, ext = _archive_scene(path, ext)
        return _scene_model(scene, path.stem, name, up, ext, include, exclude)
    found = fmt.read(path, info.st_size) if fmt.read is not None else None
    if isinstance(found, Converted):
        # read by the reader of the format it was converted to, or else by trimesh; its up
        # axis and unit stay the file's format's
        converted, target = found, FORMATS.find(found.ext)
        found = target.read_data(path, converted.data) if target.read_data is not None else None
        if found is None:
            return _scene_model(_converted_scene(converted), path.stem, name, up, ext, include, exclude)
    if isinstance(found, Mesh):
        if len(found.faces) == 0:
            raise InputError(f"{name}: no triangles in the file")
        parts = np.zeros(len(found.faces), np.int32)
        # a soup's triangles were put in order as they were read, before its corners were
        # numbered (``formats.stl``)
        faces = found.faces if found.soup else reordered_faces(found.positions, found.faces)
        joined = (found.positions, faces, parts, [path.stem])
        return _loaded(joined, name, up, fmt, include, exclude, soup=found.soup)
    if isinstance(found, Placed):
        joined = _joined(found, path.stem, name, instanced=fmt.up != "guess")
        return _loaded(joined, name, up, fmt, include, exclude)
    fmt.check_header(path, info.st_size)
    return _scene_model(_load_scene(path, ext), path.stem, name, up, ext, include, exclude)


def _scene_model(
    scene, stem: str, name: str, up: str | None, ext: str, include: PartGlobs, exclude: PartGlobs
) -> Model:
    """The model of a trimesh scene read from a file of format ``ext`` (whose files may
    state their unit: trimesh reports it as the scene's)."""
    fmt = FORMATS.find(ext)
    stated = scene.units if fmt.stated_unit is not None else None
    joined = _flatten(scene, stem, name, instanced=fmt.up != "guess")
    return _loaded(joined, name, up, fmt, include, exclude, stated)


def _loaded(
    joined,
    name: str,
    up: str | None,
    fmt: Format,
    include: PartGlobs,
    exclude: PartGlobs,
    stated=None,
    soup: bool = False,
) -> Model:
    """The model of a scene's instances ``joined`` (``_joined``) read from a file of format
    ``fmt`` that states the unit ``stated`` (``Format.unit_of``); a soup's (``Model.soup``)
    where ``soup``."""
    positions, faces, face_part, names = joined
    if faces is None:  # kept as instances: the formats that do are not the ones guessing up
        return _checked_instances(
            positions, names, name, up, fmt.up, include, exclude, fmt.unit_of(name, stated)
        )
    if len(faces) == 0:
        raise InputError(f"{name}: no triangles in the file")
    guess = fmt.up == "guess"
    default = "y" if guess else fmt.up
    unit = fmt.unit_of(name, stated)
    return _checked(
        positions, faces, face_part, names, name, up, default, guess, include, exclude, unit, soup=soup
    )


def model_from_object(
    obj, up: str | None = None, name: str | None = None, include: PartGlobs = None, exclude: PartGlobs = None
) -> Model:
    """A model from an object of the Python ecosystem, checked as ``load_model`` checks files.

    Parameters
    ----------
    obj : Model, trimesh.Trimesh, trimesh.Scene or (vertices, faces)
        A ``trimesh.Scene`` gives one part per mesh instance, named from its node and geometry
        names, node transforms applied; a mesh or a pair of arrays ((V, 3) floats and (F, 3)
        vertex indices) gives one part.
    up : {"y", "z"} or None
        Up axis for the named views (default y; a Model keeps its own unless given).
    name : str, optional
        What messages call the object (default: its type).
    include, exclude : str or sequence of str and int, optional
        Parts to keep, and parts to leave out, as ``load_model`` takes them (a Model is kept
        whole when neither is given).

    Raises
    ------
    InputError
        In one line: an object that is not a mesh (a point cloud, a path), an empty scene,
        faces out of range, NaN or infinite vertices, only degenerate faces.
    """
    if up is not None and up not in ("y", "z"):
        raise InputError(f"unknown up axis {up!r} (choose y or z)")
    if isinstance(obj, Model):
        model = obj if up is None or up == obj.up else obj.replaced(up=up)
        if include is None and exclude is None:
            return model
        if model.instances is None:
            return choose_parts(model, include, exclude)
        from blueprint.scene.instanced_parts import choose_instanced_parts

        return choose_instanced_parts(model, include, exclude)
    if isinstance(obj, tuple | list) and len(obj) == 2:
        label = name or "(vertices, faces)"
        positions, faces = _pair(obj, label)
        if len(faces) == 0:
            raise InputError(f"{label}: no triangles")
        one_part = np.zeros(len(faces), np.int32)
        unit = (None, "arrays carry no unit")
        return _checked(positions, faces, one_part, ["mesh"], label, up, "y", False, include, exclude, unit)
    import trimesh

    if isinstance(obj, trimesh.Scene):
        label = name or "trimesh.Scene"
        positions, faces, face_part, names = _flatten(obj, None, instanced=True)
        if faces is None:
            unit = object_unit(obj.units)
            return _checked_instances(positions, names, label, up, "y", include, exclude, unit)
        if len(faces) == 0:
            raise InputError(f"{label}: no triangles in the scene (it holds no meshes with faces)")
    elif isinstance(obj, trimesh.Trimesh):
        label = name or "trimesh.Trimesh"
        positions, faces = np.asarray(obj.vertices, np.float64), np.asarray(obj.faces, np.int64)
        face_part, names = np.zeros(len(faces), np.int32), [str(obj.metadata.get("name") or "mesh")]
    elif isinstance(obj, trimesh.PointCloud):
        raise InputError(f"{name or 'trimesh.PointCloud'}: a point cloud has no triangles to draw")
    else:
        raise InputError(
            f"{name or type(obj).__name__}: cannot draw this object "
            "(give a file, a Model, a trimesh.Trimesh or trimesh.Scene, or (vertices, faces) arrays)"
        )
    if len(faces) == 0:
        raise InputError(f"{label}: no triangles")
    unit = object_unit(obj.units)
    return _checked(positions, faces, face_part, names, label, up, "y", False, include, exclude, unit)


def _pair(obj, label: str) -> tuple[np.ndarray, np.ndarray]:
    try:
        positions = np.asarray(obj[0], dtype=np.float64)
        faces = np.asarray(obj[1])
    except (TypeError, ValueError):
        raise InputError(f"{label}: vertices and faces must be arrays of numbers") from None
    if positions.ndim != 2 or positions.shape[1] != 3:
        raise InputError(f"{label}: vertices must be a (V, 3) array, got shape {positions.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3 or (faces.size and faces.dtype.kind not in "iu"):
        raise InputError(
            f"{label}: faces must be a (F, 3) array of vertex indices, got {faces.dtype} {faces.shape}"
        )
    return positions, faces.astype(np.int64)


def _checked(
    positions,
    faces,
    face_part,
    names,
    name: str,
    up: str | None,
    default_up: str,
    guess_up: bool = False,
    include: PartGlobs = None,
    exclude: PartGlobs = None,
    unit: tuple[str | None, str] = (None, "no unit given"),
    soup: bool = False,
) -> Model:
    """The checks every model passes, whether from a file or an object, named ``name``; its up
    axis ``up`` where given, else guessed from the shape (``guess_up``) or ``default_up``; the
    parts ``include`` and ``exclude`` choose; its length ``unit`` and where that came from;
    ``soup``: ``Model.soup``."""
    finite = np.isfinite(positions)
    if not finite.all():
        bad = ~finite.all(axis=1)
        raise InputError(f"{name}: {int(bad.sum())} vertices have NaN or infinite coordinates")
    del finite
    if max(positions.max(), -positions.min()) > MAX_COORDINATE:
        raise InputError(f"{name}: coordinates beyond {MAX_COORDINATE:g} cannot be drawn")
    if faces.min() < 0 or faces.max() >= len(positions):
        raise InputError(f"{name}: faces refer to vertices that do not exist")

    chosen = up_of(up, default_up, guess_up, positions, faces)
    model = Model(
        np.ascontiguousarray(positions, np.float32),
        np.ascontiguousarray(faces, np.int32),
        np.ascontiguousarray(face_part, np.int32),
        tuple(names),
        chosen.axis,
        name,
        chosen.reason,
        *unit,
        soup=soup,
    )
    # one pass over the faces' corners for every check that reads them: the environment's
    # (only where it is looked for) reads their extremes
    copies = len(model.faces) > settings.COINCIDENT_LIMIT
    keys = model.measure_faces(keys=copies, extremes=include is None and len(model.part_names) > 1)
    degenerate = model.degenerate_faces()
    if degenerate.all():
        raise InputError(f"{name}: all {len(faces)} faces are degenerate (zero area)")
    if copies:
        _check_coincident(keys, name)
    if degenerate.any():
        log.warning("%s: dropped %d degenerate faces", name, int(degenerate.sum()))
    return choose_parts(model, include, exclude)


# Keys the coincidence check hashes at a time, and about as many as share a bucket of its hash:
# a bucket holds more than ``COINCIDENT_LIMIT`` values of one copy alone, not by chance.
_BLOCK = 1 << 16
_PER_BUCKET = 16


def _checked_instances(
    inst: Instances,
    names,
    name: str,
    up: str | None,
    default_up: str,
    include: PartGlobs,
    exclude: PartGlobs,
    unit: tuple[str | None, str],
) -> Model:
    """``_checked`` of a scene kept as instances, from its unique meshes and transforms: it is
    never flattened here."""
    from blueprint.scene.instanced_parts import choose_instanced_parts
    from blueprint.scene.instances import mesh_degenerate, most_coincident

    bad = ~np.isfinite(inst.positions).all(axis=1)
    bad_per_mesh = np.add.reduceat(bad.astype(np.int64), inst.vertex_start[:-1])
    unplaced = ~np.isfinite(inst.transform).all(axis=(1, 2))
    count = int(np.where(unplaced, inst.mesh_vertices()[inst.mesh], bad_per_mesh[inst.mesh]).sum())
    if count:
        raise InputError(f"{name}: {count} vertices have NaN or infinite coordinates")
    chosen = up_of(up, default_up, False, None, None)
    model = Model(None, None, None, tuple(names), chosen.axis, name, chosen.reason, *unit, instances=inst)
    bounds = model.bounds
    if not np.isfinite(bounds).all() or np.abs(bounds).max() > MAX_COORDINATE:
        raise InputError(f"{name}: coordinates beyond {MAX_COORDINATE:g} cannot be drawn")
    degenerate = mesh_degenerate(inst)
    per_mesh = np.add.reduceat(degenerate.astype(np.int64), inst.face_start[:-1])
    dropped = int(per_mesh[inst.mesh].sum())
    if dropped == model.triangle_count:
        raise InputError(f"{name}: all {dropped} faces are degenerate (zero area)")
    limit = settings.COINCIDENT_LIMIT
    if model.triangle_count > limit and (most := most_coincident(inst)) > limit:
        raise InputError(
            f"{name}: {most} faces lie on one another (one triangle over and over), more than the "
            f"{limit} layers a drawing can peel"
        )
    if dropped:
        log.warning("%s: dropped %d degenerate faces", name, dropped)
    return choose_instanced_parts(model, include, exclude)


def _check_coincident(key: np.ndarray, name: str) -> None:
    """Refuse more than ``COINCIDENT_LIMIT`` copies of one triangle: each copy is a layer of
    its own to the peel, every layer draws them all, so 10^6 copies would take hours to draw
    and show one triangle. Copies share their faces' coincidence ``key``
    (``Model.measure_faces``)."""
    limit = settings.COINCIDENT_LIMIT
    if _bucketed_most(key) <= limit:
        return
    _, counts = np.unique(key, return_counts=True)
    most = int(counts.max())
    if most > limit:
        raise InputError(
            f"{name}: {most} faces lie on one another (one triangle over and over), more than the "
            f"{limit} layers a drawing can peel"
        )


def _bucketed_most(key: np.ndarray) -> int:
    """The most values of ``key`` (float64) in one bucket of a hash of their bits, some
    ``_PER_BUCKET`` values a bucket: at least the most copies of one value, found without a
    sort, each block's buckets counted side by side."""
    bits = min(22, max(10, (len(key) // _PER_BUCKET).bit_length()))
    counted = parallel.run(functools.partial(_bucket_counts, key, bits), len(key), min_block=_BLOCK)
    if any(counts is None for counts in counted):
        return len(key)  # a NaN
    total = counted[0]
    for counts in counted[1:]:
        total += counts
    return int(total.max())


def _bucket_counts(key: np.ndarray, bits: int, lo: int, hi: int) -> np.ndarray | None:
    """The values of ``key[lo:hi]`` in each of ``2 ** bits`` buckets of a hash of their bits;
    None where one is NaN."""
    block = key[lo:hi]
    if np.isnan(block).any():
        return None
    hashed = (block + 0.0).view(np.uint64)  # -0.0 is 0.0, as np.unique counts them
    hashed *= np.uint64(0x9E3779B97F4A7C15)
    hashed >>= np.uint64(64 - bits)
    return np.bincount(hashed.view(np.int64), minlength=1 << bits)


def _archive_scene(path: Path, kind: str):
    """The models in a zip archive or a compressed file (``kind``: zip, gz, bz2, xz) as one
    scene, expanded within the limits of ``blueprint.scene.archive``, and the format of the
    first (which decides the default up axis). Files the models reference (materials,
    textures, buffers) are looked up among the archive's members."""
    import trimesh

    from blueprint.scene.archive import members

    files = members(path, kind)
    loadable = {s for f in FORMATS if f.trimesh and f.container is None for s in f.suffixes}
    found = [(n, ext) for n in files if (ext := Path(n).suffix.lower().lstrip(".")) in loadable]
    if not found:
        listed = ", ".join(sorted(files)[:5]) + (", ..." if len(files) > 5 else "")
        raise InputError(f"{path}: the archive holds no model file (it holds: {listed or 'nothing'})")
    resolver = trimesh.resolvers.ZipResolver({n: io.BytesIO(d) for n, d in files.items()})
    scenes = []
    for member, ext in found:
        where = f"{path}: {member}"
        data = files[member]
        FORMATS.find(ext).check_header(Path(where), len(data), data)
        scenes.append(_trimesh_scene(where, ext, io.BytesIO(data), resolver))
    scene = scenes[0] if len(scenes) == 1 else trimesh.scene.scene.append_scenes(scenes)
    return scene, found[0][1]


def _converted_scene(converted: Converted):
    """trimesh's scene of a file converted to another format (STEP meshed into GLB)."""
    import trimesh

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return trimesh.load_scene(io.BytesIO(converted.data), file_type=converted.ext, process=False)
    except Exception:  # the converter wrote a file trimesh cannot read
        raise InputError(converted.failure) from None


def _load_scene(path: Path, ext: str):
    """trimesh's scene of the file ``path`` of format ``ext``, the files it references read
    through ``read_file``."""
    resolver = _resolver_type()(str(path))
    # an open file, not the name: trimesh names meshes after a file name and hashes the names
    # as UTF-8, which the bytes of a name that are not UTF-8 cannot be
    with open_file(path, MODEL_FILE_LIMIT, "a model file") as fh:
        scene = _trimesh_scene(str(path), ext, fh, resolver)
    if resolver.refused:
        # also where trimesh went on without the file: its OBJ loader drops materials it cannot
        # read, whatever the reason, but a reference to a FIFO or a device is a hostile file
        raise InputError(f"{path}: {resolver.refused[0]}")
    return scene


def _trimesh_scene(name: str, ext: str, fh, resolver):
    """trimesh's scene of the open file ``fh`` in format ``ext``, its failures as one line
    naming ``name``. trimesh's own messages are not for users ("list index out of range",
    "cannot reshape array of size 956 into shape (3)"), so none is passed on."""
    import trimesh

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            logging.getLogger("trimesh").setLevel(logging.ERROR)
            with np.errstate(all="ignore"):
                return trimesh.load_scene(fh, file_type=ext, process=False, resolver=resolver)
    except MemoryError:
        raise InputError(f"{name}: too large to load into this machine's memory") from None
    except RecursionError:
        raise InputError(f"{name}: cannot read as {ext.upper()}: it nests too deeply") from None
    except ImportError as exc:
        raise InputError(f"{name}: reading this file needs the Python package '{exc.name}'") from None
    except Exception:  # trimesh raises many types for broken files
        if getattr(resolver, "refused", None):
            return None  # the refusal, which trimesh may have wrapped, is the message
        raise InputError(
            f"{name}: cannot read as {ext.upper()} (the file is damaged or not in that format)"
        ) from None


@functools.cache
def _resolver_type():
    """trimesh's resolver of the files a model references (OBJ materials and textures, glTF
    buffers and images), reading each through ``read_file``: regular files only, each within
    the limit of a model file, and every refusal kept in ``refused``. Made on first use, as
    trimesh is imported on first use."""
    from trimesh.resolvers import FilePathResolver

    class CheckedResolver(FilePathResolver):
        def __init__(self, source: str, refused: list[InputError] | None = None) -> None:
            super().__init__(source)
            # trimesh's OBJ loader names meshes after this name: UTF-8 for the reason in _load_scene
            self.file_name = os.fsencode(self.file_name).decode("utf-8", "backslashreplace")
            self.refused = [] if refused is None else refused

        def get(self, name: str) -> bytes:
            # the names trimesh's own resolver tries, in its order
            for candidate in (name.strip(), name.strip().lstrip("/"), os.path.split(name)[-1]):
                try:
                    target = self.absolute(candidate)
                except ValueError:
                    continue
                if target.exists():
                    try:
                        return read_file(target, MODEL_FILE_LIMIT, "a file a model references")
                    except InputError as exc:
                        self.refused.append(exc)
                        raise
            return super().get(name)  # not found, or outside the model's folder: trimesh's error

        def namespaced(self, namespace: str):
            return CheckedResolver(os.path.join(self.parent, namespace), self.refused)

    return CheckedResolver


def _flatten(scene, stem: str | None, label: str = "the scene", instanced: bool = False):
    """Concatenate every mesh instance of a trimesh Scene in graph order, or keep them as
    instances (``_joined``)."""
    import trimesh

    world = _world_transforms(scene.graph)
    node_data = scene.graph.transforms.node_data
    instances = []
    for node in scene.graph.nodes_geometry:
        if node not in world:
            continue
        geometry = node_data[node].get("geometry")
        mesh = scene.geometry.get(geometry)
        arrays = (mesh.vertices, mesh.faces) if isinstance(mesh, trimesh.Trimesh) else (None, None)
        instances.append(Instance(str(node), str(geometry), *arrays, world[node]))
    return _joined(placed_of(instances, label), stem, label, instanced)


def _joined(placed: Placed, stem: str | None, label: str, instanced: bool = False):
    """Join a scene's instances (``Placed``) into one mesh, or where ``instanced`` and the
    scene draws its meshes several times over (``instances.worth_instancing``) keep them as
    instances: then (``Instances``, None, None, names). A scene of one instance names its part
    ``stem`` (a file's), or after its node where ``stem`` is None. More than
    ``INSTANCE_LIMIT`` instances or more triangles than the memory budget holds
    (``headers.check_triangle_count``, by their unique triangles where they are kept as
    instances) are refused naming ``label``, before any is placed.

    The instances of one mesh are placed together, a block of them at a time (one matrix
    product a block), into arrays made once at their joined size: 10^5 instances of a box
    cost their triangles, not 10^5 arrays of each kind. Meshes placed once each (10^5 small
    distinct parts) are placed a block of those of one vertex count at a time, and every
    instance's faces by one gather a block of instances."""
    check_instance_count(label, len(placed))
    mesh_faces = np.diff(placed.face_start)
    drawn = np.flatnonzero(mesh_faces[placed.mesh] > 0)
    used, first_use = np.unique(placed.mesh[drawn], return_index=True)
    used = used[np.argsort(first_use, kind="stable")]  # in order of first use
    total, unique = int(mesh_faces[placed.mesh[drawn]].sum()), int(mesh_faces[used].sum())
    if instanced:
        check_triangle_count(label, total, len(drawn), unique)
    else:
        check_triangle_count(label, total, len(drawn))
    if not len(drawn):
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros(0, np.int32), [stem or "mesh"]
    _check_own_vertices(placed, used, label)
    _in_local_order(placed, used)
    single = len(placed) == 1 and stem is not None
    taken: set[str] = set()
    counts: dict[str, int] = {}
    node, geometry = placed.node, placed.geometry
    if single:
        names = [stem]
    elif all(node[k] is not None and node[k].startswith(geometry[k]) for k in drawn.tolist()):
        names = [node[k] for k in drawn.tolist()]  # every part named after its node
    else:
        names = [_part_name(node[k], geometry[k], taken, counts) for k in drawn.tolist()]
    from blueprint.scene.instances import worth_instancing

    if instanced and worth_instancing(total, unique):
        return _kept_instances(placed, drawn, used), None, None, names
    return (*_flattened(placed, drawn), names)


def _check_own_vertices(placed: Placed, meshes: np.ndarray, label: str) -> None:
    """Refuse a face of ``meshes`` of ``placed`` that indexes past its own mesh's vertices, which
    joined or placed would name another mesh's (or, in 32 bits, wrap into range), naming
    ``label``; blocks of meshes side by side on the pool."""
    vertex_count = np.diff(placed.vertex_start)[meshes]
    face_count = np.diff(placed.face_start)[meshes]

    def fine(block: tuple[int, int]) -> bool:
        lo, hi = block
        start = placed.face_start[meshes[lo:hi]]
        if (meshes[lo + 1 : hi] == meshes[lo : hi - 1] + 1).all():
            local = placed.faces[start[0] : start[0] + face_count[lo:hi].sum()]  # meshes in a row
        else:
            local = placed.faces[ranges(start, face_count[lo:hi])]
        # a column at a time: NumPy reduces short rows slowly
        low = np.minimum(np.minimum(local[:, 0], local[:, 1]), local[:, 2])
        high = np.maximum(np.maximum(local[:, 0], local[:, 1]), local[:, 2])
        return low.min() >= 0 and not (high >= np.repeat(vertex_count[lo:hi], face_count[lo:hi])).any()

    if not all(parallel.each(fine, runs(face_count, _PLACED_ROWS))):
        raise InputError(f"{label}: faces refer to vertices that do not exist")


def _in_local_order(placed: Placed, meshes: np.ndarray) -> None:
    """Put the faces of each of ``meshes`` of ``placed`` that has ``order.MIN_FACES`` faces or
    more in a local order where the file scatters them (``order.reordered_faces``), in place:
    each mesh's faces stay its own, flattened or kept as instances. A loop over those meshes
    alone, at most the file's faces over ``MIN_FACES`` of them."""
    face_count = np.diff(placed.face_start)[meshes]
    for m in meshes[face_count >= MIN_FACES].tolist():
        lo, hi = placed.face_start[m], placed.face_start[m + 1]
        vertices = placed.vertices[placed.vertex_start[m] : placed.vertex_start[m + 1]]
        faces = placed.faces[lo:hi]
        ordered = reordered_faces(vertices, faces)
        if ordered is not faces:
            placed.faces[lo:hi] = ordered


def _kept_instances(placed: Placed, drawn: np.ndarray, used: np.ndarray) -> Instances:
    """The instances ``drawn`` of ``placed`` as the meshes ``used`` (in order of first use)
    placed by their transforms, a part each."""
    from blueprint.scene.instances import Instances

    vertex_count = np.diff(placed.vertex_start)[used]
    face_count = np.diff(placed.face_start)[used]
    faces = placed.faces[ranges(placed.face_start[used], face_count)]
    number = np.empty(len(placed.vertex_start) - 1, np.int32)
    number[used] = np.arange(len(used), dtype=np.int32)
    return Instances(
        placed.vertices[ranges(placed.vertex_start[used], vertex_count)].astype(np.float64),
        faces.astype(np.int32),
        np.r_[0, np.cumsum(vertex_count)],
        np.r_[0, np.cumsum(face_count)],
        number[placed.mesh[drawn]],
        placed.transform[drawn],
        np.arange(len(drawn), dtype=np.int32),
    )


# rows (vertices or faces) of instances placed by one matrix product
_PLACED_ROWS = 1 << 18


def _flattened(placed: Placed, drawn: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(V, 3) float64 positions, (F, 3) faces (int32, as the model holds them, where the
    vertices fit, else int64) and (F,) int32 parts of the instances ``drawn`` of ``placed``, a
    part each, joined in their order."""
    mesh = placed.mesh[drawn]
    vertex_count = np.diff(placed.vertex_start)[mesh]
    face_count = np.diff(placed.face_start)[mesh]
    vertex_start = np.cumsum(vertex_count) - vertex_count
    face_start = np.cumsum(face_count) - face_count
    positions = np.empty((int(vertex_count.sum()), 3))
    index = np.int32 if len(positions) <= np.iinfo(np.int32).max else np.int64
    faces = np.empty((int(face_count.sum()), 3), index)
    uses = np.bincount(mesh, minlength=len(placed.vertex_start) - 1)[mesh]
    # blocks of instances, each written to its own rows of the joined arrays: side by side on
    # the thread pool. The meshes drawn several times, a block of one mesh's instances at a
    # time; the meshes placed once (many small distinct parts), by their vertex count
    blocks = []
    shared = np.flatnonzero(uses > 1)
    for m, which in grouped(mesh[shared]):
        members = shared[which]
        # the mesh's vertices in double precision once, for all its blocks
        vertices = placed.vertices[placed.vertex_start[m] : placed.vertex_start[m + 1]].astype(np.float64)
        step = max(1, _PLACED_ROWS // max(len(vertices), int(face_count[members[0]])))
        blocks += [(vertices, members[first : first + step]) for first in range(0, len(members), step)]
    alone = np.flatnonzero(uses == 1)
    for count, which in grouped(vertex_count[alone]):
        members = alone[which]
        step = max(1, _PLACED_ROWS // max(count, 1))
        blocks += [(None, members[first : first + step]) for first in range(0, len(members), step)]

    def place(task) -> None:
        vertices, block = task
        # NaN and infinite vertices are refused with their count once joined, not warned about
        with np.errstate(all="ignore"):
            if vertices is not None:
                rows = vertex_start[block][:, None] + np.arange(len(vertices))
                _place(vertices[None], placed, drawn[block], rows, positions)
            else:
                at = np.arange(vertex_count[block[0]])
                stacked = placed.vertices[placed.vertex_start[mesh[block]][:, None] + at].astype(np.float64)
                _place(stacked, placed, drawn[block], vertex_start[block][:, None] + at, positions)

    def numbered(run: tuple[int, int]) -> None:
        # every instance's faces, numbering the joined vertices
        lo, hi = run
        rows = ranges(placed.face_start[mesh[lo:hi]], face_count[lo:hi])
        at = slice(face_start[lo], face_start[lo] + len(rows))
        faces[at] = placed.faces[rows] + np.repeat(vertex_start[lo:hi], face_count[lo:hi])[:, None]

    parallel.each(place, blocks)
    parallel.each(numbered, runs(face_count, _PLACED_ROWS))
    parts = np.repeat(np.arange(len(drawn), dtype=np.int32), face_count)
    return positions, faces, parts


def _place(vertices: np.ndarray, placed: Placed, instances: np.ndarray, rows: np.ndarray, positions) -> None:
    """Place ``vertices`` ((1, V, 3) of one mesh, or (B, V, 3) of one mesh an instance) at the
    ``instances`` (B,) of ``placed`` into the joined ``positions`` at their ``rows`` (B, V):
    each mesh's vertices times its instance's transform, one matrix product for them all."""
    moved = placed.moved[instances]
    if moved.any():
        stack = placed.transform[instances[moved]]
        chosen = vertices if len(vertices) == 1 else vertices[moved]
        turned = np.matmul(chosen, stack[:, :3, :3].transpose(0, 2, 1))
        positions[rows[moved]] = turned + stack[:, None, :3, 3]
    if not moved.all():
        positions[rows[~moved]] = vertices if len(vertices) == 1 else vertices[~moved]


def _world_transforms(graph) -> dict:
    """Every node reachable from the base frame, to its transform from the frame (None where no
    edge on the way has one), in one walk down the graph: asking trimesh node by node finds each path anew,
    which takes time quadratic in a chain's depth. A node on a cycle (trimesh keeps one parent a
    node) is not reachable, and left out."""
    forest = graph.transforms
    children: dict = {}
    for child, parent in forest.parents.items():
        if child != parent:
            children.setdefault(parent, []).append(child)
    world = {graph.base_frame: None}
    stack = [graph.base_frame]
    while stack:
        parent = stack.pop()
        above = world[parent]
        for child in children.get(parent, ()):
            if child in world:
                continue
            matrix = forest.edge_data[(parent, child)].get("matrix")
            if matrix is not None:
                matrix = np.asarray(matrix, dtype=np.float64)
            world[child] = matrix if above is None else (above if matrix is None else above @ matrix)
            stack.append(child)
    return world


def _part_name(node: str | None, geometry: str, taken: set[str], counts: dict[str, int]) -> str:
    """The node's name where it says more than its mesh's name (CAD instance paths), else the
    mesh's name (always where the node has none), numbered from the second instance on, so
    patterns like ``Piston*`` match.

    ``counts`` keeps the last number given per mesh, so that 10^5 instances of one mesh are
    named in one pass, not by trying every number from 2 against every name given."""
    if node is not None and node.startswith(geometry):
        name = node
    else:
        name, k = geometry, counts.get(geometry, 1)
        while name in taken:
            k += 1
            name = f"{geometry}[{k}]"
        counts[geometry] = k
    taken.add(name)
    return name
