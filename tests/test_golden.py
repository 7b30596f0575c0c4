"""Golden frames at 256x192, one per style and option: the generated gearbox and sleeve
(tests/golden_helpers.py has the cases, the models and the tolerances).

Compared only on the pinned software rasterizer (Mesa llvmpipe) with explicit tolerances: the
mean absolute difference of every channel below ``MEAN_TOLERANCE`` (0-255 scale) and fewer than
``PIXEL_FRACTION`` of the pixels differing by more than ``PIXEL_TOLERANCE`` in any channel.
Colour is compared premultiplied by alpha, so the colour of invisible pixels does not count.
Each frame's layer count and the samples of its layers are pinned exactly in
tests/golden/frames.json.

Regenerate with ``pytest tests/test_golden.py --regen-goldens``, then look at the images. On a
mismatch the actual image, the golden and an amplified difference are saved in the ``artifacts``
folder (tests/_artifacts). Property tests beside the goldens check what the images must show
on any renderer: paper colours, alpha, the grid's period, thicker lines, four views on the
plan sheet, and that the options pinned change the picture beyond the tolerance.
"""

from __future__ import annotations

import numpy as np
import pytest
from golden_helpers import (
    CASES,
    GOLDEN,
    MODELS,
    PINNED,
    SIZE,
    assert_frame_pinned,
    assert_like_golden,
    case,
    compare,
    frame_record,
    golden_path,
    pinned_frames,
    skip_unless_pinned,
    write_pinned_frames,
)
from PIL import Image

from blueprint import render_frame
from blueprint.compose.lookup import get_style
from blueprint.compose.style import STYLES

# Where depth masking stopped today, written here rather than in frames.json so that
# --regen-goldens cannot move it: (layers, share of the highlighted parts uncovered).
REVEALED = {
    "paper_reveal90": (5, 0.9522422092728655),
    "paper_reveal50": (3, 0.800101342791994),
    "sleeve_reveal100": (5, 1.0),
}

# (case, the case without its option): the option must change the picture beyond the
# tolerance, or its golden could not tell the option was lost
OPTION_CHANGES = [
    ("blueprint_ss1_all_layers", "blueprint"),
    ("blueprint_layers10_line2_5", "blueprint_line2"),
    ("sleeve_crease50_all_layers", "sleeve_paper_all_layers"),
    ("blueprint_highlight", "blueprint"),
    ("paper_highlight", "paper"),
    ("paper_reveal90", "paper_highlight"),
    ("paper_reveal50", "paper_reveal90"),
    ("paper_shade", "paper"),
    ("paper_shade50", "paper_shade"),
    ("paper_shade_highlight", "paper_shade"),
    ("paper_shade_highlight", "paper_highlight"),
    ("paper_id_silhouettes", "paper"),
    ("blueprint_glyphs", "blueprint"),
    ("blueprint_glyphs_highlight", "blueprint_glyphs"),
    ("blueprint_glyphs_highlight", "blueprint_highlight"),
]


def rgba8(color) -> np.ndarray:
    return np.round(np.asarray(color) * 255).astype(np.uint8)


@pytest.fixture(scope="module")
def frames(renderer, request) -> dict:
    """Every case rendered once; with --regen-goldens (on the pinned rasterizer) also written
    as the goldens and frames.json."""
    models = {name: build() for name, build in MODELS.items()}
    out = {}
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("SOURCE_DATE_EPOCH", "0")  # the plan sheet's title block dates it
        for name in CASES:
            model, options = case(name)
            frame = render_frame(models[model], size=SIZE, renderer=renderer, **options)
            assert frame.layers >= 2, f"{name}: hidden layers missing"
            out[name] = frame
    for model in models.values():
        renderer.forget(model)
    if request.config.getoption("--regen-goldens") and renderer.info["renderer"].startswith(PINNED):
        GOLDEN.mkdir(exist_ok=True)
        for name, frame in out.items():
            Image.fromarray(frame.image).save(golden_path(name))
        write_pinned_frames({name: frame_record(frame) for name, frame in out.items()})
    return out


@pytest.fixture(scope="module")
def images(frames) -> dict[str, np.ndarray]:
    """(H, W, 4) uint8 of every case."""
    return {name: frame.image for name, frame in frames.items()}


@pytest.mark.parametrize("name", list(CASES))
def test_golden_image(name, images, renderer, artifacts):
    skip_unless_pinned(renderer)
    assert_like_golden(name, images[name], artifacts)


@pytest.mark.parametrize("name", list(CASES))
def test_golden_layers(name, frames, renderer):
    skip_unless_pinned(renderer)
    assert_frame_pinned(name, frames[name])


def test_frames_json_has_every_case_and_no_other():
    assert list(pinned_frames()) == list(CASES)


@pytest.mark.parametrize("name", list(REVEALED))
def test_depth_masking_stops_where_it_did(name, frames, renderer):
    skip_unless_pinned(renderer)
    layers, revealed = REVEALED[name]
    assert frames[name].layers == layers
    assert frames[name].revealed == pytest.approx(revealed, abs=1e-6)


# the pixels, of a picture's, that an option changes by more than a golden's pixel tolerance at
# the least: a golden's tolerance admits what another renderer draws apart, which an option's
# change on one renderer need not pass (highlighted parts revealed to 90 %, against all of
# them: 78 such pixels on llvmpipe, 56 on the H200)
CHANGED_FRACTION = 0.0005


@pytest.mark.parametrize(("name", "without"), OPTION_CHANGES, ids=lambda n: n)
def test_each_option_changes_the_picture(images, name, without):
    _, fraction, _ = compare(images[name], images[without])
    assert fraction >= CHANGED_FRACTION, compare(images[name], images[without])[:2]


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


@pytest.mark.parametrize("name", ["blueprint", "paper", "wireframe", "blueprint_line2", "paper_plan"])
def test_paper_colour_at_the_corners(images, name):
    paper = rgba8(get_style(CASES[name]["style"]).paper)
    np.testing.assert_array_equal(_corners(images[name]), np.tile(paper, (4, 1)))


def test_plan_sheet_has_four_views(images):
    """Top, iso, front and right view above the title block, in four blocks of ink that a row
    and a column of paper keep apart, inside the border."""
    image = images["paper_plan"].astype(int)
    ink = np.abs(image - image[0, 0]).max(axis=-1) > 8
    height, width = ink.shape
    views = ink[8 : int(0.6 * height), 8 : width - 8]  # inside the border, above the title block
    rows = [y for y in range(len(views) // 4, 3 * len(views) // 4) if not views[y].any()]
    columns = [x for x in range(views.shape[1] // 4, 3 * views.shape[1] // 4) if not views[:, x].any()]
    assert rows and columns
    y, x = rows[len(rows) // 2], columns[len(columns) // 2]
    for block in (views[:y, :x], views[:y, x:], views[y:, :x], views[y:, x:]):
        assert block.mean() > 0.02
    assert ink[:, 2:5].any(axis=1).mean() > 0.95  # the border's left line


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
    """Paper style: the visible ink (#0a1f44) and the lighter hidden ink (#4f5d75) both appear."""
    image = images["paper"][..., :3].astype(int)
    style = STYLES["paper"]
    visible = rgba8(style.ink)[:3]
    hidden = rgba8(style.hidden_ink)[:3]
    near_visible = (np.abs(image - visible).max(axis=-1) <= 12).sum()
    # a hidden line of layer 1 over white where it covers a pixel, its width a share of it,
    # give or take anti-aliasing
    share = style.hidden_opacity * style.hidden_width / style.width
    hidden_on_white = np.round(share * hidden + (1 - share) * 255).astype(int)
    near_hidden = (np.abs(image - hidden_on_white).max(axis=-1) <= 24).sum()
    assert near_visible > 100 and near_hidden > 100, (near_visible, near_hidden)


def test_wireframe_is_binary_before_filtering(images):
    """Wireframe thresholds the edge samples, so with 2x2 supersampling each of a pixel's four
    samples is paper, a hidden line (black at 0.5) or a visible one (black), the strongest line
    of the sample's layers: the pixel is 255 * (1 - j / 8) for a whole j from 0 to 8 (give or
    take rounding)."""
    image = images["wireframe"]
    assert (image[..., 0] == image[..., 1]).all() and (image[..., 1] == image[..., 2]).all()
    assert (image[..., 3] == 255).all()
    allowed = {round(255 * (1 - j / 8)) + d for j in range(9) for d in (-1, 0, 1)}
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
    """Every mark belongs to a line: no blob of ink of one or two pixels on its own. Any ink
    counts (4 levels of 255 off the paper): a faint hidden line half a pixel wide alternates
    between a pixel it covers and two it straddles, and a higher cut would chop it into dots."""
    from scipy import ndimage

    image = images[name].astype(int)
    ink = np.abs(image - image[0, 0]).max(axis=-1) > 4
    labels, count = ndimage.label(ink, structure=np.ones((3, 3)))
    sizes = ndimage.sum(ink, labels, range(1, count + 1))
    assert count >= 1 and (sizes > 2).all(), sorted(sizes)[:10]


def test_line_width_two_draws_thicker_lines(images):
    paper = rgba8(STYLES["blueprint"].paper)[:3].astype(int)

    def ink(image):
        return np.abs(image[..., :3].astype(int) - paper).sum()

    ratio = ink(images["blueprint_line2"]) / ink(images["blueprint"])
    assert 1.5 < ratio < 2.6, ratio
