"""Environment meshes: parts that surround the scene rather than belong to it.

Game and city models often sit inside a skybox (an inward-facing box or sphere), under a dome
or on a ground plane far larger than everything else. Fitted to, such a part makes the scene
a speck in the middle of the picture, and as the nearest surface at every pixel it hides the
whole scene behind it. A part is taken for environment when the rest of the model lies
inside its bounding box and either it faces inwards (most of its area turned towards its own
centre: a skybox or dome seen from inside) or it is flat and many times wider than the rest
(a ground plane). Models of one part have none.

:func:`choose_parts` is what loading applies: explicit ``include`` / ``exclude`` name globs
first, then, where ``include`` is not given, the environment left out with a warning naming it.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable

import numpy as np

from blueprint.columns import face_cross
from blueprint.errors import InputError
from blueprint.scene.model import Model
from blueprint.scene.parts import select_parts
from blueprint.scene.up import AXES
from blueprint.sorting import stable_argsort

log = logging.getLogger("blueprint")

# Inward-facing: this fraction of the part's area faces its centre.
_INWARD = 0.8
# The rest must lie inside the part's bounding box, grown by this fraction of its size.
_INSIDE = 1e-3
# A ground plane: thinner than this fraction of its width, and wider than the rest by this
# factor along both horizontal axes.
_FLAT = 0.01
_WIDER = 4.0

PartGlobs = str | Iterable[str | int] | None


def _bounds_by_part(model: Model) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(P, 3) lows and highs of every part's faces in one pass over the faces, (P,) whether the
    part has any, and (P + 1,) where each part's faces start among the faces ordered by part
    (``_part_faces``): per part, a pass over every face would take minutes for 10^5 instances."""
    count = len(model.part_names)
    # every face's low and high corner, coordinate by coordinate, in the positions' own type
    # (the extremes of float32 values are the float32 values of the float64 extremes)
    tri_lo = np.empty((len(model.faces), 3), model.positions.dtype)
    tri_hi = np.empty_like(tri_lo)
    for k in range(3):
        corner = [model.positions[:, k][model.faces[:, j]] for j in range(3)]
        np.minimum(np.minimum(corner[0], corner[1]), corner[2], out=tri_lo[:, k])
        np.maximum(np.maximum(corner[0], corner[1]), corner[2], out=tri_hi[:, k])
    del corner
    order = _faces_by_part(model)
    part = model.face_part
    if order is not None:
        part = part[order]
        tri_lo, tri_hi = np.take(tri_lo, order, axis=0), np.take(tri_hi, order, axis=0)
    starts = np.searchsorted(part, np.arange(count + 1))
    has = starts[1:] > starts[:-1]
    lo, hi = np.full((count, 3), np.inf), np.full((count, 3), -np.inf)
    if has.any():
        lo[has] = np.minimum.reduceat(tri_lo, starts[:-1][has], axis=0)
        hi[has] = np.maximum.reduceat(tri_hi, starts[:-1][has], axis=0)
    return lo, hi, has, starts


def _faces_by_part(model: Model) -> np.ndarray | None:
    """(F,) the faces ordered by part, in order within each (None: they are, as loaders write
    a scene's parts), made once per model."""
    if "faces_by_part" not in model._cache:
        part = model.face_part
        model._cache["faces_by_part"] = None if np.all(part[1:] >= part[:-1]) else stable_argsort(part)
    return model._cache["faces_by_part"]


def _lowest_of_the_rest(values: np.ndarray, alive: np.ndarray) -> np.ndarray:
    """(P, 3): for each part, the lowest of ``values`` over the other parts alive, by axis (the
    lowest of all, or for the part that holds it the second lowest; inf where none)."""
    axes = np.arange(values.shape[1])
    v = np.where(alive[:, None], values, np.inf)
    first = v.argmin(axis=0)
    lowest = v[first, axes]
    v[first, axes] = np.inf
    second = v.min(axis=0)
    return np.where(np.arange(len(values))[:, None] == first[None, :], second[None, :], lowest[None, :])


def _inward_fraction(model: Model, faces: np.ndarray | slice, centre: np.ndarray) -> float:
    tri = model.positions[model.faces[faces]].astype(np.float64)
    cross = face_cross(tri)
    area = np.linalg.norm(cross, axis=1)
    towards = np.einsum("ij,ij->i", cross, centre - tri.mean(axis=1)) > 0
    total = area.sum()
    return float(area[towards].sum() / total) if total > 0 else 0.0


def environment_parts(model: Model) -> np.ndarray:
    """(P,) bool: the parts that enclose the rest of the model (inward-facing boxes, spheres,
    domes) or lie under it as a ground plane far wider than the rest."""
    count = len(model.part_names)
    found = np.zeros(count, bool)
    if count < 2:
        return found
    up = AXES[model.up]
    across = [a for a in range(3) if a != up]
    lo, hi, has, starts = _bounds_by_part(model)
    by_part = _faces_by_part(model)
    size = hi - lo
    grow = _INSIDE * size.max(axis=1)
    order = np.arange(count)
    inward: dict[int, float] = {}
    # Parts in order, each tested against the rest (the other parts not yet found), twice: a
    # skybox found first no longer counts as the rest a ground plane must span. All parts are
    # tested at once against the rest as it stands; it changes only where a part is found.
    for _ in range(2):
        start = 0
        while start < count:
            alive = has & ~found
            others_lo = _lowest_of_the_rest(lo, alive)
            others_hi = -_lowest_of_the_rest(-hi, alive)
            other_size = others_hi - others_lo
            eligible = alive & (alive.sum() - alive > 0) & (order >= start)
            inside = (others_lo >= lo - grow[:, None]).all(axis=1) & (others_hi <= hi + grow[:, None]).all(
                axis=1
            )
            flat = size[:, up] <= _FLAT * size[:, across].max(axis=1)
            below = hi[:, up] <= others_lo[:, up] + grow
            wider = (size[:, across] >= _WIDER * np.maximum(other_size[:, across], 1e-30)).all(axis=1)
            within = ((lo[:, across] <= others_lo[:, across]) & (hi[:, across] >= others_hi[:, across])).all(
                axis=1
            )
            ground = flat & below & wider & within
            start = count
            for part in np.flatnonzero(eligible & (inside | ground)):
                part = int(part)
                if not ground[part] and part not in inward:
                    centre = (lo[part] + hi[part]) / 2
                    faces = slice(starts[part], starts[part + 1])
                    faces = faces if by_part is None else by_part[faces]
                    inward[part] = _inward_fraction(model, faces, centre)
                if ground[part] or inward[part] >= _INWARD:
                    found[part] = True
                    start = part + 1
                    break
    return found


def choose_parts(model: Model, include: PartGlobs = None, exclude: PartGlobs = None) -> Model:
    """The model with only the parts to draw: those matching ``include`` (every part where
    None; environment parts then left out, see :func:`environment_parts`, with a warning
    naming them), less those matching ``exclude``. Patterns are name globs or part indices, a
    string may hold several separated by commas (as ``--highlight``).

    Raises
    ------
    InputError
        A pattern matches no part, or nothing is left to draw; the message names the file.
    """
    name = model.source or "the model"
    keep = _matching(model, include, "--include", True)
    keep &= ~_matching(model, exclude, "--exclude", False)
    if include is None:
        environment = environment_parts(model) & keep
        if environment.any() and environment.sum() < keep.sum():
            names = ", ".join(model.part_names[i] for i in np.flatnonzero(environment))
            log.warning(
                "%s: left out %s, which surround%s the scene (--include to keep)",
                name,
                names,
                "s" if environment.sum() == 1 else "",
            )
            keep &= ~environment
    if not keep.any():
        raise InputError(f"{name}: --include/--exclude leave no part to draw")
    if keep.all():
        return model
    return subset(model, keep)


def _matching(model: Model, patterns: PartGlobs, option: str, empty: bool) -> np.ndarray:
    if patterns is None:
        return np.full(len(model.part_names), empty)
    try:
        return select_parts(model, patterns)
    except InputError as exc:
        raise InputError(f"{model.source or 'the model'}: {option}: {exc}") from None


def subset(model: Model, keep: np.ndarray) -> Model:
    """The model with the parts flagged in ``keep`` (P,) bool alone, renumbered in order."""
    faces = keep[model.face_part]
    # only the vertices the kept faces use: camera fits look at every vertex
    used, kept_faces = np.unique(model.faces[faces], return_inverse=True)
    number = np.cumsum(keep) - 1
    return Model(
        np.ascontiguousarray(model.positions[used]),
        np.ascontiguousarray(kept_faces.reshape(-1, 3), np.int32),
        np.ascontiguousarray(number[model.face_part[faces]], np.int32),
        tuple(n for n, k in zip(model.part_names, keep, strict=True) if k),
        model.up,
        model.source,
        model.up_reason,
        model.unit,
        model.unit_reason,
    )
