"""Choosing the parts of a model kept as instances (``blueprint.scene.instances``) without
flattening it: ``include`` / ``exclude`` and the environment test of
``blueprint.scene.environment``, the latter on a stand-in model that holds each part's
bounds and the triangles of the few parts that could enclose the rest."""

from __future__ import annotations

import numpy as np

from blueprint.scene import environment
from blueprint.scene.instances import instance_corners
from blueprint.scene.model import Model

# Parts found enclosing the rest in one model at most, for choosing which parts the stand-in
# holds whole: an enclosing part holds every other part but those found before it.
_MOST_FOUND = 8


def part_boxes(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """(P, 3) lowest and highest corner of every part of a model kept as instances (inf and
    -inf where a part has no instance): exact, from its instances' bounds."""
    count = len(model.part_names)
    boxes = model.instance_boxes()
    part = model.instances.part
    lo, hi = np.full((count, 3), np.inf), np.full((count, 3), -np.inf)
    np.minimum.at(lo, part, boxes[:, 0])
    np.maximum.at(hi, part, boxes[:, 1])
    return lo, hi


def _could_enclose(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(P,) bool: the parts whose bounds, grown as ``environment`` grows them, hold every
    other part's on each side but at most ``_MOST_FOUND`` (counted a side at a time: more
    parts than any that could enclose the rest)."""
    has = np.isfinite(lo).all(axis=1)
    grow = environment._INSIDE * np.where(has, (hi - lo).max(axis=1), 0.0)
    could = has.copy()
    for axis in range(3):
        lows, highs = np.sort(lo[has, axis]), np.sort(hi[has, axis])
        below = np.searchsorted(lows, lo[:, axis] - grow, side="left")
        above = len(highs) - np.searchsorted(highs, hi[:, axis] + grow, side="right")
        could &= (below <= _MOST_FOUND) & (above <= _MOST_FOUND)
    return could


def stand_in(model: Model) -> Model:
    """A flat model with ``model``'s parts, names and up axis whose parts have the same bounds
    and, where a part could enclose the rest, the same triangles: each part a triangle of no
    area across its bounds, and those parts' placed triangles."""
    lo, hi = part_boxes(model)
    has = np.isfinite(lo).all(axis=1)
    corners = [np.stack([lo[has], hi[has], hi[has]], axis=1)]
    parts = [np.flatnonzero(has)]
    inst = model.instances
    for part in np.flatnonzero(_could_enclose(lo, hi)):
        tri = instance_corners(inst, np.flatnonzero(inst.part == part))
        corners.append(tri)
        parts.append(np.full(len(tri), part))
    tri = np.concatenate(corners).astype(np.float32)
    return Model(
        tri.reshape(-1, 3),
        np.arange(3 * len(tri), dtype=np.int32).reshape(-1, 3),
        np.concatenate(parts).astype(np.int32),
        model.part_names,
        model.up,
        model.source,
    )


def environment_of(model: Model) -> np.ndarray:
    """``environment.environment_parts`` of ``model``, of its stand-in where it is kept as
    instances: never flattened (``blueprint info`` lists a scene of 10^6 instances)."""
    return environment.environment_parts(model if model.instances is None else stand_in(model))


def choose_instanced_parts(model: Model, include=None, exclude=None) -> Model:
    """``environment.choose_parts`` of a model kept as instances, which it keeps so: the
    instances of the parts chosen, their parts renumbered in order.

    Raises
    ------
    InputError
        A pattern matches no part, or nothing is left to draw; the message names the file.
    """
    keep = environment.parts_to_draw(model, include, exclude, shape=stand_in(model))
    if keep.all():
        return model
    number = np.cumsum(keep) - 1
    instances = model.instances.subset(keep[model.instances.part], number)
    return model.replaced(
        part_names=tuple(n for n, k in zip(model.part_names, keep, strict=True) if k), instances=instances
    )
