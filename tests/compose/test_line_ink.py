"""How strong and wide lines are drawn: coincident lines of several layers are one line (the
strongest ink, not the sum), hidden lines stay clearly fainter than visible ones in every style,
and narrower (ISO 128: half the width of visible lines).

A square tube lying across the view, seen from the top orthographically, has its inner walls
edge-on: their rims at the inner half-width are hidden edges of three layers (the tube's inner
ceiling, its inner floor and its outer bottom) on the same pixels, the way featuretype's side
holes are in its plan. Ink is measured as luminance contrast against the paper, 1 for the
style's visible ink at full coverage; a line's ink per unit length is the ink summed across it
(independent of where it falls in the pixel grid). Which pixels are hidden-only comes from a
second frame of layer 0 alone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import project

import blueprint
from blueprint import examples
from blueprint.compose.style import STYLES

SIZE = (256, 256)
HALF_LENGTH, OUTER, INNER = 1.0, 0.5, 0.25


def _luma(rgb: np.ndarray) -> np.ndarray:
    return rgb[..., :3] @ np.array([0.2126, 0.7152, 0.0722])


def ink_of(image: np.ndarray, style) -> np.ndarray:
    """(H, W) ink of each pixel: its contrast against the paper over the visible ink's. A
    transparent frame is laid over white first (straight alpha)."""
    rgba = image.astype(np.float64) / 255.0
    if style.paper is None:
        paper = np.ones(3)
        rgb = rgba[..., :3] * rgba[..., 3:] + (1.0 - rgba[..., 3:])
    else:
        paper = np.asarray(style.paper[:3], np.float64)
        rgb = rgba[..., :3]
    full = _luma(np.asarray(style.ink[:3], np.float64)) - _luma(paper)
    return (_luma(rgb) - _luma(paper)) / full


def single_line_ink(style, layer: int) -> float:
    """Ink of one line of ``layer`` at full coverage."""
    ink = style.layer_inks(layer + 1)[layer]
    paper = np.ones(3) if style.paper is None else np.asarray(style.paper[:3], np.float64)
    full = _luma(np.asarray(style.ink[:3], np.float64)) - _luma(paper)
    return float(ink[3] * (_luma(ink[:3]) - _luma(paper)) / full)


def square_tube() -> blueprint.Model:
    """A square tube along x, its walls parallel to the axes (a 4-sided tube turned by 45°)."""
    vertices, faces = examples.tube(INNER * math.sqrt(2), OUTER * math.sqrt(2), 2 * HALF_LENGTH, 4, axis=0)
    y, z = vertices[:, 1].copy(), vertices[:, 2].copy()
    c = math.cos(math.pi / 4)
    vertices[:, 1], vertices[:, 2] = c * (y - z), c * (y + z)
    # off-centre, so the lines do not all fall on pixel boundaries alike
    return examples.assemble({"tube": (vertices + [0.013, 0.0, 0.031], faces)})


def line_ink(ink: np.ndarray, a: np.ndarray, b: np.ndarray, band: float = 3.0, trim: float = 6.0) -> float:
    """Ink per pixel of length of the line a-b (pixels): the ink of every pixel within
    ``band`` of it, summed, over the length, leaving ``trim`` pixels at each end."""
    rows, cols = np.mgrid[0 : ink.shape[0], 0 : ink.shape[1]]
    p = np.stack([cols + 0.5, rows + 0.5], axis=-1)
    d = b - a
    length = float(np.linalg.norm(d))
    t = ((p - a) @ d) / length
    across = np.abs((p - a) @ np.array([-d[1], d[0]]) / length)
    near = (across <= band) & (t >= trim) & (t <= length - trim)
    return float(ink[near].sum() / (length - 2 * trim))


def _frames(renderer, model, style, **options):
    camera = blueprint.Camera.fit(model.positions, "top", ortho=True)
    full = renderer.render(model, camera, size=SIZE, style=style, max_layers=None, **options)
    front = renderer.render(model, camera, size=SIZE, style=style, max_layers=1, **options)
    return full, front


def _hidden_only(full_ink: np.ndarray, front_ink: np.ndarray) -> np.ndarray:
    """Pixels with ink in the whole frame and none within 2 px in layer 0's frame."""
    near_front = np.zeros_like(front_ink, bool)
    inked = np.abs(front_ink) > 0.02
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            near_front |= np.roll(np.roll(inked, dy, 0), dx, 1)
    return (np.abs(full_ink) > 0.02) & ~near_front


@pytest.mark.parametrize("compute", [False, True], ids=["fragment", "compute"])
@pytest.mark.parametrize("name", list(STYLES))
def test_coincident_hidden_lines_are_one_line_fainter_than_visible(renderer, monkeypatch, name, compute):
    """Both forms of the compositor (fragment passes, compute where GL 4.3 has it)."""
    if compute and renderer.ctx.version_code < 430:
        pytest.skip("compute shaders need OpenGL 4.3")
    monkeypatch.setattr(renderer, "use_compute", compute)
    style = STYLES[name]
    model = square_tube()
    full, front = _frames(renderer, model, name)
    assert full.layers == 4
    ink, front_ink = ink_of(full.image, style), ink_of(front.image, style)
    x0, x1 = -HALF_LENGTH + 0.013, HALF_LENGTH + 0.013
    # the three hidden rims on the inner wall, and the outer silhouette (visible) beside it
    hidden_a, hidden_b = project(
        np.array([[x0, 0.0, INNER + 0.031], [x1, 0.0, INNER + 0.031]]), full.camera, size=SIZE
    )
    vis_a, vis_b = project(
        np.array([[x0, 0.0, OUTER + 0.031], [x1, 0.0, OUTER + 0.031]]), full.camera, size=SIZE
    )
    hidden = line_ink(ink, hidden_a, hidden_b)
    visible = line_ink(ink, vis_a, vis_b)
    # one line of layer 1, not three summed: its ink per unit length is layer 1's ink over one
    # hidden line's width (style.hidden_width px at line width 1; 8-bit rounding aside)
    strongest = single_line_ink(style, 1) * min(style.hidden_width / style.width, 1.0)
    assert hidden == pytest.approx(strongest, rel=0.06, abs=0.01), (hidden, strongest)
    assert visible == pytest.approx(single_line_ink(style, 0), rel=0.06), visible
    assert hidden <= 0.85 * visible, (hidden, visible)
    # at its brightest, a hidden-only pixel stays below the visible ink at full coverage
    only = _hidden_only(ink, front_ink)
    assert only.sum() > 200
    assert ink[only].max() <= 0.85, ink[only].max()


def test_featuretype_plan_hidden_lines_dimmer_than_visible(renderer, shared_models):
    """featuretype's side holes, seen from the top, are hidden rims of several layers on the
    same pixels; in every style they stay below 0.85 of the visible ink."""
    from blueprint.scene.loader import load_model

    model = load_model(shared_models / "trimesh" / "featuretype.STL")
    for name, style in STYLES.items():
        full, front = _frames(renderer, model, name)
        ink, front_ink = ink_of(full.image, style), ink_of(front.image, style)
        only = _hidden_only(ink, front_ink)
        assert only.sum() > 500, name
        assert ink[only].max() <= 0.85, (name, ink[only].max())
        assert ink[only].max() <= single_line_ink(style, 1) + 0.02, (name, ink[only].max())


@pytest.mark.parametrize("compute", [False, True], ids=["fragment", "compute"])
@pytest.mark.parametrize("line_width", [1.0, 4.0])
def test_hidden_lines_are_half_as_wide(renderer, monkeypatch, line_width, compute):
    """ISO 128's 2:1: in the paper style a visible line is ``line_width`` px wide, a hidden one
    half that; measured as ink per unit length over the ink of a line at full coverage."""
    if compute and renderer.ctx.version_code < 430:
        pytest.skip("compute shaders need OpenGL 4.3")
    monkeypatch.setattr(renderer, "use_compute", compute)
    style = STYLES["paper"]
    assert style.hidden_width == 0.5 * style.width
    model = square_tube()
    full, _ = _frames(renderer, model, "paper", line_width=line_width)
    ink = ink_of(full.image, style)
    x0, x1 = -HALF_LENGTH + 0.013, HALF_LENGTH + 0.013
    hidden_a, hidden_b = project(
        np.array([[x0, 0.0, INNER + 0.031], [x1, 0.0, INNER + 0.031]]), full.camera, size=SIZE
    )
    vis_a, vis_b = project(
        np.array([[x0, 0.0, OUTER + 0.031], [x1, 0.0, OUTER + 0.031]]), full.camera, size=SIZE
    )
    band = line_width + 2.0
    visible_width = line_ink(ink, vis_a, vis_b, band) / single_line_ink(style, 0)
    hidden_width = line_ink(ink, hidden_a, hidden_b, band) / single_line_ink(style, 1)
    assert visible_width == pytest.approx(line_width, rel=0.12), visible_width
    assert hidden_width == pytest.approx(0.5 * line_width, rel=0.12), hidden_width
