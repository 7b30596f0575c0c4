"""GPU-free model data: triangles, parts and their names."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, fields
from functools import partial
from typing import TYPE_CHECKING

import numpy as np

from blueprint import parallel
from blueprint.columns import column_cross, face_cross, indexed_cross, used_bounds
from blueprint.scene.headers import check_triangle_count
from blueprint.scene.units import UNITS_MM

if TYPE_CHECKING:
    from blueprint.scene.instances import Instances

# The instances' module is imported by the models kept as instances: a flat model's drawing
# loads none of it.


class _Flattened:
    """A model's ``positions``, ``faces`` or ``face_part``: the array given, or for a model
    kept as instances (given None) the flattened scene's, made on first read and kept; refused
    in one line (``headers.check_triangle_count``) where its drawn triangles, flattened, would
    pass the memory budget that its unique ones passed."""

    def __set_name__(self, owner, name: str) -> None:
        self.name, self.key = name, "_" + name

    def __get__(self, model, owner=None):
        if model is None:
            raise AttributeError(self.name)  # a field without a default
        value = model.__dict__[self.key]
        if value is None:
            from blueprint.scene.instances import flatten

            inst = model.instances
            check_triangle_count(model.source or "the model", inst.triangle_count, len(inst.mesh))
            positions, faces, face_part = flatten(inst)
            model.__dict__.update(_positions=positions, _faces=faces, _face_part=face_part)
            value = model.__dict__[self.key]
        return value

    def __set__(self, model, value) -> None:
        model.__dict__[self.key] = value


# Mesh bytes below which BLAKE2b, loaded without OpenSSL, digests sooner than SHA-256 through
# OpenSSL, loading included (docs/performance.md).
_SMALL_DIGEST = 1 << 21
_FLATTENED = ("positions", "faces", "face_part")
# Bytes of a big mesh's array digested at a time (``Model.content_digest``).
_DIGEST_BLOCK = 1 << 23


def _block_digests(data: np.ndarray, first: int, last: int) -> bytes:
    """The SHA-256 digests of blocks ``first`` to ``last`` of ``_DIGEST_BLOCK`` bytes of
    ``data`` (uint8), one after another."""
    import hashlib

    return b"".join(
        hashlib.sha256(data[k * _DIGEST_BLOCK : (k + 1) * _DIGEST_BLOCK]).digest() for k in range(first, last)
    )


@dataclass(frozen=True, eq=False, repr=False)
class Model:
    """A triangle model split into named parts.

    Parameters
    ----------
    positions : (V, 3) float32
        Vertex positions in model coordinates, scene transforms applied.
    faces : (F, 3) int32
        Vertex indices per triangle. Face ``i`` is triangle ID ``i`` in every buffer.
    face_part : (F,) int32
        Part index of each face.
    part_names : tuple of str
        One name per part (a scene's node name, or the file's stem for a single mesh).
    up : {"y", "z"}
        The model's up axis, used by the named views.
    source : str or None
        The file it came from, for messages.
    up_reason : str
        Where ``up`` came from ("given", "by the format", or how the shape decided it), for
        ``blueprint info`` and printed lines.
    unit : str or None
        The length unit of ``positions`` (a name of ``blueprint.scene.units.UNITS_MM``) where
        the file states one (glTF, STEP: ``"m"``; 3MF: its own); None where it does not, and
        drawings to scale assume millimetres (``blueprint.scene.units.drawing_unit``).
    unit_reason : str
        Where ``unit`` came from, or why there is none, for ``blueprint info`` and warnings.
    instances : Instances or None
        The scene as unique meshes and instances placing them (``blueprint.scene.instances``),
        where it is kept so; ``positions``, ``faces`` and ``face_part`` are then given as None
        and are the flattened scene's, made on first read (``is_flat`` says whether they are).
    soup : bool
        The file listed every face's corners apart (a triangle soup: STL) and ``positions``
        are its distinct corners, bit for bit, numbered by first corner: prepared for the GPU
        (``scene.prepare``) as every corner a vertex of its own would be.
    """

    positions: np.ndarray = _Flattened()
    faces: np.ndarray = _Flattened()
    face_part: np.ndarray = _Flattened()
    part_names: tuple[str, ...]
    up: str = "y"
    source: str | None = None
    up_reason: str = "given"
    unit: str | None = None
    unit_reason: str = "no unit given"
    instances: Instances | None = None
    soup: bool = False
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.up not in ("y", "z"):
            raise ValueError(f"up must be 'y' or 'z', got {self.up!r}")
        if self.unit is not None and self.unit not in UNITS_MM:
            raise ValueError(f"unit must be one of {', '.join(UNITS_MM)} or None, got {self.unit!r}")
        if self.instances is not None:
            part = self.instances.part
            if len(part) and (part.min() < 0 or part.max() >= len(self.part_names)):
                raise ValueError("instances refer to parts that do not exist")
            return
        if self.__dict__["_positions"] is None:
            raise ValueError("a model without positions must be kept as instances")
        if self.positions.ndim != 2 or self.positions.shape[1] != 3:
            raise ValueError(f"positions must be (V, 3), got {self.positions.shape}")
        if self.faces.ndim != 2 or self.faces.shape[1] != 3:
            raise ValueError(f"faces must be (F, 3), got {self.faces.shape}")
        if self.face_part.shape != (len(self.faces),):
            raise ValueError("face_part must have one entry per face")
        if len(self.faces) and (self.faces.min() < 0 or self.faces.max() >= len(self.positions)):
            raise ValueError("faces refer to vertices that do not exist")
        if len(self.face_part) and (self.face_part.min() < 0 or self.face_part.max() >= len(self.part_names)):
            raise ValueError("face_part refers to parts that do not exist")

    def __repr__(self) -> str:
        kind = f"{len(self.instances.mesh)} instances" if self.instances is not None else "flat"
        return (
            f"Model({self.source or 'arrays'}: {self.triangle_count} triangles, "
            f"{len(self.part_names)} parts, {kind}, up {self.up})"
        )

    @property
    def is_flat(self) -> bool:
        """Whether the flattened arrays are at hand: always, unless the model is kept as
        instances and no reader has asked for them yet."""
        return self.__dict__["_positions"] is not None

    def replaced(self, **changes) -> Model:
        """``dataclasses.replace`` that leaves a model kept as instances unflattened (its cache
        dropped, as the values it holds may change)."""
        given = {
            f.name: getattr(self, f.name)
            for f in fields(self)
            if f.init and f.name not in (*_FLATTENED, "_cache")
        }
        # a model's own flattened arrays, unless its instances change
        kept = self.instances is None or "instances" not in changes
        given.update({name: self.__dict__["_" + name] if kept else None for name in _FLATTENED})
        return Model(**{**given, **changes})

    @classmethod
    def from_arrays(
        cls,
        positions: np.ndarray,
        faces: np.ndarray,
        face_part: np.ndarray | None = None,
        part_names: tuple[str, ...] | list[str] | None = None,
        up: str = "y",
        source: str | None = None,
        unit: str | None = None,
    ) -> Model:
        """Build a model from plain arrays (one part unless ``face_part`` says otherwise), its
        length unit ``unit`` where given."""
        positions = np.ascontiguousarray(positions, dtype=np.float32)
        faces = np.ascontiguousarray(faces, dtype=np.int32)
        if face_part is None:
            face_part = np.zeros(len(faces), np.int32)
        face_part = np.ascontiguousarray(face_part, dtype=np.int32)
        if part_names is None:
            count = int(face_part.max()) + 1 if len(face_part) else 1
            part_names = tuple(f"part{i}" for i in range(count))
        reason = "given" if unit is not None else "no unit given"
        return cls(positions, faces, face_part, tuple(part_names), up, source, unit=unit, unit_reason=reason)

    @property
    def triangle_count(self) -> int:
        if self.instances is not None:
            return self.instances.triangle_count
        return len(self.faces)

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) float64: minimum and maximum corner of the used vertices."""
        # every camera fit asks (the viewer: every frame), and a model's arrays do not change
        if "bounds" not in self._cache and self.instances is not None:
            boxes = self.instance_boxes()
            self._cache["bounds"] = np.array([boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)])
        if "bounds" not in self._cache:
            self._cache["bounds"] = used_bounds(self.positions, self.faces)
        return self._cache["bounds"].copy()

    def instance_boxes(self) -> np.ndarray:
        """(N, 2, 3) float64: each instance's bounds (``instances.instance_boxes``), made once;
        only for a model kept as instances."""
        if "instance_boxes" not in self._cache:
            from blueprint.scene.instances import instance_boxes

            self._cache["instance_boxes"] = instance_boxes(self.instances)
        return self._cache["instance_boxes"]

    def placed_points(self, keep: np.ndarray | None = None):
        """An iterator of (N, 3) float64 blocks of the placed vertices of a model kept as
        instances (of the instances ``keep``, (N,) bool flags, where given): the flattened
        model's positions, a block of instances at a time."""
        from blueprint.scene.instances import placed_blocks

        return (block.reshape(-1, 3).astype(np.float64) for block in placed_blocks(self.instances, keep))

    def content_digest(self) -> bytes:
        """A cryptographic digest of the triangles (positions, faces, parts and the part count;
        of a model kept as instances, its meshes and instances): models with one digest draw
        alike, so work kept by it serves a file loaded again. BLAKE2b of a mesh of fewer than
        ``_SMALL_DIGEST`` bytes, else SHA-256 with each array's bytes given as the SHA-256
        digests of its blocks of ``_DIGEST_BLOCK`` bytes (digested side by side, whatever the
        thread count the same). Made once."""
        if "digest" not in self._cache:
            i = self.instances
            arrays = (
                (self.positions, self.faces, self.face_part)
                if i is None
                else (i.positions, i.faces, i.vertex_start, i.face_start, i.mesh, i.transform, i.part)
            )
            small = sum(array.nbytes for array in arrays) < _SMALL_DIGEST
            if small:
                # a small mesh hashes faster than hashlib's OpenSSL loads; the digests live in
                # this process's caches alone, and the size fixes the hash of each content
                from _blake2 import blake2b as new_digest
            else:
                import hashlib

                new_digest = hashlib.sha256
            digest = new_digest()
            for array in arrays:
                digest.update(str((array.dtype.str, array.shape)).encode())
                data = np.ascontiguousarray(array).reshape(-1).view(np.uint8)
                if small:
                    digest.update(data)
                else:
                    # a big mesh's blocks digested side by side, their digests digested in order
                    blocks = -(-len(data) // _DIGEST_BLOCK)
                    for found in parallel.run(partial(_block_digests, data), blocks, min_block=1):
                        digest.update(found)
            digest.update(str(len(self.part_names)).encode())
            self._cache["digest"] = digest.digest()
        return self._cache["digest"]

    def parts_of(self, faces: np.ndarray) -> np.ndarray:
        """The part of each face of ``faces`` (any shape, int): ``face_part[faces]``, of a
        model kept as instances found from its instances' first faces."""
        if self.instances is None or self.is_flat:
            return self.face_part[faces]
        i = self.instances
        return i.part[np.searchsorted(i.first_face(), faces, side="right") - 1]

    def part_triangle_counts(self) -> np.ndarray:
        """(P,) int64: triangles per part, counted once (read-only: the viewer's heads-up line
        asks each frame a part is picked)."""
        if "part_counts" not in self._cache:
            if self.instances is not None:
                i = self.instances
                counts = np.bincount(i.part, weights=i.instance_faces(), minlength=len(self.part_names))
            else:
                counts = np.bincount(self.face_part, minlength=len(self.part_names))
            counts = counts.astype(np.int64)
            counts.setflags(write=False)
            self._cache["part_counts"] = counts
        return self._cache["part_counts"]

    def corners(self) -> np.ndarray:
        """(F, 3, 3) float64: every face's corners, made anew unless ``holding_corners``."""
        held = self._cache.get("corners")
        return self.positions[self.faces].astype(np.float64) if held is None else held

    def corner_cross(self) -> np.ndarray:
        """(F, 3) float64: ``columns.face_cross`` of ``corners()``, held as they are."""
        if "corners" not in self._cache:
            return indexed_cross(self.positions, self.faces)
        if "corner_cross" not in self._cache:
            self._cache["corner_cross"] = face_cross(self._cache["corners"])
        return self._cache["corner_cross"]

    @contextmanager
    def holding_corners(self) -> Iterator[None]:
        """Hold ``corners()`` and ``corner_cross()`` while the block runs, for work that reads
        every face's corners more than once (the loader's checks, a vector drawing's lines
        and planes): made once, not kept with the model (4 times its own size)."""
        if "corners" in self._cache:
            yield
            return
        self._cache["corners"] = self.positions[self.faces].astype(np.float64)
        try:
            yield
        finally:
            self._cache.pop("corners", None)
            self._cache.pop("corner_cross", None)

    def degenerate_faces(self) -> np.ndarray:
        """(F,) bool: faces with zero area or a repeated vertex; they are never drawn."""
        if "degenerate" not in self._cache:
            self.measure_faces()
        return self._cache["degenerate"]

    def face_extremes(self) -> tuple[np.ndarray, np.ndarray]:
        """(F, 3) each: every face's lowest and highest corner, in the positions' own type (the
        extremes of float32 values are the float32 values of the float64 extremes); those
        ``measure_faces`` kept, given once and let go."""
        if "extremes" not in self._cache:
            self.measure_faces(extremes=True)
        return self._cache.pop("extremes")

    def measure_faces(self, keys: bool = False, extremes: bool = False) -> np.ndarray | None:
        """One pass over every face's corners, a block of faces and a coordinate at a time (all
        of them at once in float64 would take 72 bytes a face), for the checks that read them
        all: ``degenerate_faces`` (kept), and where asked ``face_extremes`` (kept until read) and
        each face's coincidence key (returned, None where not asked): its corners' sum and area
        hashed to one number, so that copies of one triangle share it."""
        count = len(self.faces)
        degenerate = np.empty(count, bool)
        key = np.empty(count) if keys else None
        lows = np.empty((count, 3), self.positions.dtype) if extremes else None
        highs = np.empty_like(lows) if extremes else None
        scale = np.ptp(self.bounds, axis=0).max() if count else 1.0
        # |cross|^2 is a length^4: compare with a relative area of 1e-12
        least = (scale * scale * 1e-12) ** 2
        measured = partial(_measured, self.positions, self.faces, least, degenerate, key, lows, highs)
        parallel.run(measured, count, min_block=_FACES)
        self._cache["degenerate"] = degenerate
        if extremes:
            self._cache["extremes"] = (lows, highs)
        return key


# Faces whose corners ``Model.measure_faces`` reads at a time.
_FACES = 1 << 16
# The weights of a face's corners' sum in its coincidence key (``Model.measure_faces``).
_COINCIDENCE = np.array([1.0, np.pi, np.e])


def _measured(
    positions: np.ndarray,
    faces: np.ndarray,
    least: float,
    degenerate: np.ndarray,
    key: np.ndarray | None,
    lows: np.ndarray | None,
    highs: np.ndarray | None,
    first: int,
    last: int,
) -> None:
    """``Model.measure_faces`` of faces ``first`` to ``last``: repeating a vertex, or a squared
    cross product of at most ``least``, into ``degenerate``; the coincidence ``key`` and the
    extremes (``lows``, ``highs``) where not None."""
    columns = [positions[:, k] for k in range(3)]
    for start in range(first, last, _FACES):
        stop = min(start + _FACES, last)
        block = faces[start:stop]
        corner = [block[:, j].astype(np.intp) for j in range(3)]
        centre = np.empty((stop - start, 3)) if key is not None else None
        u, v = [], []
        for k, column in enumerate(columns):
            a, b, c = (column[at] for at in corner)
            if lows is not None:
                np.minimum(np.minimum(a, b), c, out=lows[start:stop, k])
                np.maximum(np.maximum(a, b), c, out=highs[start:stop, k])
            a, b, c = (x.astype(np.float64) for x in (a, b, c))
            u.append(b - a)
            v.append(c - a)
            if centre is not None:
                np.add(a + b, c, out=centre[:, k])
        cross = column_cross(u, v)
        square = np.einsum("ij,ij->i", cross, cross)
        np.less_equal(square, least, out=degenerate[start:stop])
        degenerate[start:stop] |= (block[:, 0] == block[:, 1]) | (block[:, 1] == block[:, 2])
        degenerate[start:stop] |= block[:, 0] == block[:, 2]
        if key is not None:
            key[start:stop] = centre @ _COINCIDENCE + np.sqrt(square) * np.sqrt(2)
