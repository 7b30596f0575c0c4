"""Environment meshes: parts that surround the scene rather than belong to it.

Game and city models often sit inside a skybox (an inward-facing box or sphere), under a dome
or on a ground plane far larger than everything else, each in one piece or in several (the six
panels of a skybox, a ring of walls with a lid, the segments of a dome, the tiles of a ground).
Fitted to, such parts make the scene a speck in the middle of the picture, and as the nearest
surface at every pixel they hide the whole scene behind them. Models of one part have none.
Three rules, applied in turn until none finds more, each against the rest as it stands (the
parts not yet found):

* **One part that encloses**: the rest lies inside its bounding box and most of its area
  (``_INWARD``) faces its own centre, as a one-mesh skybox or dome seen from inside does.
* **A group that encloses** (panels of a box or prism, segments of a dome): the parts are
  sorted by size, largest first, and every split into a group (the first k) and the rest is
  judged at once from running bounds. The group must hold the rest's standing content (the
  rest less its horizontally flat parts: a ground inside a skybox does not count in its scale,
  and may reach past a ring of walls) inside its bounding box; each of its parts must be
  larger than that content, and together ``_WIDER`` times wider than it along both horizontal
  axes. Of the splits that pass, those with the widest gap between the group's smallest part
  and the content are tried first, a few at most, by their faces: each part of the group must
  have most of its area (``_INWARD``) turned so that the whole of the content's bounding box
  lies in front of each face's plane (the group's smallest part is tried alone first). The
  scale is what sets a skybox apart from a room: the one-sided walls, floor and ceiling of a
  room around its furniture pass every other test. Walls built as solid boxes fail the facing
  test as well, their outer faces turned away from the content.
* **A ground**: the horizontally flat parts at or below the foot of the lowest standing part,
  together one flat slab, under the rest, ``_WIDER`` times wider than it along both horizontal
  axes, around it, and covering at least ``_COVER`` of their bounding rectangle seen from above
  (tiles, not a few pads far apart).

Per-part work is done on the parts' bounds in NumPy (sorted once, running minima and maxima for
every split at once); only the faces of the few groups tried are read.

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

# Inward-facing: this fraction of the area faces the centre (one part) or the rest (a group).
_INWARD = 0.8
# The rest must lie inside the bounding box, grown by this fraction of its size.
_INSIDE = 1e-3
# Flat: thinner along the up axis than this fraction of the width; a ground or a group is wider
# than the rest by this factor along both horizontal axes.
_FLAT = 0.01
_WIDER = 4.0
# A ground's parts cover this fraction of their bounding rectangle seen from above.
_COVER = 0.5
# Relative rounding error of float32 positions, with room to spare.
_ROUNDING = 1e-6
# Splits of the parts by size whose faces are read, at most, per group search.
_TRIES = 4
# Rounds of the three rules; a round that finds nothing ends the search.
_ROUNDS = 4
# Names a warning lists before it counts the rest.
_NAMED = 10

PartGlobs = str | Iterable[str | int] | None


def _bounds_by_part(model: Model) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(P, 3) lows and highs of every part's faces in one pass over the faces, (P,) whether the
    part has any, and (P + 1,) where each part's faces start among the faces ordered by part
    (``_part_faces``): per part, a pass over every face would take minutes for 10^5 instances."""
    count = len(model.part_names)
    tri_lo, tri_hi = model.face_extremes()
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


def _facing_fractions(
    model: Model, parts: np.ndarray, lo: np.ndarray, hi: np.ndarray, tol: float
) -> np.ndarray:
    """(P,) for each part flagged in ``parts`` (P,) bool, the fraction of its area whose faces
    have the whole box ``lo`` to ``hi`` (3,) in front of their plane, within ``tol`` (0
    elsewhere)."""
    faces = np.flatnonzero(parts[model.face_part])
    tri = model.positions[model.faces[faces]].astype(np.float64)
    cross = face_cross(tri)
    area = np.linalg.norm(cross, axis=1)
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    # the box's corner nearest a face's plane is its centre less the half sizes along the normal
    nearest = (cross * (centre - tri[:, 0])).sum(axis=1) - (np.abs(cross) * half).sum(axis=1)
    owner = model.face_part[faces]
    total = np.bincount(owner, area, len(parts))
    facing = np.bincount(owner, np.where(nearest >= -tol * area, area, 0.0), len(parts))
    return np.divide(facing, total, out=np.zeros(len(parts)), where=total > 0)


def environment_parts(model: Model) -> np.ndarray:
    """(P,) bool: the parts that enclose the rest of the model (inward-facing boxes, spheres,
    domes, in one part or as a group of panels or segments) or lie under it as a ground far
    wider than the rest (in one part or in tiles); the rules are the module's."""
    count = len(model.part_names)
    found = np.zeros(count, bool)
    if count < 2:
        return found
    bounds = _bounds_by_part(model)
    for _ in range(_ROUNDS):
        before = int(found.sum())
        _enclosing_parts(model, bounds, found)
        _enclosing_group(model, bounds, found)
        _ground(model, bounds, found)
        if found.sum() == before:
            break
    return found


def _enclosing_parts(model: Model, bounds: tuple, found: np.ndarray) -> None:
    """Mark in ``found`` the parts that alone enclose the rest and face their own centre."""
    lo, hi, has, starts = bounds
    count = len(found)
    by_part = _faces_by_part(model)
    grow = _INSIDE * (hi - lo).max(axis=1)
    order = np.arange(count)
    # All parts are tested at once against the rest as it stands; it changes only where a part
    # is found, and the parts after it are then tested against the new rest.
    start = 0
    while start < count:
        alive = has & ~found
        others_lo = _lowest_of_the_rest(lo, alive)
        others_hi = -_lowest_of_the_rest(-hi, alive)
        eligible = alive & (alive.sum() - alive > 0) & (order >= start)
        inside = (others_lo >= lo - grow[:, None]).all(axis=1) & (others_hi <= hi + grow[:, None]).all(axis=1)
        start = count
        for part in np.flatnonzero(eligible & inside):
            part = int(part)
            faces = slice(starts[part], starts[part + 1])
            faces = faces if by_part is None else by_part[faces]
            if _inward_fraction(model, faces, (lo[part] + hi[part]) / 2) >= _INWARD:
                found[part] = True
                start = part + 1
                break


def _enclosing_group(model: Model, bounds: tuple, found: np.ndarray) -> None:
    """Mark in ``found`` the largest parts that together enclose the rest, far larger than it
    and facing it, where there are such."""
    lo_all, hi_all, has, _ = bounds
    alive = np.flatnonzero(has & ~found)
    if len(alive) < 2:
        return
    up = AXES[model.up]
    across = [a for a in range(3) if a != up]
    extent = (hi_all[alive] - lo_all[alive]).max(axis=1)
    # largest first: split s puts parts[: s + 1] in the group and the others in the rest
    order = np.argsort(-extent, kind="stable")
    parts, extent = alive[order], extent[order]
    lo, hi = lo_all[parts], hi_all[parts]
    group_lo = np.minimum.accumulate(lo, axis=0)[:-1]
    group_hi = np.maximum.accumulate(hi, axis=0)[:-1]
    # the content each split's group must enclose: the rest less its horizontally flat parts
    # (a ground may reach past the walls around it), or the whole rest where all are flat
    size = hi - lo
    flat = (size[:, up] <= _FLAT * size[:, across].max(axis=1))[:, None]
    rest_lo = np.minimum.accumulate(lo[::-1], axis=0)[::-1][1:]
    rest_hi = np.maximum.accumulate(hi[::-1], axis=0)[::-1][1:]
    content_lo = np.minimum.accumulate(np.where(flat, np.inf, lo)[::-1], axis=0)[::-1][1:]
    content_hi = np.maximum.accumulate(np.where(flat, -np.inf, hi)[::-1], axis=0)[::-1][1:]
    none = np.isinf(content_lo[:, 0])
    content_lo[none], content_hi[none] = rest_lo[none], rest_hi[none]
    content = content_hi - content_lo
    group_size = group_hi - group_lo
    grow = _INSIDE * group_size.max(axis=1)[:, None]
    inside = ((content_lo >= group_lo - grow) & (content_hi <= group_hi + grow)).all(axis=1)
    wider = (group_size[:, across] >= _WIDER * np.maximum(content[:, across], 1e-30)).all(axis=1)
    gap = extent[:-1] / np.maximum(content.max(axis=1), 1e-30)
    splits = np.flatnonzero(inside & wider & (gap >= 1.0))
    for split in splits[np.argsort(-gap[splits], kind="stable")][:_TRIES]:
        # in front within a small fraction of the content, or the rounding of float32 positions
        tol = max(_INSIDE * content[split].max(), _ROUNDING * group_size[split].max())
        box = (content_lo[split], content_hi[split])
        # the group's smallest part first, alone: where it turns away, the group's faces are not read
        group = np.zeros(len(found), bool)
        group[parts[split]] = True
        if _facing_fractions(model, group, *box, tol)[parts[split]] < _INWARD:
            continue
        group[parts[:split]] = True
        if (_facing_fractions(model, group, *box, tol)[group] >= _INWARD).all():
            found |= group
            return


def _ground(model: Model, bounds: tuple, found: np.ndarray) -> None:
    """Mark in ``found`` the flat parts at the foot of the rest that together are its ground."""
    lo, hi, has, _ = bounds
    up = AXES[model.up]
    across = [a for a in range(3) if a != up]
    alive = has & ~found
    size = np.where(alive[:, None], hi - lo, 0.0)
    width = size[:, across].max(axis=1)
    flat = alive & (width > 0) & (size[:, up] <= _FLAT * width)
    standing = alive & ~flat
    if not standing.any():
        return
    ground = flat & (hi[:, up] <= lo[standing, up].min() + _INSIDE * width)
    rest = alive & ~ground
    if not ground.any() or not rest.any():
        return
    ground_lo, ground_hi = lo[ground].min(axis=0), hi[ground].max(axis=0)
    rest_lo, rest_hi = lo[rest].min(axis=0), hi[rest].max(axis=0)
    ground_size, rest_size = ground_hi - ground_lo, rest_hi - rest_lo
    wide = ground_size[across].max()
    tol = _INSIDE * wide
    if not (
        ground_size[up] <= _FLAT * wide
        and ground_hi[up] <= rest_lo[up] + tol
        and (ground_size[across] >= _WIDER * np.maximum(rest_size[across], 1e-30)).all()
        and (ground_lo[across] <= rest_lo[across] + tol).all()
        and (ground_hi[across] >= rest_hi[across] - tol).all()
    ):
        return
    tri = model.positions[model.faces[ground[model.face_part]]].astype(np.float64)
    seen_from_above = np.abs(face_cross(tri)[:, up]).sum() / 2
    if seen_from_above >= _COVER * ground_size[across].prod():
        found |= ground


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
    keep = parts_to_draw(model, include, exclude)
    return model if keep.all() else subset(model, keep)


def parts_to_draw(
    model: Model, include: PartGlobs = None, exclude: PartGlobs = None, shape: Model | None = None
) -> np.ndarray:
    """(P,) bool: the parts of ``model`` that ``choose_parts`` keeps, the environment found in
    ``shape`` (the model itself where None; a stand-in with its parts, for a model kept as
    instances), and the warning that names what was left out.

    Raises
    ------
    InputError
        A pattern matches no part, or nothing is left to draw; the message names the file.
    """
    name = model.source or "the model"
    keep = _matching(model, include, "--include", True)
    keep &= ~_matching(model, exclude, "--exclude", False)
    if include is None:
        environment = environment_parts(model if shape is None else shape) & keep
        if environment.any() and environment.sum() < keep.sum():
            which = np.flatnonzero(environment)
            names = ", ".join(model.part_names[i] for i in which[:_NAMED])
            more = f" and {len(which) - _NAMED} more" if len(which) > _NAMED else ""
            log.warning(
                "%s: left out %s%s, which surround%s the scene (--include to keep)",
                name,
                names,
                more,
                "s" if len(which) == 1 else "",
            )
            keep &= ~environment
    if not keep.any():
        raise InputError(f"{name}: --include/--exclude leave no part to draw")
    return keep


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
