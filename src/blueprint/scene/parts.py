"""Choosing parts of a model: by name pattern, by index, or by a second model in the same place."""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable

import numpy as np

from blueprint.errors import InputError
from blueprint.scene.model import Model


def select_parts(model: Model, patterns: str | int | Iterable[str | int]) -> np.ndarray:
    """(P,) bool: the parts matching any of ``patterns``.

    A pattern is a glob on the part name (``Piston*``, case-insensitive) or a part index; a
    string may hold several, separated by commas; one index may come alone.

    Raises
    ------
    InputError
        A pattern matches no part; the message lists the closest part names.
    """
    if isinstance(patterns, str):
        patterns = [p.strip() for p in patterns.split(",") if p.strip()]
    elif isinstance(patterns, int | np.integer):
        patterns = [patterns]
    names = model.part_names
    lowered = [n.lower() for n in names]
    selected = np.zeros(len(names), bool)
    for pattern in patterns:
        if isinstance(pattern, int | np.integer) or (isinstance(pattern, str) and pattern.isdigit()):
            index = int(pattern)
            if not 0 <= index < len(names):
                raise InputError(f"part index {index} is out of range (the model has {len(names)} parts)")
            selected[index] = True
            continue
        hits = [i for i, n in enumerate(lowered) if fnmatch.fnmatchcase(n, str(pattern).lower())]
        if not hits:
            import difflib  # for this message alone: it brings heapq along

            close = difflib.get_close_matches(str(pattern), names, n=5, cutoff=0.3)
            hint = f"; closest: {', '.join(close)}" if close else f"; parts are e.g. {', '.join(names[:5])}"
            raise InputError(f"no part matches {pattern!r}{hint}")
        selected[hits] = True
    if not selected.any():
        raise InputError("no part pattern given")
    return selected


def select_parts_like(model: Model, other: Model, tolerance: float | None = None) -> np.ndarray:
    """(P,) bool: the parts of ``model`` that ``other`` (a second file in the same coordinates)
    covers: most of a part's vertices lie within ``tolerance`` of ``other``'s surface vertices
    (default: 1e-4 of ``model``'s bounding-box diagonal)."""
    from scipy.spatial import cKDTree

    diag = float(np.linalg.norm(np.ptp(model.bounds, axis=0))) or 1.0
    tolerance = diag * 1e-4 if tolerance is None else tolerance
    tree = cKDTree(other.positions.astype(np.float64))
    # each part's vertices once (a vertex two parts use counts for both), all looked up at once
    vertices = len(model.positions)
    pairs = np.unique(np.repeat(model.face_part.astype(np.int64), 3) * vertices + model.faces.reshape(-1))
    part, vertex = np.divmod(pairs, vertices)
    used = np.unique(vertex)
    distance, _ = tree.query(model.positions[used].astype(np.float64), distance_upper_bound=tolerance)
    near = np.zeros(vertices, bool)
    near[used] = np.isfinite(distance)
    count = len(model.part_names)
    # most of a part's vertices near: more than half of them
    selected = np.bincount(part, near[vertex], count) > 0.5 * np.bincount(part, minlength=count)
    if not selected.any():
        raise InputError(f"{other.source}: lies on no part of {model.source or 'the model'}")
    return selected


def designated_parts(model: Model, spec) -> np.ndarray:
    """(P,) bool from a part spec: name globs and indices (a comma-separated string or a
    sequence), a second Model in the same coordinates, or already a bool array."""
    if isinstance(spec, Model):
        return select_parts_like(model, spec)
    array = np.asarray(spec) if not isinstance(spec, str) else None
    if array is not None and array.dtype == bool:
        if array.shape != (len(model.part_names),):
            raise InputError(f"highlight needs one flag per part ({len(model.part_names)})")
        return array
    return select_parts(model, spec)
