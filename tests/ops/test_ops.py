"""Every operation of the pipeline library against a NumPy reference, on small synthetic images.

Inputs and outputs are in texture row order (row 0 is texture row 0, y up), the edge of the
image is clamped. Integer and ID operations are compared exactly; binary operations exactly
away from ties (where the reference is within 1e-4 of the threshold either answer is right);
float operations within 1e-5 (float32 targets) or one step of 8 bits.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from blueprint import examples
from blueprint.compose.style import STYLES
from blueprint.ops import BLUR, OPS
from blueprint.pipeline.spec import OPERATIONS
from blueprint.scene.camera import fit_camera

H, W = 11, 13
rng = np.random.default_rng(4)


@pytest.fixture(scope="module")
def ex(renderer):
    return renderer.executor


def shift(a: np.ndarray, dx: int, dy: int) -> np.ndarray:
    """a(x + dx, y + dy), clamped to the image."""
    ys = np.clip(np.arange(a.shape[0]) + dy, 0, a.shape[0] - 1)
    xs = np.clip(np.arange(a.shape[1]) + dx, 0, a.shape[1] - 1)
    return a[ys][:, xs]


def rgba(h=H, w=W) -> np.ndarray:
    return rng.random((h, w, 4), dtype=np.float32)


def grey(h=H, w=W) -> np.ndarray:
    return rng.random((h, w, 1), dtype=np.float32)


def exact_away_from_ties(actual, expected, margin, tol=1e-4):
    away = np.abs(margin) > tol
    assert away.mean() > 0.9
    np.testing.assert_array_equal(actual[away], expected[away])


def test_every_op_has_a_shader_file_and_is_tested():
    from importlib import resources

    for op in OPERATIONS.values():
        package, name = op.shader.split(":")
        assert resources.files(package).joinpath(name).is_file(), op.shader
    tested = {
        "edges",
        "dilate",
        "erode",
        "roberts",
        "sobel",
        "blur",
        "downsample",
        "threshold",
        "invert",
        "mix",
    }
    tested |= {
        "contrast",
        "screen",
        "lambert",
        "toon",
        "normal_edges",
        "depth_edges",
        "id_edges",
        "composite",
        "shade",
    }
    tested.add("shade_layer")  # accumulates over a peel: tests/pipeline/test_executor.py
    assert set(OPERATIONS) == tested


def test_capabilities_the_pipeline_plans_by():
    """The pipeline plans by descriptor fields, never an op's name: a compute form only with a
    compute shader; an in-place form (``IN_PLACE``, its shaders present) for exactly the ops
    that may read their layers where a capture holds them; the edges op's triangle-ID
    silhouettes need face IDs, and no in-place form reads them."""
    from importlib import resources

    from blueprint.pipeline.layers import IN_PLACE

    for op in OPS.values():
        assert op.compute_form in (None, "slice", "array"), op.name
        assert op.compute_form is None or op.compute is not None, op.name
        assert (op.in_place is not None) == (op.name in IN_PLACE), op.name
    for forms in IN_PLACE.values():
        assert set(forms.compute) <= set(forms.fragment)
        for shader in (*forms.fragment.values(), *forms.compute.values()):
            package, name = shader.split(":")
            assert resources.files(package).joinpath(name).is_file(), shader
    edges = OPS["edges"]
    assert edges.depth_first and edges.compute_form == "slice" and OPS["dilate"].compute_form == "array"
    for ids in (False, True):
        values = edges.uniforms(id_silhouettes=ids)
        assert edges.face_ids(values) == ids and edges.in_place(values) == (not ids)
    # what a frame's contour lines take from the passes they are drawn beside: the dilation
    # widens lines (erosion and blur have radii too, and widen none), the edges give hidden ink
    dilate = OPS["dilate"]
    assert dilate.widens(dilate.uniforms(radius=2.5, hidden_width=0.4)) == (2.5, 0.4)
    assert edges.hidden_ink(edges.uniforms(hidden_ink=0.3)) == 0.3
    assert [op.name for op in OPERATIONS.values() if op.widens is not None] == ["dilate"]
    assert [op.name for op in OPERATIONS.values() if op.hidden_ink is not None] == ["edges"]


# -- edge detectors ------------------------------------------------------------------------------
@pytest.mark.parametrize("channels", [1, 3, 4])
def test_roberts_magnitude(ex, channels):
    a = rgba()
    m = np.arange(4) < channels
    g = np.linalg.norm((a - shift(a, 1, 1))[..., m], axis=-1) + np.linalg.norm(
        (shift(a, 1, 0) - shift(a, 0, 1))[..., m], axis=-1
    )
    out = ex.run_op("roberts", {"source": a}, {"channels": channels}, output="r32f")
    np.testing.assert_allclose(out[..., 0], g, atol=1e-5)


def test_roberts_threshold_inverted_is_binary(ex):
    a = rgba()
    g = np.linalg.norm((a - shift(a, 1, 1))[..., :3], axis=-1) + np.linalg.norm(
        (shift(a, 1, 0) - shift(a, 0, 1))[..., :3], axis=-1
    )
    out = ex.run_op("roberts", {"source": a}, {"threshold": 0.8, "invert": True})
    assert out.dtype == np.uint8 and out.shape == (H, W, 1)
    exact_away_from_ties(out[..., 0], np.where(g > 0.8, 0, 255).astype(np.uint8), g - 0.8)


def _sobel(a, channels):
    m = np.arange(4) < channels

    def f(dx, dy):
        return shift(a, dx, dy)[..., m]

    gx = (f(1, -1) + 2 * f(1, 0) + f(1, 1)) - (f(-1, -1) + 2 * f(-1, 0) + f(-1, 1))
    gy = (f(-1, 1) + 2 * f(0, 1) + f(1, 1)) - (f(-1, -1) + 2 * f(0, -1) + f(1, -1))
    return 0.25 * np.sqrt((gx**2).sum(-1) + (gy**2).sum(-1))


@pytest.mark.parametrize("channels", [1, 3])
def test_sobel_magnitude(ex, channels):
    a = rgba()
    out = ex.run_op("sobel", {"source": a}, {"channels": channels}, output="r32f")
    np.testing.assert_allclose(out[..., 0], _sobel(a, channels), atol=1e-5)


def test_sobel_unit_step_gives_one():
    a = np.zeros((6, 6, 4), np.float32)
    a[:, 3:, 0] = 1.0
    assert _sobel(a, 1)[2, 2] == pytest.approx(1.0) and _sobel(a, 1)[2, 3] == pytest.approx(1.0)


def test_sobel_threshold(ex):
    a = rgba()
    g = _sobel(a, 3)
    out = ex.run_op("sobel", {"source": a}, {"threshold": 0.5})
    exact_away_from_ties(out[..., 0], np.where(g > 0.5, 255, 0).astype(np.uint8), g - 0.5)


def test_id_edges_exact(ex):
    ids = rng.integers(0, 3, (H, W, 2), dtype=np.int32)
    ids[..., 1] = np.where(np.arange(W) < 6, 7, 9)[None, :]
    for channel in (0, 1):
        c = ids[..., channel]
        differs = np.zeros((H, W), bool)
        for dx, dy in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            differs |= shift(c, dx, dy) != c
        out = ex.run_op("id_edges", {"ids": ids}, {"channel": channel})
        np.testing.assert_array_equal(out[..., 0], np.where(differs, 255, 0))
    part = ex.run_op("id_edges", {"ids": ids}, {"channel": 1})[..., 0]
    assert set(np.nonzero(part.any(axis=0))[0]) == {5, 6}


def test_depth_edges(ex):
    y, x = np.mgrid[0:H, 0:W].astype(np.float32)
    depth = (0.3 + 0.01 * x + 0.02 * y)[..., None]  # a plane: no edges
    depth[:, 7:] += 0.2  # a jump: edges on both sides of it
    depth += rng.random(depth.shape, dtype=np.float32) * 1e-3
    d = depth[..., 0]
    sx = np.abs(shift(d, -1, 0) + shift(d, 1, 0) - 2 * d)
    sy = np.abs(shift(d, 0, -1) + shift(d, 0, 1) - 2 * d)
    sx[:, [0, -1]] = 0.0  # no difference across the frame
    sy[[0, -1], :] = 0.0
    second = np.maximum(sx, sy)
    out = ex.run_op("depth_edges", {"depth": depth}, {"threshold": 0.01})
    exact_away_from_ties(out[..., 0], np.where(second > 0.01, 255, 0).astype(np.uint8), second - 0.01)
    assert out[:, 6:8, 0].all() and not out[:, :5, 0].any()


def test_normal_edges(ex):
    n = rng.normal(size=(H, W, 3)).astype(np.float32)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    normal = np.concatenate([n, np.ones((H, W, 1), np.float32)], axis=-1)
    depth = np.full((H, W, 1), 0.5, np.float32)
    depth[:3, :3] = 1.0  # no surface there
    covered = depth[..., 0] < 1
    cos = math.cos(math.radians(60.0))
    edge = np.zeros((H, W), bool)
    margin = np.full((H, W), np.inf)
    for dx, dy in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        d = (n * shift(n, dx, dy)).sum(-1)
        both = covered & shift(covered, dx, dy)
        edge |= both & (d < cos)
        margin = np.where(both, np.minimum(margin, np.abs(d - cos)), margin)
    out = ex.run_op(
        "normal_edges", {"normal": normal, "depth": depth}, {"angle": 60.0}, formats={"depth": "depth"}
    )
    exact_away_from_ties(out[..., 0], np.where(edge, 255, 0).astype(np.uint8), margin)
    assert not out[:3, :3].any()


def test_edges_coverage_and_part_boundaries(ex, renderer):
    """The blueprint's edges operation on a flat, head-on G-buffer: lines exactly where coverage
    or the part ID changes (no creases, no depth jumps)."""
    depth = np.full((H, W, 1), 0.5, np.float32)
    depth[:, :2] = 1.0
    normal = np.zeros((H, W, 4), np.float32)
    normal[..., 2] = normal[..., 3] = 1.0
    ids = np.ones((H, W, 2), np.int32)
    ids[:, 8:, 1] = 2
    cov = depth[..., 0] < 1
    expected = np.zeros((H, W), bool)
    for dx, dy in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        expected |= shift(cov, dx, dy) != cov
        expected |= cov & (shift(ids[..., 1], dx, dy) != ids[..., 1])
    camera = fit_camera(examples.gearbox(), (W, H))
    out = ex.run_op(
        "edges", {"depth": depth, "normal": normal, "ids": ids}, formats={"depth": "depth"}, camera=camera
    )
    np.testing.assert_array_equal(out[..., 0], np.where(expected, 255, 0))


# -- morphology, filters ----------------------------------------------------------------------------
def _disc(x, radius, reduce):
    r = math.ceil(radius)
    acc = None
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            w = min(max(radius + 1 - math.hypot(dx, dy), 0.0), 1.0)
            v = reduce(w, shift(x, dx, dy))
            acc = v if acc is None else (np.maximum(acc, v) if reduce is _dil else np.minimum(acc, v))
    return acc


def _dil(w, x):
    return w * x


def _ero(w, x):
    return 1 - w * (1 - x)


@pytest.mark.parametrize("radius", [0.5, 1.0, 2.3])
def test_dilate_and_erode(ex, radius):
    x = grey()
    out = ex.run_op("dilate", {"source": x}, {"radius": radius}, output="r32f")
    np.testing.assert_allclose(out, _disc(x, radius, _dil), atol=1e-6)
    out = ex.run_op("erode", {"source": x}, {"radius": radius}, output="r32f")
    np.testing.assert_allclose(out, _disc(x, radius, _ero), atol=1e-6)


def test_dilate_r8_within_one_step(ex):
    x = (rng.random((H, W, 1)) > 0.8).astype(np.uint8) * 255
    out = ex.run_op("dilate", {"source": x}, {"radius": 1.5})
    ref = np.round(_disc(x / 255.0, 1.5, _dil) * 255)
    assert np.abs(out.astype(int) - ref).max() <= 1


@pytest.mark.parametrize("sigma", [0.5, 1.5])
def test_separable_blur(ex, sigma):
    a = rgba()
    u = BLUR.derive({"u_sigma": sigma})
    radius, weights = u["u_radius"], u["u_weights"]
    assert sum(weights[0:1]) + 2 * sum(weights[1 : radius + 1]) == pytest.approx(1.0)

    def along(x, axis):
        out = weights[0] * x
        for i in range(1, radius + 1):
            d = (i, 0) if axis == 0 else (0, i)
            out = out + weights[i] * (shift(x, *d) + shift(x, -d[0], -d[1]))
        return out

    ref = along(along(a, 0), 1)
    out = ex.run_op("blur", {"source": a}, {"sigma": sigma})
    assert out.shape == a.shape and out.dtype == np.float32
    np.testing.assert_allclose(out, ref, atol=1e-5)
    g = np.exp(-(np.arange(-radius, radius + 1) ** 2) / (2 * sigma**2))
    assert np.allclose(np.array(weights[: radius + 1]), (g / g.sum())[radius:])


@pytest.mark.parametrize("factor", [2, 3])
def test_downsample_box_and_gaussian(ex, factor):
    h, w = 4 * factor, 5 * factor
    a = rgba(h, w)
    box = a.reshape(h // factor, factor, w // factor, factor, 4).mean(axis=(1, 3))
    out = ex.run_op("downsample", {"source": a}, {"filter": "box"}, scale=1 / factor)
    assert out.shape == (h // factor, w // factor, 4)
    np.testing.assert_allclose(out, box, atol=1e-5)
    half = (factor + 1) // 2
    taps = np.arange(-half, factor + half)
    wts = np.exp(-((taps - (factor - 1) / 2) ** 2) * 2.0 / factor**2)
    ref = np.zeros_like(box)
    for oy in range(h // factor):
        for ox in range(w // factor):
            ys = np.clip(oy * factor + taps, 0, h - 1)
            xs = np.clip(ox * factor + taps, 0, w - 1)
            block = a[ys][:, xs]
            ww = wts[:, None] * wts[None, :]
            ref[oy, ox] = (block * ww[..., None]).sum(axis=(0, 1)) / ww.sum()
    out = ex.run_op("downsample", {"source": a}, {"filter": "gaussian"}, scale=1 / factor)
    np.testing.assert_allclose(out, ref, atol=1e-5)


def test_threshold_exact(ex):
    a = rgba()
    out = ex.run_op("threshold", {"source": a}, {"level": 0.4})
    ref = np.concatenate([(a[..., :3] >= 0.4).astype(np.float32), a[..., 3:]], axis=-1)
    np.testing.assert_array_equal(out, ref)
    out = ex.run_op("threshold", {"source": a}, {"level": 0.4, "invert": True})
    np.testing.assert_array_equal(out[..., :3], 1 - ref[..., :3])


def test_invert_and_contrast(ex):
    a = rgba()
    np.testing.assert_allclose(
        ex.run_op("invert", {"source": a}), np.dstack([1 - a[..., :3], a[..., 3]]), atol=1e-6
    )
    out = ex.run_op("contrast", {"source": a}, {"contrast": 2.0, "brightness": 0.1})
    np.testing.assert_allclose(out[..., :3], (a[..., :3] - 0.5) * 2 + 0.6, atol=1e-6)
    np.testing.assert_array_equal(out[..., 3], a[..., 3])
    u8 = (a * 255).astype(np.uint8)
    out = ex.run_op("contrast", {"source": u8}, {"contrast": 2.0})
    ref = np.clip(np.round(((u8[..., :3] / 255.0 - 0.5) * 2 + 0.5) * 255), 0, 255)
    assert np.abs(out[..., :3].astype(int) - ref).max() <= 1


@pytest.mark.parametrize("mode", ["mix", "multiply", "add", "subtract", "min", "max", "screen"])
def test_mix_modes(ex, mode):
    a, b = rgba(), rgba()
    r = {
        "mix": b,
        "multiply": a * b,
        "add": a + b,
        "subtract": a - b,
        "min": np.minimum(a, b),
        "max": np.maximum(a, b),
        "screen": 1 - (1 - a) * (1 - b),
    }[mode]
    out = ex.run_op("mix", {"a": a, "b": b}, {"mode": mode, "factor": 0.7})
    np.testing.assert_allclose(out, a * 0.3 + r * 0.7, atol=1e-6)


def test_mix_broadcasts_one_channel(ex):
    a, b = rgba(), grey()
    out = ex.run_op("mix", {"a": a, "b": b}, {"mode": "multiply", "factor": 1.0})
    np.testing.assert_allclose(out, a * np.dstack([b, b, b, np.ones_like(b)]), atol=1e-6)


def test_screen_halftone(ex):
    a = rgba(24, 32)
    lum = a[..., :3] @ np.array([0.299, 0.587, 0.114])
    y, x = np.mgrid[0:24, 0:32] + 0.5
    t = math.radians(30.0)
    u, v = math.cos(t) * x + math.sin(t) * y, -math.sin(t) * x + math.cos(t) * y
    k = 2 * math.pi / 5.0
    screen = 0.5 + 0.25 * (np.cos(k * u) + np.cos(k * v))
    out = ex.run_op("screen", {"source": a}, {"period": 5.0, "angle": 30.0})
    exact_away_from_ties(out[..., 0], np.where(lum > screen, 255, 0).astype(np.uint8), lum - screen)
    one = ex.run_op("screen", {"source": a[..., :1].copy()}, {"period": 5.0, "angle": 30.0})
    exact_away_from_ties(
        one[..., 0], np.where(a[..., 0] > screen, 255, 0).astype(np.uint8), a[..., 0] - screen
    )


# -- shading ---------------------------------------------------------------------------------------
def _shading_inputs():
    n = rng.normal(size=(H, W, 3)).astype(np.float32)
    n[..., 2] = np.abs(n[..., 2])
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    normal = np.dstack([n, np.ones((H, W), np.float32)])
    depth = np.full((H, W, 1), 0.5, np.float32)
    depth[:2] = 1.0
    color = rgba()
    return n, normal, depth, color


def _light(az, el):
    az, el = math.radians(az), math.radians(el)
    return np.array([math.cos(el) * math.sin(az), math.sin(el), math.cos(el) * math.cos(az)])


def test_lambert(ex):
    n, normal, depth, color = _shading_inputs()
    d = np.maximum(n @ _light(20.0, 30.0), 0)
    ref = np.dstack([color[..., :3] * (0.25 + 0.75 * d)[..., None], np.ones((H, W))])
    ref[:2] = 0.0
    out = ex.run_op(
        "lambert",
        {"normal": normal, "depth": depth, "color": color},
        {"azimuth": 20.0, "elevation": 30.0, "ambient": 0.25},
        formats={"depth": "depth"},
        output="rgba32f",
    )
    np.testing.assert_allclose(out, ref, atol=1e-5)
    out = ex.run_op(
        "lambert",
        {"normal": normal, "depth": depth, "color": color},
        {"background": 0.5},
        formats={"depth": "depth"},
    )
    # 0.5 lies halfway between two 8-bit steps: drivers round the tie either way (llvmpipe up,
    # the H200's compute form down)
    assert np.isin(out[:2, :, :3], (127, 128)).all() and (out[:2, :, 3] == 255).all()


@pytest.mark.parametrize("style", ["blueprint", "paper"])
def test_shade_in_the_styles_colour(ex, style):
    """Headlight Lambert in the style's shade colour (0.35 ambient), premultiplied by the
    opacity; nothing where there is no surface."""
    n, normal, depth, _ = _shading_inputs()
    shade = np.array(STYLES[style].shade[:3])
    light = 0.35 + 0.65 * np.clip(n[..., 2], 0.0, 1.0)
    ref = np.dstack([shade * light[..., None] * 0.6, np.full((H, W), 0.6)])
    ref[:2] = 0.0
    out = ex.run_op(
        "shade",
        {"depth": depth, "normal": normal},
        {"opacity": 0.6},
        formats={"depth": "depth"},
        output="rgba32f",
        style=style,
    )
    np.testing.assert_allclose(out, ref, atol=1e-5)


def test_toon(ex):
    n, normal, depth, color = _shading_inputs()
    d = np.maximum(n @ _light(-30.0, 40.0), 0)
    q = np.minimum(np.floor(d * 4), 3) / 3
    ref = np.dstack([color[..., :3] * (0.2 + 0.8 * q)[..., None], np.ones((H, W))])
    ref[:2] = 0.0
    out = ex.run_op(
        "toon",
        {"normal": normal, "depth": depth, "color": color},
        {"bands": 4},
        formats={"depth": "depth"},
        output="rgba32f",
    )
    margin = np.abs(d * 4 - np.round(d * 4))
    margin[:2] = 1.0
    away = margin > 1e-4
    np.testing.assert_allclose(out[away], ref[away], atol=1e-5)


# -- composite -------------------------------------------------------------------------------------
@pytest.mark.parametrize("style", ["blueprint", "transparent", "wireframe"])
@pytest.mark.parametrize("count", [3, 10])
def test_composite_matches_depth_sprite_reference(ex, style, count):
    s = STYLES[style]
    layers = [
        (rng.random((8, 12, 1)) * 255 * (rng.random((8, 12, 1)) > 0.5)).astype(np.uint8) for _ in range(count)
    ]
    out = ex.run_op("composite", {"layers": layers}, {"style": style}, scale=0.5)
    assert out.shape == (4, 6, 4)
    inks = s.layer_inks(count)
    paper = np.array(s.paper if s.paper else (0, 0, 0, 0), np.float64)
    below = np.broadcast_to(np.r_[paper[:3] * paper[3], paper[3]], (4, 6, 4)).copy()

    def group(first: int, last: int) -> np.ndarray:
        # at each sample the strongest line of the group wins: the front line's own coverage
        # in its ink, what the lines behind add up to the maximum in theirs
        lines = np.zeros((8, 12, 4))
        for k in range(last - 1, first - 1, -1):
            e = layers[k][..., 0] / 255.0
            e = (e >= 0.5).astype(float) if s.threshold else e
            a = np.clip(e, 0, 1) * inks[k, 3]
            total = np.maximum(lines[..., 3], a)
            share = np.divide(total - a, lines[..., 3], out=np.zeros_like(a), where=lines[..., 3] > 0)
            lines = np.dstack([inks[k, :3] * a[..., None] + lines[..., :3] * share[..., None], total])
        return lines.reshape(4, 2, 6, 2, 4).mean(axis=(1, 3))

    # groups of eight layers are laid over each other, the back-most first
    for first in range(((count - 1) // 8) * 8, -1, -8):
        lines = group(first, min(first + 8, count))
        below = lines + below * (1 - lines[..., 3:])
    assert np.abs(out.astype(int) - np.round(below * 255)).max() <= 1
