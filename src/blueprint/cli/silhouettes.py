"""``blueprint silhouettes MODEL``: GPU (or CPU) silhouettes of a still model or of a deforming one,
a thin shell over ``blueprint.api.files.render_silhouettes_file``; ``main`` runs the command on
its own with the CLI's error handling (one line, exit code 2).
"""

from __future__ import annotations

from pathlib import Path

import click

from blueprint.cli.options import camera_options, progress_bar
from blueprint.cli.shell import run
from blueprint.errors import printable
from blueprint.gpu_silhouettes import DEFAULT_LAYERS, DEFAULT_METHOD, STILL_METHODS
from blueprint.silhouette.deform import KINDS

DEFAULT_SIZE = (800, 600)


@click.command("silhouettes")
@click.argument("model", type=click.Path(path_type=Path))
@click.option(
    "-o",
    "--output",
    type=click.Path(path_type=Path),
    required=True,
    help="PNG to write, or MP4 with --animate.",
)
@camera_options
@click.option(
    "--method",
    type=click.Choice(STILL_METHODS),
    default=DEFAULT_METHOD,
    show_default=True,
    help="gpu-edges: the object-space silhouette edges classified and drawn anti-aliased on the GPU; "
    "gpu-vertex: triangle IDs + vertex storage (no preprocessing); gpu-idlist: triangle IDs + "
    "precomputed adjacency lists; cpu: object-space edges (weld, connect, orient, classify), "
    "hidden ones included.",
)
@click.option(
    "--layers",
    type=int,
    default=DEFAULT_LAYERS,
    show_default=True,
    help="Depth layers (GPU methods): 1 draws what is visible, more add hidden silhouettes, fainter; "
    "with gpu-edges the last layer holds every silhouette behind the one before.",
)
@click.option("--animate", type=click.Choice(KINDS), default=None, help="Deform the model every frame.")
@click.option("--frames", type=int, default=60, show_default=True, help="Frames of the animation.")
@click.option("--fps", type=float, default=30.0, show_default=True, help="Frames per second of the video.")
@click.option(
    "--split-at",
    type=float,
    default=0.5,
    show_default=True,
    help="Fraction of the animation after which the model splits into two pieces (1: never).",
)
def silhouettes(
    model,
    output,
    size,
    view,
    azimuth,
    elevation,
    fov,
    ortho,
    up,
    include,
    exclude,
    method,
    layers,
    animate,
    frames,
    fps,
    split_at,
):
    """Draw MODEL's silhouettes into a PNG, or, with --animate, the
    silhouettes of MODEL deforming (and splitting in two part-way) into an MP4."""
    from blueprint.api import default_renderer
    from blueprint.api.silhouettes import render_silhouettes_file

    options = dict(
        method=method,
        layers=layers,
        size=tuple(size) if size else DEFAULT_SIZE,
        view=view,
        azimuth=azimuth,
        elevation=elevation,
        fov=fov,
        ortho=ortho,
        up=up,
        include=include,
        exclude=exclude,
        animate=animate,
        frames=frames,
        fps=fps,
        split_at=split_at,
    )
    if animate is None:
        done = render_silhouettes_file(model, output, **options)
        shown, timing = f"{done['width']}x{done['height']}", f"{done['ms']:.1f} ms"
        if done["chunks"]:
            # a mesh that did not fit the GPU beside the frame: drawn, slower, a chunk at a time
            shown += f", drawn in {done['chunks']} chunks"
    else:
        with progress_bar(f"{animate} {method}") as progress:
            done = render_silhouettes_file(model, output, progress=progress, **options)
        shown = f"{done['frames']} frames of {done['width']}x{done['height']}"
        timing = f"{done['ms']:.1f} ms per frame (median)"
    click.echo(
        printable(
            f"{output}: {shown}, {done['triangles']} triangles, {method}, {timing} "
            f"on {default_renderer().info['renderer']}"
        )
    )


def main(argv: list[str] | None = None) -> None:
    """``blueprint silhouettes`` as a program of its own."""
    run(silhouettes, argv, "blueprint silhouettes")
