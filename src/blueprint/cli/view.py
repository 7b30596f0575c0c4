"""``blueprint view MODEL``: the click command over ``blueprint.viewer`` and a stand-alone entry
point, ``main``, with the CLI's error handling."""

from __future__ import annotations

import json
from pathlib import Path

import click

from blueprint.cli.options import CAMERA_OPTIONS, STYLE_NAMES, drawing_options, drawing_values
from blueprint.cli.shell import run
from blueprint.errors import InputError
from blueprint.scene.camera import VIEWS
from blueprint.viewer.pacing import MOVING_FPS

DEFAULT_SIZE = (800, 600)


@click.command("view")
@click.argument("model", type=click.Path(path_type=Path))
@drawing_options(
    *CAMERA_OPTIONS, "style", "grid", "max_layers", "min_fraction", "crease_angle", "line_width",
    "supersample", "smooth_contours", size=DEFAULT_SIZE, max_layers=5,
    helps={
        "style": f"One of {', '.join(STYLE_NAMES)}.",
        "smooth_contours": "The drawing shown once the view rests: outline smooth surfaces by the "
        "contour of their interpolated normals (a pass over the mesh each time the view rests; "
        "off by default).",
    },
)  # fmt: skip
@click.option(
    "--moving-fps",
    type=float,
    default=MOVING_FPS,
    show_default=True,
    help="Frame rate kept while the view moves: each frame the richest of full quality, "
    "supersample 1, fewer layers, a smaller drawing, a coarse mesh that keeps it.",
)
@click.option(
    "--interactive-scale",
    type=float,
    default=0.0,
    show_default=True,
    help="Frames drawn while the view moves at this fraction of the window, supersample 1 and "
    "--max-layers, whatever they cost (0: as --moving-fps asks).",
)
@click.option(
    "--frames",
    type=int,
    default=0,
    show_default=True,
    help="Measure: spin the turntable for N frames, then draw N still frames, print both frame "
    "rates as JSON and exit.",
)
def view(model, moving_fps, interactive_scale, frames, **values):
    """Open MODEL in a window: orbit, pan and zoom with the mouse, click a part to highlight it.

    Keys: D / Shift+D one layer more / fewer (from --max-layers), A all layers, S next style,
    1-7 named views (iso front back left right top bottom), O orthographic / perspective, M depth
    mask on the picked part, P screenshot beside the model, T turntable, H help, Esc quit.
    While the view moves, frames are drawn as well as --moving-fps allows; once it rests, the
    full drawing at --supersample follows.
    """
    from blueprint.api.options import DrawOptions
    from blueprint.viewer.app import run_viewer

    options = DrawOptions(**drawing_values(values))
    if options.view not in VIEWS:
        raise InputError(f"unknown view {options.view!r} (choose {', '.join(VIEWS)})")
    if frames < 0:
        raise InputError(f"frames must be >= 0, got {frames}")
    result = run_viewer(
        model,
        options,
        styles=STYLE_NAMES,
        interactive_scale=interactive_scale,
        moving_fps=moving_fps,
        frames=frames,
    )
    if result is not None:
        click.echo(json.dumps(result))


def main(argv: list[str] | None = None) -> None:
    """``blueprint view`` as a program of its own (the tests start it so)."""
    run(view, argv, "blueprint view")
