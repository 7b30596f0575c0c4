"""Golden images of the generated gearbox at 256x192, one per style and option.

Compared only on the pinned software rasterizer (Mesa llvmpipe) with explicit tolerances:
the mean absolute difference of every channel below ``MEAN_TOLERANCE`` (0-255 scale) and fewer
than ``PIXEL_FRACTION`` of the pixels differing by more than ``PIXEL_TOLERANCE`` in any channel.
Colour is compared premultiplied by alpha, so the colour of invisible pixels does not count.

Regenerate with ``pytest tests/test_golden.py --regen-goldens``, then look at the images. On a
mismatch the actual image, the golden and an amplified difference are saved in the ``artifacts``
folder (tests/_artifacts). Property tests beside the goldens check what the images must show
on any renderer: paper colours, alpha, the grid's period, thicker lines.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from blueprint import examples, render_frame
from blueprint.compose.style import STYLES, get_style

GOLDEN = Path(__file__).parent / "golden"
SIZE = (256, 192)
PINNED = "llvmpipe"
MEAN_TOLERANCE = 1.0
PIXEL_TOLERANCE = 32
PIXEL_FRACTION = 0.005

CASES = {
    "blueprint": dict(style="blueprint"),
    "paper": dict(style="paper"),
    "transparent": dict(style="transparent"),
    "wireframe": dict(style="wireframe"),
    "blueprint_grid16": dict(style=get_style("blueprint", 16)),
    "blueprint_line2": dict(style="blueprint", line_width=2.0),
}


def rgba8(color) -> np.ndarray:
    return np.round(np.asarray(color) * 255).astype(np.uint8)


@pytest.fixture(scope="module")
def images(renderer) -> dict[str, np.ndarray]:
    """Every case rendered once: (H, W, 4) uint8."""
    model = examples.gearbox()
    out = {}
    for name, options in CASES.items():
        frame = render_frame(model, size=SIZE, renderer=renderer, **options)
        assert frame.layers >= 2, f"{name}: hidden layers missing"
        out[name] = frame.image
    renderer.forget(model)
    return out


def _comparable(image: np.ndarray) -> np.ndarray:
    f = image.astype(np.float64)
    f[..., :3] *= f[..., 3:4] / 255.0
    return f


def compare(actual: np.ndarray, expected: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """(mean absolute difference per channel, fraction of differing pixels, |difference|)."""
    diff = np.abs(_comparable(actual) - _comparable(expected))
    return diff.mean(axis=(0, 1)), float((diff.max(axis=-1) > PIXEL_TOLERANCE).mean()), diff


def _save_failure(folder: Path, name: str, actual: np.ndarray, expected: np.ndarray, diff) -> list[Path]:
    paths = [folder / f"{name}.actual.png", folder / f"{name}.golden.png", folder / f"{name}.diff.png"]
    Image.fromarray(actual).save(paths[0])
    Image.fromarray(expected).save(paths[1])
    amplified = np.clip(diff.max(axis=-1) * 4, 0, 255).astype(np.uint8)
    visible = np.stack([amplified, amplified // 4, amplified // 4, np.full_like(amplified, 255)], axis=-1)
    Image.fromarray(visible).save(paths[2])
    return paths


@pytest.mark.parametrize("name", list(CASES))
def test_golden_image(name, images, renderer, request, artifacts):
    if not renderer.info["renderer"].startswith(PINNED):
        pytest.skip(f"goldens are made on {PINNED}, this is {renderer.info['renderer']}")
    actual = images[name]
    path = GOLDEN / f"{name}.png"
    if request.config.getoption("--regen-goldens"):
        GOLDEN.mkdir(exist_ok=True)
        Image.fromarray(actual).save(path)
    if not path.exists():
        pytest.fail(f"no golden image {path}: run pytest --regen-goldens and look at it")
    with Image.open(path) as picture:
        expected = np.asarray(picture.convert("RGBA"))
    assert expected.shape == actual.shape, f"golden is {expected.shape}, rendered {actual.shape}"
    mean, fraction, diff = compare(actual, expected)
    if mean.max() >= MEAN_TOLERANCE or fraction >= PIXEL_FRACTION:
        saved = _save_failure(artifacts, name, actual, expected, diff)
        pytest.fail(
            f"{name}: mean abs difference per channel {np.round(mean, 3).tolist()} (limit "
            f"{MEAN_TOLERANCE}), {fraction:.3%} pixels differ by > {PIXEL_TOLERANCE} (limit "
            f"{PIXEL_FRACTION:.1%}); see {', '.join(str(p) for p in saved)}"
        )


def test_compare_exact_values():
    a = np.zeros((10, 10, 4), np.uint8)
    a[..., 3] = 255
    b = a.copy()
    b[0, 0, 0] = 100  # one pixel of 100, far above the per-pixel tolerance
    mean, fraction, _ = compare(b, a)
    np.testing.assert_allclose(mean, [1.0, 0, 0, 0])
    assert fraction == 0.01
    # colour under zero alpha does not count
    c, d = np.zeros((2, 2, 4), np.uint8), np.zeros((2, 2, 4), np.uint8)
    d[..., :3] = 200
    assert compare(c, d)[0].max() == 0


# -- what the images must show, on any renderer ------------------------------------------------------


def _corners(image: np.ndarray) -> np.ndarray:
    return np.stack([image[0, 0], image[0, -1], image[-1, 0], image[-1, -1]])


@pytest.mark.parametrize("name", ["blueprint", "paper", "wireframe", "blueprint_line2"])
def test_paper_colour_at_the_corners(images, name):
    paper = rgba8(get_style(CASES[name]["style"]).paper)
    np.testing.assert_array_equal(_corners(images[name]), np.tile(paper, (4, 1)))


def test_transparent_has_alpha(images):
    image = images["transparent"]
    alpha = image[..., 3]
    np.testing.assert_array_equal(_corners(image)[:, 3], 0)
    assert (alpha == 0).mean() > 0.5  # mostly empty
    assert (alpha == 255).sum() > 100  # solid visible ink
    assert ((alpha > 0) & (alpha < 255)).sum() > 100  # anti-aliased and hidden (faded) ink
    ink = rgba8(STYLES["transparent"].ink)
    solid = alpha == 255
    # straight alpha: solid pixels carry the visible ink colour exactly
    assert (np.abs(image[solid][:, :3].astype(int) - ink[:3]).max(axis=-1) <= 1).mean() > 0.9


def test_hidden_lines_are_drawn(images):
    """Paper style: the visible ink (#0a1f44) and the lighter hidden ink (#2f6bd0) both appear."""
    image = images["paper"][..., :3].astype(int)
    visible = rgba8(STYLES["paper"].ink)[:3]
    hidden = rgba8(STYLES["paper"].hidden_ink)[:3]
    near_visible = (np.abs(image - visible).max(axis=-1) <= 12).sum()
    # hidden ink at opacity 0.8 over white, give or take anti-aliasing
    hidden_on_white = np.round(0.8 * hidden + 0.2 * 255).astype(int)
    near_hidden = (np.abs(image - hidden_on_white).max(axis=-1) <= 24).sum()
    assert near_visible > 100 and near_hidden > 100, (near_visible, near_hidden)


def test_wireframe_is_binary_before_filtering(images):
    """Wireframe thresholds the edge samples, so with 2x2 supersampling each layer covers a pixel
    by 0, 1/4, 1/2, 3/4 or all of it, and black ink over white composes to grey levels
    255 * 0.75^a * 0.5^b (give or take rounding)."""
    image = images["wireframe"]
    assert (image[..., 0] == image[..., 1]).all() and (image[..., 1] == image[..., 2]).all()
    assert (image[..., 3] == 255).all()
    allowed = {round(255 * 0.75**a * 0.5**b) + d for a in range(24) for b in range(10) for d in (-1, 0, 1)}
    levels = set(np.unique(image[..., 0]).tolist())
    assert levels <= allowed, sorted(levels - allowed)
    assert {0, 255} <= levels


def test_grid_has_a_period_of_16_pixels(images):
    """Minor lines every 16 pixels, a major line every fifth (80 pixels), 1 pixel wide."""
    gridded = images["blueprint_grid16"].astype(int)
    plain = images["blueprint"].astype(int)
    for line, reference in ((gridded[1, :, :3], plain[1, :, :3]), (gridded[:, 1, :3], plain[:, 1, :3])):
        # a row and a column in the margin, where there is no model
        on = np.flatnonzero((line != reference).any(axis=-1))
        assert len(on) >= 10, "no grid in the margin"
        np.testing.assert_array_equal(np.diff(on), 16)
        np.testing.assert_array_equal(line[:-80], line[80:])
        assert len({tuple(v) for v in line[on]}) == 2  # minor and major lines


@pytest.mark.parametrize("name", [n for n in CASES if n != "blueprint_grid16"])
def test_no_speckle(images, name):
    """Every mark belongs to a line: no blob of ink of one or two pixels on its own."""
    from scipy import ndimage

    image = images[name].astype(int)
    ink = np.abs(image - image[0, 0]).max(axis=-1) > 8
    labels, count = ndimage.label(ink, structure=np.ones((3, 3)))
    sizes = ndimage.sum(ink, labels, range(1, count + 1))
    assert count >= 1 and (sizes > 2).all(), sorted(sizes)[:10]


def test_line_width_two_draws_thicker_lines(images):
    paper = rgba8(STYLES["blueprint"].paper)[:3].astype(int)

    def ink(image):
        return np.abs(image[..., :3].astype(int) - paper).sum()

    ratio = ink(images["blueprint_line2"]) / ink(images["blueprint"])
    assert 1.5 < ratio < 2.6, ratio
