"""Passes drawn over the tiles their layer covers (pipeline.tiles): the tile arithmetic against
brute force, and every drawing the same, pixel for pixel, as with full-screen passes."""

from __future__ import annotations

import textwrap

import numpy as np
import pytest
from scan_helpers import noisy_sphere

import blueprint
from blueprint import examples
from blueprint.pipeline import load_pipeline, render_blueprint
from blueprint.pipeline.tiles import TILE, Tiles, covered_tiles, rectangles, widen


def sparse_depth(rng, h, w):
    depth = np.ones((h, w), np.float32)
    for _ in range(5):
        y, x = rng.integers(0, h), rng.integers(0, w)
        depth[y : y + rng.integers(1, 9), x : x + rng.integers(1, 9)] = rng.random()
    return depth


@pytest.mark.parametrize("shape", [(64, 64), (75, 50), (17, 130)])
def test_covered_tiles_and_widen_against_brute_force(shape):
    rng = np.random.default_rng(sum(shape))
    depth = sparse_depth(rng, *shape)
    tiles = covered_tiles(depth)
    th, tw = -(-shape[0] // TILE), -(-shape[1] // TILE)
    rows = [depth[i * TILE : (i + 1) * TILE] for i in range(th)]
    expected = np.array([[(row[:, j * TILE : (j + 1) * TILE] < 1).any() for j in range(tw)] for row in rows])
    np.testing.assert_array_equal(tiles, expected)
    for by in (1, 2):
        grown = widen(tiles, by)
        want = np.zeros_like(tiles)
        for i, j in np.argwhere(tiles):
            want[max(i - by, 0) : i + by + 1, max(j - by, 0) : j + by + 1] = True
        np.testing.assert_array_equal(grown, want)


@pytest.mark.parametrize("size", [(64, 48), (50, 75)])
def test_rectangles_cover_exactly_the_tiles(size):
    """Rasterised at pixel centres, the rectangles cover every pixel of a set tile and no other."""
    w, h = size
    rng = np.random.default_rng(w)
    tiles = rng.random((-(-h // TILE), -(-w // TILE))) < 0.5
    vertices = rectangles(tiles, size).reshape(-1, 6, 2)
    covered = np.zeros((h, w), int)
    ys, xs = np.mgrid[0:h, 0:w] + 0.5
    for quad in vertices:
        (x0, y0), (x1, y1) = (quad.min(axis=0) + 1) / 2 * (w, h), (quad.max(axis=0) + 1) / 2 * (w, h)
        covered += (xs >= x0) & (xs < x1) & (ys >= y0) & (ys < y1)
    want = np.repeat(np.repeat(tiles, TILE, axis=0), TILE, axis=1)[:h, :w]
    np.testing.assert_array_equal(covered, want.astype(int))


@pytest.fixture
def tiled(renderer, monkeypatch):
    """Switches the executor's tiled passes on or off, counting the tiled draws."""
    if renderer.use_compute:
        pytest.skip("this renderer runs the image passes in compute form, which is not tiled")
    ex = renderer.executor
    saved = ex.tiled
    drawn = []
    original = Tiles.draw

    def counted(self, prog, reach):
        drawn.append(reach)
        return original(self, prog, reach)

    monkeypatch.setattr(Tiles, "draw", counted)

    def use(on: bool) -> list:
        ex.tiled = on
        drawn.clear()
        return drawn

    yield use
    ex.tiled = saved


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"line_width": 3.0},
        {"style": "paper", "max_layers": None},
        {"highlight": ["shaft"], "reveal": 0.5},
        {"shade": ["cover"], "supersample": 1},
        {"supersample": 3, "line_width": 2.0},
    ],
    ids=["default", "wide", "paper-all", "reveal", "shade", "supersample3"],
)
def test_same_drawing_as_full_screen_passes(renderer, tiled, options):
    model = examples.gearbox()
    for key in ("highlight", "shade"):
        if key in options:
            options[key] = np.array([n in options[key] for n in model.part_names])
    images = {}
    for on in (True, False):
        drawn = tiled(on)
        images[on] = render_blueprint(renderer, model, size=(160, 120), **options).image
        assert bool(drawn) == on
    np.testing.assert_array_equal(images[True], images[False])


def test_passes_that_spread_are_drawn_whole(renderer, tiled, tmp_path):
    """A blur and an inversion of the per-layer edges have values far from any covered pixel:
    they run full screen, and what they read outside the tiles is cleared, not stale."""
    text = textwrap.dedent(
        """
        [pipeline]
        output = "drawing"
        layers = 4
        [attributes]
        depth = {}
        normal = {}
        ids = {}
        [passes.edges]
        op = "edges"
        inputs = { depth = "depth", normal = "normal", ids = "ids" }
        per_layer = true
        [passes.soft]
        op = "blur"
        inputs = { source = "edges" }
        params = { sigma = 3 }
        per_layer = true
        [passes.negative]
        op = "invert"
        inputs = { source = "soft" }
        per_layer = true
        [passes.drawing]
        op = "composite"
        inputs = { layers = "negative" }
        """
    )
    path = tmp_path / "spread.toml"
    path.write_text(text, encoding="utf-8")
    spec = load_pipeline(str(path))
    ex = renderer.executor
    model = examples.gearbox()
    outputs = {}
    for on in (True, False):
        drawn = tiled(on)
        outputs[on] = ex.run(spec, model, size=(96, 72)).output
        assert (set(drawn) == {1}) if on else not drawn
    np.testing.assert_array_equal(outputs[True], outputs[False])


def test_contour_lines_composed_over_the_tiles(renderer, tiled, monkeypatch):
    """A picture with smooth contour lines composes its maps over the covered tiles too: the
    lines lie on the faces drawn, within the tile the composite's tiles are widened by, so
    the picture is the full-screen composite's to the pixel (a sphere cut by the frame's
    edge, another behind a plate, their lines at levels 0 and 1)."""
    sphere = noisy_sphere(0.006)
    moved = sphere.positions + (1.6, 0.4, 0.0)
    plate = examples.box((-1.2, -1.2, 1.3), (0.0, 1.2, 1.35))
    model = examples.assemble(
        {"sphere": (sphere.positions, sphere.faces), "edge": (moved, sphere.faces), "plate": plate}
    )
    composed = []
    original = Tiles.draw_layers

    def counted(self, prog, first, count, reach):
        composed.append(count)
        return original(self, prog, first, count, reach)

    monkeypatch.setattr(Tiles, "draw_layers", counted)
    images = {}
    for on in (True, False):
        tiled(on)
        composed.clear()
        options = dict(size=(200, 150), view="front", smooth_contours=True, renderer=renderer)
        images[on] = np.asarray(blueprint.render(model, **options))
        assert renderer.executor.last_run.contours is not None
        assert bool(composed) == on
    np.testing.assert_array_equal(images[True], images[False])
