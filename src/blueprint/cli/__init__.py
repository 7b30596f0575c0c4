"""The command line: a thin shell over the Python API (every option is an API argument).

Commands live in the modules of this package by subject and share ``blueprint.cli.options``;
``main`` is the ``blueprint`` console script (``python -m blueprint.cli`` runs it too). A
command's module is imported only when that command runs: ``blueprint --help`` lists them from
``COMMANDS`` without loading the renderer, whose imports a help does not need.
"""

from __future__ import annotations

import atexit
import functools
import gc
import importlib
import os
import sys

import click

from blueprint import __version__
from blueprint.allocator import keep_freed
from blueprint.cli.shell import run, setup_logging

# 0: the command runs in the program's own process (for profilers), not in a child
SUPERVISE_ENV = "BLUEPRINT_SUPERVISE"

__all__ = ["COMMANDS", "SUPERVISE_ENV", "STYLE_NAMES", "camera_options", "cli", "main", "progress_bar", "run"]

# name: (module, attribute, its short help: tests/cli/test_cli.py keeps it the command's own)
COMMANDS: dict[str, tuple[str, str, str]] = {
    "render": (
        "blueprint.cli.render",
        "render",
        "Draw the blueprint of MODEL into a picture (PNG), or as vector lines into SVG, PDF or DXF.",
    ),
    "layers": (
        "blueprint.cli.render",
        "layers",
        "Peel MODEL's depth layers and write them as NPZ (depth, triangle, part, view, projection).",
    ),
    "info": (
        "blueprint.cli.info",
        "info",
        "Without MODEL: the OpenGL renderer, the ways it draws and the EGL devices (for --gpus and "
        "BLUEPRINT_GL_DEVICE).",
    ),
    "bench": (
        "blueprint.cli.info",
        "bench",
        "Time whole frames (image read back) and print one JSON object per configuration.",
    ),
    "pipeline": (
        "blueprint.cli.pipeline",
        "pipeline",
        "Image-space pipelines declared in TOML files (or presets: blueprint, edges-sobel, ...).",
    ),
    "ops": (
        "blueprint.cli.pipeline",
        "ops",
        "List the image-space operations with their inputs, output and parameters.",
    ),
    "turntable": (
        "blueprint.cli.pipeline",
        "turntable",
        "Orbit the camera around MODEL and write a video of a pipeline (the blueprint by default).",
    ),
    "silhouettes": (
        "blueprint.cli.silhouettes",
        "silhouettes",
        "Draw MODEL's silhouettes into a PNG, or, with --animate, the silhouettes of MODEL deforming "
        "(and splitting in two part-way) into an MP4.",
    ),
    "view": (
        "blueprint.cli.view",
        "view",
        "Open MODEL in a window: orbit, pan and zoom with the mouse, click a part to highlight it.",
    ),
    "batch": (
        "blueprint.cli.batch",
        "batch",
        "Draw INPUTS (files, folders, glob patterns) in every view and format into OUTDIR, one Dask "
        "task per input; OUTDIR/manifest.json records each input's outputs, layers, time or error.",
    ),
}


class _LazyGroup(click.Group):
    """A group whose commands are imported when one runs, listed from ``COMMANDS``."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name not in COMMANDS:
            return None
        module, attribute, _ = COMMANDS[name]
        return getattr(importlib.import_module(module), attribute)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        limit = formatter.width - 6 - max(len(name) for name in COMMANDS)
        rows = [
            (name, click.utils.make_default_short_help(COMMANDS[name][2], limit)) for name in sorted(COMMANDS)
        ]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


@click.group(cls=_LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(version=__version__, prog_name="blueprint")
def cli() -> None:
    """Blueprints of 3D models: the visible and hidden edges of every part, drawn on the GPU."""
    setup_logging()


def main(argv: list[str] | None = None) -> None:
    """Entry point: user errors become one line on stderr and exit code 2. Without ``argv`` (the
    console script) the command runs in a child process that Ctrl-C stops at once, exit code
    130 (``blueprint.cli.supervise``; ``BLUEPRINT_SUPERVISE=0`` runs it in this process)."""
    # Set before NumPy is imported, unless the user chose: the command's matrix products are
    # (N, 3) by 3 x 3, held to one BLAS thread anyway (blueprint.blas), so OpenBLAS starting a
    # thread a core at NumPy's import would only cost every process time.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    # the command's process serves the preparation's threads from one allocator arena
    # (blueprint.parallel): memory their blocks free is reused by the drawing after them
    os.environ.setdefault("BLUEPRINT_ONE_ARENA", "1")
    # ...and keeps the memory it frees for what it allocates next (inherited by the child below)
    keep_freed()
    _light_exit()
    # a help or the version prints and ends: no child for Ctrl-C to stop
    asks_help = {"-h", "--help", "--version"} & set(sys.argv[1:])
    if argv is None and hasattr(os, "fork") and os.environ.get(SUPERVISE_ENV, "1") != "0" and not asks_help:
        # as the program (not called with arguments from Python): in a child that Ctrl-C can
        # stop in any phase (blueprint.cli.supervise)
        from blueprint.cli.supervise import supervised

        supervised(lambda: run(cli, argv, "blueprint"))
    run(cli, argv, "blueprint")


@functools.cache
def _light_exit() -> None:
    """At the interpreter's exit (not when a caller in this process goes on), freeze what is
    left: Python's collections at shutdown walk every object the imports made, only to free
    memory the OS takes back anyway."""
    atexit.register(gc.freeze)


def __getattr__(name: str):
    # what commands share, for code that took it from here; loaded only when asked for
    if name in ("STYLE_NAMES", "camera_options", "progress_bar"):
        from blueprint.cli import options

        return getattr(options, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
