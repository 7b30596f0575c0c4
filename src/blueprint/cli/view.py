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

DEFAULT_SIZE = (800, 600)


@click.command("view")
@click.argument("model", type=click.Path(path_type=Path))
@drawing_options(
    *CAMERA_OPTIONS, "style", "grid", "max_layers", "min_fraction", "crease_angle", "line_width",
    "supersample", size=DEFAULT_SIZE, max_layers=5, helps={"style": f"One of {', '.join(STYLE_NAMES)}."},
)  # fmt: skip
@click.option(
    "--interactive-scale",
    type=float,
    default=0.0,
    show_default=True,
    help="Resolution of frames drawn while the view moves, as a fraction of the window "
    "(0: automatic, lowered down to 0.5 while slower than 30 fps).",
)
@click.option(
    "--frames",
    type=int,
    default=0,
    show_default=True,
    help="Measure: spin the turntable for N frames, print the frame rate as JSON and exit.",
)
def view(model, interactive_scale, frames, **values):
    """Open MODEL in a window: orbit, pan and zoom with the mouse, click a part to highlight it.

    Keys: D / Shift+D one layer more / fewer (from --max-layers), A all layers, S next style,
    1-7 named views (iso front back left right top bottom), O orthographic / perspective, M depth
    mask on the picked part, P screenshot beside the model, T turntable, H help, Esc quit.
    Still frames are drawn at --supersample, frames drawn while the view moves at 1.
    """
    from blueprint.api.options import DrawOptions
    from blueprint.viewer.app import run_viewer

    options = DrawOptions(**drawing_values(values))
    if options.view not in VIEWS:
        raise InputError(f"unknown view {options.view!r} (choose {', '.join(VIEWS)})")
    if frames < 0:
        raise InputError(f"frames must be >= 0, got {frames}")
    result = run_viewer(
        model, options, styles=STYLE_NAMES, interactive_scale=interactive_scale, frames=frames
    )
    if result is not None:
        click.echo(json.dumps(result))


def main(argv: list[str] | None = None) -> None:
    """``blueprint view`` as a program of its own (the tests start it so)."""
    run(view, argv, "blueprint view")
