"""Edges drawn where the geometry puts them: a cube's 12 edges at their projected positions,
visible ones in ink and hidden ones in the fainter hidden ink, nothing elsewhere; the boundary
between two touching parts; and the same picture from a triangle soup with mixed winding.

Everything is measured on the returned image against corners projected with the frame's own
camera matrices: pixel (col, row) covers [col, col + 1] x [row, row + 1], row 0 at the top.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from helpers import project

import blueprint
from blueprint import examples

SIZE = (256, 256)
STYLE = blueprint.STYLES["paper"]
# an ink pixel differs from the paper by at least this much in some channel (of 255); a hidden
# line (half as wide as a visible one: a third of a pixel at supersample 3) straddling two
# pixels reaches about 0.9 * 176 / 6 = 26
INK = 20
# "paper" pixels may differ by at most this much (exactly 0 with a correct renderer)
PAPER_NOISE = 2


def _camera(model: blueprint.Model) -> blueprint.Camera:
    # a general view: no two corners of the cube project onto each other (iso puts the nearest
    # and the farthest corner on the same pixel)
    return blueprint.Camera.fit(model.positions, "iso", azimuth=30.0, elevation=25.0)


def _render(renderer, model, **options):
    frame = renderer.render(model, _camera(model), size=SIZE, style="paper", **options)
    assert frame.image.shape == (SIZE[1], SIZE[0], 4) and frame.image.dtype == np.uint8
    return frame


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, S) distance from each point to each segment a[s]-b[s] (all in pixels)."""
    d = b - a
    t = ((points[:, None, :] - a[None]) * d[None]).sum(-1) / np.maximum((d * d).sum(-1), 1e-12)
    closest = a[None] + np.clip(t, 0, 1)[..., None] * d[None]
    return np.linalg.norm(points[:, None, :] - closest, axis=-1)


def _pixel_centres() -> np.ndarray:
    rows, cols = np.mgrid[0 : SIZE[1], 0 : SIZE[0]]
    return np.column_stack([cols.ravel() + 0.5, rows.ravel() + 0.5])


def _ink(image: np.ndarray) -> np.ndarray:
    """(H, W, 3) how far each pixel is from the paper, per channel (paper minus pixel)."""
    paper = np.array(STYLE.paper[:3]) * 255
    return paper - image[..., :3].astype(np.float64)


def _strongest_near(ink: np.ndarray, samples: np.ndarray, radius: float = 1.0) -> np.ndarray:
    """(N, 3) the ink of the strongest pixel whose centre lies within ``radius`` px of each
    sample point."""
    strength = ink.max(axis=-1)
    offsets = [(dx, dy) for dx in range(-2, 3) for dy in range(-2, 3)]
    best = np.full(len(samples), -np.inf)
    out = np.zeros((len(samples), 3))
    base = np.floor(samples).astype(int)
    for dx, dy in offsets:
        col, row = base[:, 0] + dx, base[:, 1] + dy
        inside = (col >= 0) & (col < SIZE[0]) & (row >= 0) & (row < SIZE[1])
        col, row = np.clip(col, 0, SIZE[0] - 1), np.clip(row, 0, SIZE[1] - 1)
        near = np.hypot(col + 0.5 - samples[:, 0], row + 0.5 - samples[:, 1]) <= radius
        take = inside & near & (strength[row, col] > best)
        best[take] = strength[row, col][take]
        out[take] = ink[row, col][take]
    return out


def _hue(ink: np.ndarray) -> np.ndarray:
    """Which ink a pixel's difference from the paper points to: +1 for the visible ink, -1 for
    the hidden ink (cosine to each ink's paper-minus-ink direction, independent of coverage)."""
    paper = np.array(STYLE.paper[:3])
    visible = paper - np.array(STYLE.ink[:3])
    hidden = paper - np.array(STYLE.hidden_ink[:3])
    unit = ink / np.maximum(np.linalg.norm(ink, axis=-1, keepdims=True), 1e-9)
    cos_v = unit @ (visible / np.linalg.norm(visible))
    cos_h = unit @ (hidden / np.linalg.norm(hidden))
    return np.where(cos_v > cos_h, 1, -1)


def _samples(a: np.ndarray, b: np.ndarray, spacing: float = 2.0) -> np.ndarray:
    count = max(int(np.linalg.norm(b - a) / spacing), 2)
    t = np.linspace(0, 1, count)[:, None]
    return a + t * (b - a)


def _cube_edges(lo, hi, eye):
    """The 12 edges of a box as (a, b, visible): an edge is visible when one of its two faces
    faces the eye (the box is convex)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    edges = []
    for axis in range(3):
        others = [k for k in range(3) if k != axis]
        for ends in itertools.product((0, 1), repeat=2):
            a, b = lo.copy(), lo.copy()
            b[axis] = hi[axis]
            faces_front = []
            for k, side in zip(others, ends, strict=True):
                a[k] = b[k] = (lo[k], hi[k])[side]
                normal = np.zeros(3)
                normal[k] = 1.0 if side else -1.0
                faces_front.append(normal @ (eye - a) > 0)
            edges.append((a, b, any(faces_front)))
    return edges


def cube_model(lo=(-1, -1, -1), hi=(1, 1, 1)) -> blueprint.Model:
    return examples.assemble({"cube": examples.box(lo, hi)})


# -- the cube ------------------------------------------------------------------------------------
def test_cube_shows_all_twelve_edges(renderer):
    model = cube_model()
    frame = _render(renderer, model)
    ink = _ink(frame.image)
    edges = _cube_edges((-1, -1, -1), (1, 1, 1), np.array(frame.camera.eye))
    visible = [e for e in edges if e[2]]
    hidden = [e for e in edges if not e[2]]
    assert len(visible) == 9 and len(hidden) == 3, "a general view of a cube hides 3 edges"

    ends = [(project(np.array([a, b]), frame.camera, size=SIZE)) for a, b, _ in edges]
    seg_a = np.array([p[0] for p in ends])
    seg_b = np.array([p[1] for p in ends])
    is_visible = np.array([e[2] for e in edges])

    strengths = {True: [], False: []}
    for (a, b, vis), (pa, pb) in zip(edges, zip(seg_a, seg_b, strict=True), strict=True):
        samples = _samples(pa, pb)
        near_ink = _strongest_near(ink, samples)
        strength = near_ink.max(axis=-1)
        missing = samples[strength < INK]
        assert len(missing) == 0, (
            f"{'visible' if vis else 'hidden'} edge {a} - {b}: no ink within 1 px of "
            f"{len(missing)} of {len(samples)} points, e.g. at {missing[:3].round(1).tolist()}"
        )
        # the colour says which ink, away from crossings with lines of the other kind
        other = _segment_distance(samples, seg_a[is_visible != vis], seg_b[is_visible != vis])
        clear = other.min(axis=1) > 3.0
        hue = _hue(near_ink[clear])
        expected = 1 if vis else -1
        assert (hue == expected).all(), (
            f"{'visible' if vis else 'hidden'} edge {a} - {b} drawn in the wrong ink at "
            f"{(hue != expected).sum()} of {clear.sum()} points"
        )
        strengths[vis].extend(strength[clear])
    # hidden lines are fainter: the hidden ink at its opacity, never the full visible ink
    visible_strength, hidden_strength = np.median(strengths[True]), np.median(strengths[False])
    hidden_full = 255 * STYLE.hidden_opacity * (np.array(STYLE.paper[:3]) - STYLE.hidden_ink[:3]).max()
    assert max(strengths[False]) <= hidden_full + 3
    assert hidden_strength < 0.85 * visible_strength, (visible_strength, hidden_strength)


def test_cube_faces_are_clean_paper(renderer):
    """No speckle: every pixel farther than 3 px from all 12 projected edges is paper."""
    frame = _render(renderer, cube_model())
    edges = _cube_edges((-1, -1, -1), (1, 1, 1), np.array(frame.camera.eye))
    a = project(np.array([e[0] for e in edges]), frame.camera, size=SIZE)
    b = project(np.array([e[1] for e in edges]), frame.camera, size=SIZE)
    far = _segment_distance(_pixel_centres(), a, b).min(axis=1).reshape(SIZE[1], SIZE[0]) > 3.0
    strength = np.abs(_ink(frame.image)).max(axis=-1)
    dirty = far & (strength > PAPER_NOISE)
    assert far.sum() > 0.8 * far.size
    assert not dirty.any(), (
        f"{dirty.sum()} pixels away from every edge are not paper, e.g. (row, col) "
        f"{np.argwhere(dirty)[:5].tolist()}, up to {strength[dirty].max():.0f} off"
    )
    assert (frame.image[..., 3] == 255).all()


# -- two touching boxes --------------------------------------------------------------------------
LEFT = examples.box((-1, -0.5, -0.5), (0, 0.5, 0.5))
RIGHT = examples.box((0, -0.5, -0.5), (1, 0.5, 0.5))


def _boundary_samples(frame):
    """Points on the visible part of the shared face's outline (x = 0 on the front and top
    faces), away from the outer edges' lines, and the box's 12 outer edges projected."""
    eye = np.array(frame.camera.eye)
    assert eye[2] > 0.5 and eye[1] > 0.5, "the camera sees the front (z+) and top (y+) faces"
    outline = [((0, -0.5, 0.5), (0, 0.5, 0.5)), ((0, 0.5, -0.5), (0, 0.5, 0.5))]
    samples = np.concatenate(
        [_samples(*project(np.array([a, b], float), frame.camera, size=SIZE)) for a, b in outline], axis=0
    )
    edges = _cube_edges((-1, -0.5, -0.5), (1, 0.5, 0.5), eye)
    a = project(np.array([e[0] for e in edges]), frame.camera, size=SIZE)
    b = project(np.array([e[1] for e in edges]), frame.camera, size=SIZE)
    keep = _segment_distance(samples, a, b).min(axis=1) > 3.0
    assert keep.sum() >= 40
    return samples[keep]


def test_touching_parts_show_their_shared_boundary(renderer):
    model = examples.assemble({"left": LEFT, "right": RIGHT})
    frame = _render(renderer, model)
    samples = _boundary_samples(frame)
    near_ink = _strongest_near(_ink(frame.image), samples)
    strength = near_ink.max(axis=-1)
    assert (strength >= INK).all(), f"no line at {(strength < INK).sum()} of {len(samples)} points"
    assert (_hue(near_ink) == 1).all(), "the part boundary on visible faces is drawn in visible ink"


def test_one_part_shows_no_line_across_coplanar_faces(renderer):
    """The same two boxes as one part: their front and top faces are coplanar, so layer 0 has
    no crease, part boundary or depth step there. The shared wall inside is still a hidden
    surface, so a full drawing shows its outline, but only in hidden ink."""
    v_left, f_left = LEFT
    v_right, f_right = RIGHT
    model = blueprint.Model.from_arrays(np.vstack([v_left, v_right]), np.vstack([f_left, f_right + 8]))
    front_only = _render(renderer, model, max_layers=1)
    samples = _boundary_samples(front_only)
    strength = _strongest_near(_ink(front_only.image), samples).max(axis=-1)
    assert (strength <= PAPER_NOISE).all(), (
        f"a line on coplanar faces of one part at {(strength > PAPER_NOISE).sum()} of "
        f"{len(samples)} points (up to {strength.max():.0f} off paper)"
    )
    full = _render(renderer, model)
    near_ink = _strongest_near(_ink(full.image), samples)
    inked = near_ink.max(axis=-1) >= INK
    assert (_hue(near_ink[inked]) == -1).all(), "only hidden ink where the inner wall meets the faces"


# -- triangle soup, mixed winding ----------------------------------------------------------------
def test_soup_with_flipped_faces_draws_the_same_cube(renderer):
    positions, faces = examples.box((-1, -1, -1), (1, 1, 1))
    soup = positions[faces].reshape(-1, 3)  # 36 vertices, nothing shared
    soup_faces = np.arange(36).reshape(12, 3)
    soup_faces[::2] = soup_faces[::2, ::-1]  # every other triangle wound the wrong way
    welded = cube_model()
    mixed = examples.assemble({"cube": (soup, soup_faces)})
    assert len(mixed.positions) == 36
    a = _render(renderer, welded, max_layers=None).image.astype(int)
    b = _render(renderer, mixed, max_layers=None).image.astype(int)
    diff = np.abs(a - b).max(axis=-1)
    assert diff.max() <= 8 and (diff > 0).sum() <= 20, (
        f"{(diff > 0).sum()} pixels differ, by up to {diff.max()}"
    )


@pytest.mark.parametrize("supersample", [1, 3])
def test_cube_edges_at_other_supersampling(renderer, supersample):
    """The edge positions do not depend on the supersampling factor."""
    frame = _render(renderer, cube_model(), supersample=supersample)
    ink = _ink(frame.image)
    edges = _cube_edges((-1, -1, -1), (1, 1, 1), np.array(frame.camera.eye))
    for a, b, _ in edges:
        samples = _samples(*project(np.array([a, b]), frame.camera, size=SIZE))
        strength = _strongest_near(ink, samples).max(axis=-1)
        assert (strength >= INK).all(), f"edge {a} - {b} at supersample {supersample}"
