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

import numpy as np

from blueprint.columns import column_max, column_min, face_cross, row_norm

# The bottom slab, as a fraction of the model's extent along the axis.
_SLAB = 0.01
# Facing down: the face normal within about 18 degrees of the axis.
_DOWN = 0.95
# A base covers at least this fraction of the bounding box's cross-section across the axis.
_BASE = 0.08
# ... and at least this many times the flat area at the bottom of the other axis.
_CLEARLY = 2.0

AXES = {"y": 1, "z": 2}
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
    return _base_fraction(_Triangles(positions, faces), axis)


class _Triangles:
    """What every axis's base fraction needs of a mesh, computed once for both axes."""

    def __init__(self, positions: np.ndarray, faces: np.ndarray) -> None:
        self.tri = np.asarray(positions, np.float64)[faces]  # a loader's positions are float64: no copy
        corners = self.tri.reshape(-1, 3)
        self.lo, self.hi = column_min(corners), column_max(corners)
        self.cross = face_cross(self.tri)
        self.area = row_norm(self.cross)


def _base_fraction(mesh: _Triangles, axis: int) -> float:
    extent = mesh.hi - mesh.lo
    across = np.prod(np.delete(extent, axis))
    if extent[axis] <= 0 or across <= 0:
        return 0.0
    with np.errstate(invalid="ignore", divide="ignore"):
        along = np.abs(mesh.cross[:, axis]) / mesh.area
    heights = mesh.tri[:, :, axis]
    top = np.maximum(np.maximum(heights[:, 0], heights[:, 1]), heights[:, 2])
    low = top <= mesh.lo[axis] + _SLAB * extent[axis]
    # either winding: scans and soups do not orient their faces consistently
    flat = low & (along >= _DOWN)
    return float(mesh.area[flat].sum() / 2.0 / across)


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
    mesh = _Triangles(positions, faces)
    bases = {name: _base_fraction(mesh, axis) for name, axis in AXES.items()}
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
