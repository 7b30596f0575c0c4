"""Lines that know where they come from: the kinds of line, the model's stable edge numbering
and ``Lines``, a drawing's polylines with their part, kind, occlusion level and source edges.

A line's source edges are indices into ``edge_numbers(model)``: the undirected edges of the
model as ``Model.faces`` and ``Model.positions`` give it, welded within each part, numbered in
the order of their sorted (lower, higher) welded vertex pairs. The numbering depends on the
model alone, so one file gives the same numbers in every view and every run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from blueprint.compose.linestyle import KINDS
from blueprint.errors import InputError

__all__ = [
    "BORDER",
    "BOUNDARY",
    "CREASE",
    "DIMENSION",
    "GLYPH",
    "HATCH",
    "INTERSECTION",
    "KINDS",
    "SECTION",
    "SHEET",
    "SILHOUETTE",
    "SMOOTH",
    "Lines",
    "kind_code",
]

# Kind codes, indices into ``KINDS``; the first three are ``blueprint.silhouette``'s own.
SILHOUETTE = 1
BORDER = 2
CREASE = 3
BOUNDARY = 4
INTERSECTION = 5
SECTION = 6
HATCH = 7
GLYPH = 8
DIMENSION = 9
SHEET = 10
SMOOTH = 11


def kind_code(name: str) -> int:
    """The code of a kind named as ``KINDS`` names it; ``InputError`` for any other name."""
    if name not in KINDS or not name:
        raise InputError(f"unknown kind of line {name!r} (choose {', '.join(k for k in KINDS if k)})")
    return KINDS.index(name)


@dataclass(frozen=True)
class Lines:
    """A drawing's polylines and what each was drawn from.

    Polyline ``i`` is ``points[offsets[i]:offsets[i + 1]]`` and its source edges are
    ``edges[edge_offsets[i]:edge_offsets[i + 1]]``.

    Attributes
    ----------
    points : (N, 2) float64
        Pixels: x right, y down, origin top-left.
    offsets : (P + 1,) int64
    part : (P,) int32
        Part index of each polyline.
    kind : (P,) uint8
        Kind code of each polyline (``KINDS[kind[i]]`` is its name).
    level : (P,) int32
        Occlusion level: how many surfaces lie in front of the polyline.
    edges : (M,) int64
        Source edges (rows of ``edge_numbers``) of every polyline, one after the other, in the
        order the line runs along them: for a smooth contour (a silhouette inside faces), the
        edges it crosses; none for intersections.
    edge_offsets : (P + 1,) int64
    behind : (P,) bool
        Polylines behind a shaded part's surface (all False without shading).
    """

    points: np.ndarray
    offsets: np.ndarray
    part: np.ndarray
    kind: np.ndarray
    level: np.ndarray
    edges: np.ndarray
    edge_offsets: np.ndarray
    behind: np.ndarray

    def __len__(self) -> int:
        return len(self.offsets) - 1

    @classmethod
    def empty(cls) -> Lines:
        none = np.zeros(0, np.int32)
        return cls(
            np.zeros((0, 2)),
            np.zeros(1, np.int64),
            none,
            np.zeros(0, np.uint8),
            none,
            np.zeros(0, np.int64),
            np.zeros(1, np.int64),
            np.zeros(0, bool),
        )

    def polyline(self, i: int) -> np.ndarray:
        """(n, 2) points of polyline ``i``."""
        return self.points[self.offsets[i] : self.offsets[i + 1]]

    def edges_of(self, i: int) -> np.ndarray:
        """(m,) int64 source edges of polyline ``i``."""
        return self.edges[self.edge_offsets[i] : self.edge_offsets[i + 1]]

    def kind_names(self) -> list[str]:
        """Each polyline's kind by name."""
        return [KINDS[k] for k in self.kind.tolist()]

    def take(self, index: np.ndarray) -> Lines:
        """The polylines ``index`` (int array, or (P,) bool), in that order."""
        index = np.asarray(index)
        if index.dtype == bool:
            index = np.flatnonzero(index)
        index = index.astype(np.int64)
        points, offsets = _gather(self.points, self.offsets, index)
        edges, edge_offsets = _gather(self.edges, self.edge_offsets, index)
        return Lines(
            points,
            offsets,
            self.part[index],
            self.kind[index],
            self.level[index],
            edges,
            edge_offsets,
            self.behind[index],
        )

    def where(self, kind=None, part=None, level=None) -> Lines:
        """The polylines of the given kinds (names or codes), parts and levels (each one value
        or several; None: any), in their order."""
        keep = np.ones(len(self), bool)
        if kind is not None:
            kinds = [kind] if isinstance(kind, str | int | np.integer) else list(kind)
            codes = [kind_code(k) if isinstance(k, str) else int(k) for k in kinds]
            keep &= np.isin(self.kind, codes)
        for values, have in ((part, self.part), (level, self.level)):
            if values is not None:
                keep &= np.isin(have, np.atleast_1d(np.asarray(values)))
        return self.take(keep)

    def shifted(self, shift) -> Lines:
        """The same lines moved by ``shift`` (dx, dy) pixels."""
        return _replace_points(self, self.points + np.asarray(shift, np.float64))

    @staticmethod
    def concatenate(items: list[Lines]) -> Lines:
        """The polylines of ``items``, one after the other."""
        items = [lines for lines in items if len(lines)] or [Lines.empty()]
        points = np.concatenate([lines.points for lines in items]).reshape(-1, 2)
        edges = np.concatenate([lines.edges for lines in items]).astype(np.int64)
        return Lines(
            points,
            _joined_offsets([lines.offsets for lines in items]),
            np.concatenate([lines.part for lines in items]).astype(np.int32),
            np.concatenate([lines.kind for lines in items]).astype(np.uint8),
            np.concatenate([lines.level for lines in items]).astype(np.int32),
            edges,
            _joined_offsets([lines.edge_offsets for lines in items]),
            np.concatenate([lines.behind for lines in items]).astype(bool),
        )


def _replace_points(lines: Lines, points: np.ndarray) -> Lines:
    return Lines(
        points,
        lines.offsets,
        lines.part,
        lines.kind,
        lines.level,
        lines.edges,
        lines.edge_offsets,
        lines.behind,
    )


def _joined_offsets(offsets: list[np.ndarray]) -> np.ndarray:
    """The offsets of CSR runs laid one after the other."""
    starts = np.cumsum([0] + [int(o[-1]) for o in offsets[:-1]])
    return np.concatenate([[0]] + [o[1:] + s for o, s in zip(offsets, starts, strict=True)]).astype(np.int64)


def _gather(values: np.ndarray, offsets: np.ndarray, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The runs ``index`` of the CSR ``values``, ``offsets``, and their new offsets."""
    size = offsets[index + 1] - offsets[index]
    new = np.r_[0, np.cumsum(size)].astype(np.int64)
    rows = np.repeat(offsets[index] - new[:-1], size) + np.arange(int(new[-1]))
    return values[rows], new


def runs_of(values: np.ndarray, owner: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """CSR of ``values`` (n,) grouped by ``owner`` (n,) ascending, repeats of a value next to
    itself within one owner dropped: (kept values, (count + 1,) offsets)."""
    keep = np.ones(len(values), bool)
    keep[1:] = (owner[1:] != owner[:-1]) | (values[1:] != values[:-1])
    offsets = np.r_[0, np.cumsum(np.bincount(owner[keep], minlength=count))]
    return values[keep].astype(np.int64), offsets.astype(np.int64)
