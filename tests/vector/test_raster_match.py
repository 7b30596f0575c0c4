"""The vector drawing and the raster blueprint of the same view lie on each other, level by level.

How the comparison is made, and why it is fair:

* Raster levels. The blueprint composes the edge maps of the peeled layers front over back, so
  what it shows at a pixel is the edge of the *frontmost* layer that has one there. Rendering
  with ``max_layers = k + 1`` draws layers 0..k only; a pixel inked in that image but not with
  ``max_layers = k`` has raster level k. Inks are made binary and opaque (a threshold style), so
  levels are read off exactly, not guessed from colours.
* Vector levels. The SVG file is read back (our own path reader) and every polyline of level k
  is sampled every quarter pixel.
* Where levels cannot be told apart. A raster edge marks the pixels on both sides of a
  discontinuity, and the same outline shows up again in the next layer one pixel further in;
  so within 1.5 px of an edge of lower level the composite cannot say whether a deeper edge is
  there. Raster pixels of level k within 1.5 px of raster pixels of a lower level, and vector
  points of level k within 1.5 px of vector lines of a lower level, are left out of the count
  (and the counts say how many were judged).
* Then, per level: at least 95 % of the judged raster edge pixels lie within 1.5 px of a vector
  line of that level, and at least 95 % of the judged vector line length lies within 1.5 px of a
  raster edge pixel of that level.
"""

import numpy as np
import pytest
from scipy.spatial import cKDTree
from vector_helpers import svg_lines

from blueprint.compose.style import Style
from blueprint.examples import gearbox
from blueprint.scene.camera import fit_camera
from blueprint.scene.loader import load_model
from blueprint.vector import draw_vector, save_drawing

SIZE = (256, 256)
REACH = 1.5
LEVELS = 3
MIN_JUDGED = 60
LEVEL_STYLE = Style(
    "levels",
    paper=None,
    ink=(1.0, 1.0, 1.0, 1.0),
    hidden_ink=(1.0, 1.0, 1.0, 1.0),
    hidden_opacity=1.0,
    fade=1.0,
    threshold=True,
)


def raster_levels(renderer, model, camera, levels=LEVELS):
    """(H, W) int: the raster blueprint's level at each edge pixel, -1 elsewhere."""
    level = np.full(SIZE[::-1], -1)
    for k in reversed(range(levels)):
        frame = renderer.render(model, camera, size=SIZE, style=LEVEL_STYLE, max_layers=k + 1)
        level[frame.image[..., 3] >= 96] = k
    return level


def vector_points(svg_path, step=0.25):
    """{level: (N, 2) points every `step` pixels along the SVG's polylines}."""
    found = {}
    for (_, level), polylines in svg_lines(svg_path).items():
        for line in polylines:
            for a, b in zip(line[:-1], line[1:], strict=True):
                n = max(int(np.ceil(np.linalg.norm(b - a) / step)), 1)
                t = np.linspace(0.0, 1.0, n + 1)[:, None]
                found.setdefault(level, []).append(a + t * (b - a))
    return {k: np.concatenate(v) for k, v in found.items()}


def _near(points, others):
    if len(others) == 0 or len(points) == 0:
        return np.zeros(len(points), bool)
    return cKDTree(others).query(points, distance_upper_bound=REACH + 1e-9)[0] <= REACH


def compare(renderer, model, tmp_path):
    camera = fit_camera(model, SIZE, "iso")
    drawing = draw_vector(model, camera, SIZE, renderer=renderer, style="paper")
    svg = save_drawing(tmp_path / "drawing.svg", drawing)
    raster = raster_levels(renderer, model, camera)
    vector = vector_points(svg)
    rows, cols = np.nonzero(raster >= 0)
    centres = np.stack([cols + 0.5, rows + 0.5], axis=1)
    raster_level = raster[rows, cols]
    result = {}
    for k in range(LEVELS):
        mine_r = centres[raster_level == k]
        lower_r = centres[raster_level < k]
        judged_r = mine_r[~_near(mine_r, lower_r)] if k else mine_r
        mine_v = vector.get(k, np.zeros((0, 2)))
        lower_v = np.concatenate([vector.get(j, np.zeros((0, 2))) for j in range(k)] + [np.zeros((0, 2))])
        judged_v = mine_v[~_near(mine_v, lower_v)] if k else mine_v
        recall = _near(judged_r, mine_v).mean() if len(judged_r) else 1.0
        precision = _near(judged_v, mine_r).mean() if len(judged_v) else 1.0
        # vector points are a quarter pixel apart: count them as pixels of length
        result[k] = (len(judged_r), int(len(judged_v) * 0.25), recall, precision)
    return result


def check(result):
    for k, (raster_n, vector_n, recall, precision) in result.items():
        if k <= 1:
            assert raster_n >= MIN_JUDGED and vector_n >= MIN_JUDGED, result
        if raster_n >= MIN_JUDGED:
            assert recall >= 0.95, (
                f"level {k}: {recall:.3f} of raster edge pixels near a vector line ({result})"
            )
        if vector_n >= MIN_JUDGED:
            assert precision >= 0.95, (
                f"level {k}: {precision:.3f} of vector lines near raster edges ({result})"
            )


@pytest.mark.parametrize(
    "name",
    [
        "trimesh/featuretype.STL",
        "common-3d-test-models/stanford-bunny.obj",
        "glTF-Sample-Models/2CylinderEngine.glb",
    ],
    ids=["featuretype", "bunny", "engine"],
)
def test_shared_models_vector_and_raster_overlay_per_level(renderer, shared_models, tmp_path, name):
    check(compare(renderer, load_model(shared_models / name), tmp_path))


def test_svg_rendered_by_cairosvg_overlays_the_raster(renderer, tmp_path):
    """A real SVG renderer draws our file (solid lines at every level, no paper); its inked
    pixels and the raster blueprint's edge pixels lie within 1.5 px of each other."""
    try:
        import cairosvg
    except (ImportError, OSError) as exc:  # the package, or the system's libcairo, is missing
        pytest.skip(f"cairosvg cannot run here: {exc}")
    from PIL import Image

    from blueprint.vector import vector_style

    model = gearbox()
    camera = fit_camera(model, SIZE, "iso")
    style = vector_style("transparent", dashes=False)
    drawing = draw_vector(model, camera, SIZE, renderer=renderer, style=style)
    svg = save_drawing(tmp_path / "solid.svg", drawing)
    png = tmp_path / "solid.png"
    cairosvg.svg2png(url=str(svg), write_to=str(png), output_width=SIZE[0], output_height=SIZE[1])
    drawn = np.asarray(Image.open(png).convert("RGBA"))[..., 3] >= 64
    raster = raster_levels(renderer, model, camera, levels=8) >= 0
    vec = np.stack(np.nonzero(drawn)[::-1], axis=1) + 0.5
    ras = np.stack(np.nonzero(raster)[::-1], axis=1) + 0.5
    assert len(vec) > 1000 and len(ras) > 1000
    assert _near(ras, vec).mean() >= 0.95
    assert _near(vec, ras).mean() >= 0.95
