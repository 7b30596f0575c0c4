"""The up axis of a model whose format does not say (OBJ, PLY, OFF): guessed from its shape.

A model standing on something has a flat base: a good share of its surface lies flat in a thin
slab at the bottom, facing down. A scan of a statue or a bust made Z-up, loaded as the Y-up these
formats default to, lies on its side: its base is at the bottom of Z, not of Y. The guess takes
the axis whose bottom holds such a base, clearly more of one than the other has; otherwise the model
keeps the format's default, Y, since models without a base (animals, tools, parts) give the
shape nothing to go by and turning them would be a surprise.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from blueprint import parallel
from blueprint.columns import face_cross, row_norm, used_bounds

# The bottom slab, as a fraction of the model's extent along the axis.
_SLAB = 0.01
# Facing down: the face normal within about 18 degrees of the axis.
_DOWN = 0.95
# A base covers at least this fraction of the bounding box's cross-section across the axis.
_BASE = 0.08
# ... and at least this many times the flat area at the bottom of the other axis.
_CLEARLY = 2.0

AXES = {"y": 1, "z": 2}
# Faces whose corners the guess reads at a time.
_BLOCK = 1 << 16
# How a reason for a guessed axis begins (printed lines mention only guesses).
GUESSED = "guessed"


@dataclass(frozen=True)
class UpGuess:
    """The up axis chosen for a model and why, for ``blueprint info`` and printed lines."""

    axis: str
    reason: str


def base_fraction(positions: np.ndarray, faces: np.ndarray, axis: int) -> float:
    """The area of the faces lying flat at the bottom of ``axis``, facing down, as a fraction of
    the bounding box's cross-section across that axis (1 for a box standing on its face)."""
    return _base_fractions(positions, faces, (axis,))[axis]


def _base_fractions(positions: np.ndarray, faces: np.ndarray, axes) -> dict[int, float]:
    """``base_fraction`` of each of ``axes``, reading the faces' float64 corners a block at a
    time: all at once they would take 72 bytes a face."""
    positions = np.asarray(positions)
    faces = np.asarray(faces)
    lo, high = used_bounds(positions, faces)
    extent = high - lo
    flat_areas: dict[int, list[np.ndarray]] = {}
    for axis in axes:
        if extent[axis] > 0 and np.prod(np.delete(extent, axis)) > 0:
            flat_areas[axis] = []
    if flat_areas:
        blocks = parallel.run(
            partial(_flat_areas, positions, faces, lo, extent, tuple(flat_areas)), len(faces)
        )
        for found in blocks:
            for axis, areas in found.items():
                flat_areas[axis].extend(areas)
    fractions = dict.fromkeys(axes, 0.0)
    for axis, found in flat_areas.items():
        # the flat faces' areas summed in one array, in face order, as they would be at once
        fractions[axis] = float(
            np.concatenate([np.zeros(0), *found]).sum() / 2.0 / np.prod(np.delete(extent, axis))
        )
    return fractions


def _flat_areas(
    positions: np.ndarray, faces: np.ndarray, lo: np.ndarray, extent: np.ndarray, axes, first: int, last: int
) -> dict[int, list[np.ndarray]]:
    """The areas (twice) of faces ``first`` to ``last`` that lie flat in the bottom slab of each
    of ``axes``, facing down, a block of faces at a time, in face order."""
    flat_areas: dict[int, list[np.ndarray]] = {axis: [] for axis in axes}
    for start in range(first, last, _BLOCK):
        block = faces[start : min(start + _BLOCK, last)]
        # the faces in a bottom slab, from their heights in the positions' own type (the
        # highest of float32 corners is that of their float64 copies): few faces are, and
        # only theirs are read in float64
        low = {}
        for axis in axes:
            column = positions[:, axis]
            top = np.maximum(np.maximum(column[block[:, 0]], column[block[:, 1]]), column[block[:, 2]])
            low[axis] = top.astype(np.float64) <= lo[axis] + _SLAB * extent[axis]
        chosen = np.flatnonzero(np.logical_or.reduce(list(low.values())))
        if not len(chosen):
            continue
        cross = face_cross(positions[block[chosen]].astype(np.float64))
        area = row_norm(cross)
        for axis, found in flat_areas.items():
            with np.errstate(invalid="ignore", divide="ignore"):
                along = np.abs(cross[:, axis]) / area
            # either winding: scans and soups do not orient their faces consistently
            found.append(area[low[axis][chosen] & (along >= _DOWN)])
    return flat_areas


def guess_up(positions: np.ndarray, faces: np.ndarray, default: str = "y") -> UpGuess:
    """Guess the up axis of a model from a flat base at the bottom of Y or of Z.

    Parameters
    ----------
    positions : (V, 3) float array
    faces : (F, 3) int array
    default : {"y", "z"}
        The axis kept when the shape does not decide.

    Returns
    -------
    UpGuess
        The axis and a short reason ("flat base at the bottom of z", "no flat base").
    """
    if len(faces) == 0:
        return UpGuess(default, "format default")
    fractions = _base_fractions(positions, faces, AXES.values())
    bases = {name: fractions[axis] for name, axis in AXES.items()}
    best, other = sorted(bases, key=bases.get, reverse=True)
    # the side of a plinth is flat too: a base is the clearly larger of the two
    if bases[best] >= _BASE and bases[best] >= _CLEARLY * bases[other]:
        return UpGuess(best, f"{GUESSED} from a flat base at the bottom of {best}")
    return UpGuess(default, "format default, the shape does not decide")


def up_of(given: str | None, default: str, guess: bool, positions: np.ndarray, faces: np.ndarray) -> UpGuess:
    """The up axis a loader gives a model: ``given`` (``--up``) wins, then the shape where the
    format has no axis of its own (``guess``), else the format's ``default``."""
    if given is not None:
        return UpGuess(given, "given")
    if guess:
        return guess_up(positions, faces, default)
    return UpGuess(default, "by the format")


def guessed_up(axis: str, reason: str) -> str:
    """``", up z guessed from a flat base at the bottom of z"`` for a printed line where the
    shape chose the axis (so a surprise is explained), else nothing."""
    return f", up {axis} {reason}" if reason.startswith(GUESSED) else ""
