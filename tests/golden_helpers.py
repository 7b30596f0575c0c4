"""The golden frames: their cases, models and tolerances, shared by tests/test_golden.py (which
renders and regenerates them) and the tests that check other paths against them.

Goldens are made on the pinned software rasterizer (Mesa llvmpipe) and compared only there:
the mean absolute difference of every channel below ``MEAN_TOLERANCE`` (0-255 scale) and fewer
than ``PIXEL_FRACTION`` of the pixels differing by more than ``PIXEL_TOLERANCE`` in any channel.
Colour is compared premultiplied by alpha, so the colour of invisible pixels does not count.
Beside the PNGs, ``frames.json`` pins each case's layer count and the samples of its layers.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from blueprint import examples
from blueprint.compose.lookup import get_style

GOLDEN = Path(__file__).parent / "golden"
FRAMES = GOLDEN / "frames.json"
MARKS = Path(__file__).resolve().parents[1] / "examples" / "marks.toml"
SIZE = (256, 192)
PINNED = "llvmpipe"
# hidden lines half as wide as visible ones change a picture by little on average: an option
# that only adds or drops hidden lines (id silhouettes, depth masking) must still show
MEAN_TOLERANCE = 0.25
PIXEL_TOLERANCE = 32
PIXEL_FRACTION = 0.005


def sleeve():
    """An octagonal pin through a sleeve, a collar on the pin (its bore touching the pin's
    ridges) inside the sleeve and a key on top: surfaces nest ten deep, more than the eight
    layers peeled by default."""
    return examples.assemble(
        {
            "sleeve": examples.tube(9, 12, 40, 40, axis=0),
            "pin": examples.prism([5.0], 56, 8, axis=0),
            "collar": examples.tube(5, 8, 6, 40, axis=0, center=(14, 0, 0)),
            "key": examples.box((-4, 5, -1.5), (4, 8, 1.5)),
        }
    )


MODELS = {"gearbox": examples.gearbox, "sleeve": sleeve}

# render_frame options per golden; "model" names one of MODELS (default: the gearbox)
CASES = {
    "blueprint": dict(style="blueprint"),
    "paper": dict(style="paper"),
    "transparent": dict(style="transparent"),
    "wireframe": dict(style="wireframe"),
    "blueprint_grid16": dict(style=get_style("blueprint", 16)),
    "blueprint_line2": dict(style="blueprint", line_width=2.0),
    "blueprint_ss1_all_layers": dict(style="blueprint", supersample=1, max_layers=None),
    # on the gearbox these three change few pixels (mean 0.3, within the tolerance), so the
    # sleeve's octagonal pin, whose 45 degree creases a 50 degree angle smooths away, has them too
    "blueprint_crease50": dict(style="blueprint", crease_angle=50.0, depth_threshold=8.0, part_edges=False),
    "blueprint_layers10_line2_5": dict(style="blueprint", max_layers=10, line_width=2.5),
    "blueprint_highlight": dict(style="blueprint", highlight="gear*"),
    "paper_highlight": dict(style="paper", highlight="gear*"),
    "paper_reveal90": dict(style="paper", highlight="gear*", reveal=0.9),
    "paper_reveal50": dict(style="paper", highlight="gear*", reveal=0.5),
    "paper_shade": dict(style="paper", shade="shaft"),
    "paper_shade50": dict(style="paper", shade="shaft", shade_opacity=0.5),
    "paper_shade_highlight": dict(style="paper", shade="shaft", highlight="gear*"),
    "paper_id_silhouettes": dict(style="paper", id_silhouettes=True),
    "blueprint_glyphs": dict(style="blueprint", glyphs=MARKS),
    "blueprint_glyphs_highlight": dict(style="blueprint", glyphs=MARKS, highlight="gear*"),
    "paper_plan": dict(style="paper", view="plan"),
    "sleeve_paper_all_layers": dict(model="sleeve", style="paper", max_layers=None),
    "sleeve_crease50_all_layers": dict(
        model="sleeve",
        style="paper",
        max_layers=None,
        crease_angle=50.0,
        depth_threshold=8.0,
        part_edges=False,
    ),
    "sleeve_reveal100": dict(model="sleeve", style="blueprint", highlight="pin", reveal=1.0, max_layers=None),
    "sleeve_shade50_highlight": dict(
        model="sleeve", style="paper", shade="pin", shade_opacity=0.5, highlight="key"
    ),
}


def case(name: str) -> tuple[str, dict]:
    """(model name, render_frame options) of a golden."""
    options = dict(CASES[name])
    return options.pop("model", "gearbox"), options


def skip_unless_pinned(renderer) -> None:
    if not renderer.info["renderer"].startswith(PINNED):
        pytest.skip(f"goldens are made on {PINNED}, this is {renderer.info['renderer']}")


def golden_path(name: str) -> Path:
    return GOLDEN / f"{name}.png"


def golden_image(name: str) -> np.ndarray:
    path = golden_path(name)
    if not path.exists():
        pytest.fail(f"no golden image {path}: run pytest tests/test_golden.py --regen-goldens and look at it")
    with Image.open(path) as picture:
        return np.asarray(picture.convert("RGBA"))


def frame_record(frame) -> dict:
    """What frames.json pins of a frame. Only the drawn layers' samples: the passes that find
    where peeling ends depend on how layers are batched into passes, not on the drawing."""
    return {"layers": frame.layers, "layer_pixels": [int(n) for n in frame.layer_pixels[: frame.layers]]}


def pinned_frames() -> dict[str, dict]:
    if not FRAMES.exists():
        pytest.fail(f"no {FRAMES}: run pytest tests/test_golden.py --regen-goldens")
    return json.loads(FRAMES.read_text(encoding="utf-8"))


def write_pinned_frames(records: dict[str, dict]) -> None:
    # one case a line, so a diff shows which cases moved
    lines = [f"  {json.dumps(name)}: {json.dumps(record)}" for name, record in records.items()]
    FRAMES.write_text("{\n" + ",\n".join(lines) + "\n}\n", encoding="utf-8")


def assert_frame_pinned(name: str, frame) -> None:
    pinned = pinned_frames()
    assert name in pinned, f"{name} is not in {FRAMES}: run pytest tests/test_golden.py --regen-goldens"
    assert frame_record(frame) == pinned[name], f"{name}: layers of the frame moved"


def _comparable(image: np.ndarray) -> np.ndarray:
    f = image.astype(np.float64)
    f[..., :3] *= f[..., 3:4] / 255.0
    return f


def compare(actual: np.ndarray, expected: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
    """(mean absolute difference per channel, fraction of differing pixels, |difference|)."""
    diff = np.abs(_comparable(actual) - _comparable(expected))
    return diff.mean(axis=(0, 1)), float((diff.max(axis=-1) > PIXEL_TOLERANCE).mean()), diff


def within_tolerance(actual: np.ndarray, expected: np.ndarray) -> bool:
    mean, fraction, _ = compare(actual, expected)
    return mean.max() < MEAN_TOLERANCE and fraction < PIXEL_FRACTION


def _save_failure(folder: Path, name: str, actual: np.ndarray, expected: np.ndarray, diff) -> list[Path]:
    paths = [folder / f"{name}.actual.png", folder / f"{name}.golden.png", folder / f"{name}.diff.png"]
    Image.fromarray(actual).save(paths[0])
    Image.fromarray(expected).save(paths[1])
    amplified = np.clip(diff.max(axis=-1) * 4, 0, 255).astype(np.uint8)
    visible = np.stack([amplified, amplified // 4, amplified // 4, np.full_like(amplified, 255)], axis=-1)
    Image.fromarray(visible).save(paths[2])
    return paths


def assert_like_golden(name: str, actual: np.ndarray, artifacts: Path, label: str | None = None) -> None:
    """Fail, leaving the actual image, the golden and their difference in ``artifacts`` under
    ``label`` (default ``name``), unless ``actual`` matches the golden ``name`` within tolerance."""
    expected = golden_image(name)
    assert expected.shape == actual.shape, f"golden is {expected.shape}, rendered {actual.shape}"
    mean, fraction, diff = compare(actual, expected)
    if mean.max() >= MEAN_TOLERANCE or fraction >= PIXEL_FRACTION:
        saved = _save_failure(artifacts, label or name, actual, expected, diff)
        pytest.fail(
            f"{label or name}: mean abs difference per channel {np.round(mean, 3).tolist()} (limit "
            f"{MEAN_TOLERANCE}), {fraction:.3%} pixels differ by > {PIXEL_TOLERANCE} (limit "
            f"{PIXEL_FRACTION:.1%}) from golden {name}; see {', '.join(str(p) for p in saved)}"
        )
