"""``blueprint view MODEL``: the click command over ``blueprint.viewer`` and a stand-alone entry
point, ``main``, with the CLI's error handling."""

from __future__ import annotations

import json
from pathlib import Path

import click

from blueprint.cli.options import STYLE_NAMES, camera_options
from blueprint.cli.shell import run
from blueprint.errors import InputError
from blueprint.scene.camera import VIEWS

DEFAULT_SIZE = (800, 600)


@click.command("view")
@click.argument("model", type=click.Path(path_type=Path))
@camera_options
@click.option("--style", default="blueprint", show_default=True, help=f"One of {', '.join(STYLE_NAMES)}.")
@click.option("--grid", type=float, default=None, help="Grid spacing in pixels (0: none).")
@click.option(
    "--max-layers",
    type=int,
    default=5,
    show_default=True,
    help="Depth layers to peel at most (0: all); D / Shift+D change it.",
)
@click.option(
    "--min-fraction",
    type=float,
    default=0.0,
    show_default=True,
    help="Stop when a layer covers less than this fraction of the first.",
)
@click.option("--crease-angle", type=float, default=30.0, show_default=True, help="Degrees.")
@click.option("--line-width", type=float, default=1.0, show_default=True, help="Pixels.")
@click.option(
    "--supersample",
    type=int,
    default=2,
    show_default=True,
    help="Anti-aliasing factor (1-4) of still frames; frames drawn while the view moves use 1.",
)
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
def view(
    model,
    size,
    view,
    azimuth,
    elevation,
    fov,
    ortho,
    up,
    include,
    exclude,
    style,
    grid,
    max_layers,
    min_fraction,
    crease_angle,
    line_width,
    supersample,
    interactive_scale,
    frames,
):
    """Open MODEL in a window: orbit, pan and zoom with the mouse, click a part to highlight it.

    Keys: D / Shift+D one layer more / fewer, A all layers, S next style, 1-7 named views
    (iso front back left right top bottom), O orthographic / perspective, M depth mask on the
    picked part, P screenshot beside the model, T turntable, H help, Esc quit.
    """
    from blueprint.viewer.app import run_viewer
    from blueprint.viewer.loop import Options

    if view not in VIEWS:
        raise InputError(f"unknown view {view!r} (choose {', '.join(VIEWS)})")
    if frames < 0:
        raise InputError(f"frames must be >= 0, got {frames}")
    result = run_viewer(
        model,
        size=tuple(size) if size else DEFAULT_SIZE,
        view=view,
        azimuth=azimuth,
        elevation=elevation,
        fov=fov,
        ortho=ortho,
        up=up,
        include=include,
        exclude=exclude,
        style=style,
        styles=STYLE_NAMES,
        max_layers=max_layers or None,
        options=Options(
            grid=grid,
            min_fraction=min_fraction,
            crease_angle=crease_angle,
            line_width=line_width,
            supersample=supersample,
            interactive_scale=interactive_scale,
        ),
        frames=frames,
    )
    if result is not None:
        click.echo(json.dumps(result))


def main(argv: list[str] | None = None) -> None:
    """``blueprint view`` as a program of its own (the tests start it so)."""
    run(view, argv, "blueprint view")
