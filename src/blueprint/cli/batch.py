"""``blueprint batch``: many models, views and formats at once, on Dask workers."""

from __future__ import annotations

from pathlib import Path

import click

from blueprint.cli.options import STYLE_NAMES, progress_bar
from blueprint.errors import printable


@click.command()
@click.argument("inputs", nargs=-1, required=True)
@click.option(
    "-o", "--outdir", type=click.Path(path_type=Path), required=True, help="Folder for the drawings."
)
@click.option(
    "--views", default="iso", show_default=True, help="Comma-separated views (iso, top, ..., plan)."
)
@click.option(
    "--formats", default="png", show_default=True, help="Comma-separated formats: png, svg, pdf, dxf."
)
@click.option(
    "--workers", type=int, default=None, help="Worker processes (default: one per --gpus device, else 1)."
)
@click.option("--scheduler", default=None, help="Address of a running Dask scheduler to use instead.")
@click.option(
    "--gpus",
    default=None,
    help="EGL devices, one worker each: all, a count N, or indices like 0,2 ('2,' is device 2 alone).",
)
@click.option("--size", nargs=2, type=int, default=(1024, 1024), show_default=True, metavar="W H")
@click.option("--style", default="blueprint", show_default=True, help=f"One of {', '.join(STYLE_NAMES)}.")
@click.option("--max-layers", type=int, default=8, show_default=True, help="Depth layers at most (0: all).")
def batch(inputs, outdir, views, formats, workers, scheduler, gpus, size, style, max_layers):
    """Draw INPUTS (files, folders, glob patterns) in every view and format into OUTDIR, one Dask
    task per input; OUTDIR/manifest.json records each input's outputs, layers, time or error.
    Outputs newer than their input are kept. Exit code 1 when some inputs failed."""
    from blueprint.api.batch import MANIFEST
    from blueprint.api.batch import batch as run_batch

    with progress_bar("drawing") as update:
        manifest = run_batch(
            inputs,
            outdir,
            views=views.split(","),
            formats=formats.split(","),
            workers=workers,
            scheduler=scheduler,
            gpus=gpus,
            size=size,
            style=style,
            max_layers=max_layers or None,
            progress=update,
        )
    for record in manifest["inputs"]:
        if record.get("error"):
            click.echo(f"blueprint: failed: {printable(record['error'])}", err=True)
    click.echo(
        printable(
            f"{outdir / MANIFEST}: {manifest['drawn']} drawn, {manifest['skipped']} up to date, "
            f"{manifest['failed']} failed, {manifest['seconds']:.1f} s on {manifest['workers']} workers"
        )
    )
    if manifest["failed"]:
        raise SystemExit(1)
