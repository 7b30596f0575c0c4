"""The command line: a thin shell over the Python API (every option is an API argument).

Commands live in the modules of this package by subject and share ``blueprint.cli.options``;
``main`` is the ``blueprint`` console script (``python -m blueprint.cli`` runs it too).
"""

from __future__ import annotations

import click

from blueprint import __version__
from blueprint.cli import batch, info, pipeline, render, silhouettes, view
from blueprint.cli.options import STYLE_NAMES, camera_options, progress_bar, run, setup_logging

__all__ = ["STYLE_NAMES", "camera_options", "cli", "main", "progress_bar", "run"]


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(version=__version__, prog_name="blueprint")
def cli() -> None:
    """Blueprints of 3D models: the visible and hidden edges of every part, drawn on the GPU."""
    setup_logging()


for command in (
    render.render,
    render.layers,
    info.info,
    info.bench,
    pipeline.pipeline,
    pipeline.ops,
    pipeline.turntable,
    silhouettes.silhouettes,
    view.view,
    batch.batch,
):
    cli.add_command(command)


def main(argv: list[str] | None = None) -> None:
    """Entry point: user errors become one line on stderr and exit code 2."""
    run(cli, argv, "blueprint")
