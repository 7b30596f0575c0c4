"""Helpers for the vector tests: reading our SVG back, measuring lines, a slab-count oracle."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np

SVG = "{http://www.w3.org/2000/svg}"
_TOKEN = re.compile(r"[MmLl]|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def parse_path(d: str) -> list[np.ndarray]:
    """Polylines of an SVG path made of M/m and L/l commands (what the writer emits)."""
    lines: list[list[tuple[float, float]]] = []
    command, numbers, x, y = None, [], 0.0, 0.0

    def flush():
        nonlocal numbers, x, y
        for i in range(0, len(numbers) - 1, 2):
            dx, dy = numbers[i], numbers[i + 1]
            relative = command.islower()
            if command in "Mm" and i == 0:
                x, y = (x + dx, y + dy) if relative and lines else (dx, dy)
                lines.append([(x, y)])
            else:
                x, y = (x + dx, y + dy) if relative else (dx, dy)
                lines[-1].append((x, y))
        numbers = []

    for token in _TOKEN.findall(d):
        if token in "MmLl":
            if command is not None:
                flush()
            command = token
        else:
            numbers.append(float(token))
    if command is not None:
        flush()
    return [np.array(line) for line in lines]


def group_scale(group) -> float:
    """The factor of a group's ``transform="scale(s)"`` (1 without one)."""
    found = re.fullmatch(r"scale\(([^)]*)\)", group.get("transform") or "scale(1)")
    return float(found.group(1))


def svg_line_paths(path):
    """(part group, level group, path, scale) of every line path of an SVG file: a part's layer
    holds a group per level (``data-level``), that a path per kind (``data-kind``), in line
    groups scaled to the output grid."""
    root = ET.parse(path).getroot()
    for lines in root.iter(f"{SVG}g"):
        if lines.get("id") not in ("lines", "lines-behind-shading"):
            continue
        scale = group_scale(lines)
        for part in lines.findall(f"{SVG}g"):
            for level in part.findall(f"{SVG}g"):
                for element in level.findall(f"{SVG}path"):
                    yield part, level, element, scale


def svg_lines(path) -> dict[tuple[str, int], list[np.ndarray]]:
    """{(part group id, level): polylines in view-box units} read from an SVG file."""
    found: dict[tuple[str, int], list[np.ndarray]] = {}
    for part, level, element, scale in svg_line_paths(path):
        key = (part.get("id"), int(level.get("data-level")))
        found.setdefault(key, []).extend(line * scale for line in parse_path(element.get("d")))
    return found


def svg_edges(text: str | None) -> list[np.ndarray]:
    """The source edges of each subpath from a path's ``data-edges``: entries apart by ``;``,
    every number the difference from the one before it in the attribute."""
    if not text:
        return []
    entries = text.split(";")
    steps = [np.array(entry.split(), np.int64) for entry in entries]
    flat = np.cumsum(np.concatenate(steps)) if steps else np.zeros(0, np.int64)
    cuts = np.cumsum([len(s) for s in steps])[:-1]
    return np.split(flat, cuts)


def segments_of(polylines: list[np.ndarray]) -> np.ndarray:
    """(N, 2, 2) segments of 2D polylines."""
    parts = [np.stack([p[:-1], p[1:]], axis=1) for p in polylines if len(p) >= 2]
    return np.concatenate(parts) if parts else np.zeros((0, 2, 2))


def split_at_corners(points: np.ndarray, angle: float = 30.0) -> list[np.ndarray]:
    """A 2D polyline cut at every vertex where it turns by more than ``angle`` degrees: lines
    chained through a corner, back to one straight-ish stretch per edge."""
    step = np.diff(points, axis=0)
    length = np.linalg.norm(step, axis=1)
    step = step[length > 1e-9] / length[length > 1e-9, None]
    points = points[np.r_[True, length > 1e-9]]
    if len(step) < 2:
        return [points]
    turn = np.einsum("ij,ij->i", step[:-1], step[1:]) < np.cos(np.radians(angle))
    cuts = np.flatnonzero(turn) + 1
    bounds = np.r_[0, cuts, len(points) - 1]
    return [points[a : b + 1] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def point_segment_distance(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(P, N) distances from 2D points to 2D segments."""
    a = segments[None, :, 0]
    d = segments[None, :, 1] - a
    rel = points[:, None] - a
    length2 = np.maximum((d * d).sum(-1), 1e-300)
    t = np.clip((rel * d).sum(-1) / length2, 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * d, axis=-1)


def box_edges(lo, hi) -> np.ndarray:
    """The 12 edges (12, 2, 3) of an axis-aligned box."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    corners = lo + corners * (hi - lo)
    pairs = [(i, j) for i in range(8) for j in range(i + 1, 8) if bin(i ^ j).count("1") == 1]
    return np.array([[corners[i], corners[j]] for i, j in pairs])


def boxes_in_front(point: np.ndarray, toward_eye: np.ndarray, boxes, eps: float = 1e-9) -> int:
    """Oracle: box faces crossed by the ray from ``point`` towards the eye (slab method)."""
    count = 0
    for lo, hi in boxes:
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            t0 = (lo - point) / toward_eye
            t1 = (hi - point) / toward_eye
        near = np.where(
            toward_eye == 0, np.where((point >= lo) & (point <= hi), -np.inf, np.inf), np.minimum(t0, t1)
        )
        far = np.where(
            toward_eye == 0, np.where((point >= lo) & (point <= hi), np.inf, -np.inf), np.maximum(t0, t1)
        )
        t_in, t_out = near.max(), far.min()
        if t_in > t_out:
            continue
        count += int(t_in > eps) + int(t_out > eps)
    return count
