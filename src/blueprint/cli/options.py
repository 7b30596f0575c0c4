"""What every command shares: the camera options and the progress bar; and, from
``blueprint.cli.shell``, the one-line warnings and ``run``, which makes a click command a program
whose user errors are one line and exit code 2."""

from __future__ import annotations

import contextlib

import click

from blueprint.compose.style import STYLES
from blueprint.errors import InputError
from blueprint.scene.camera import VIEWS

STYLE_NAMES = tuple(STYLES)


@contextlib.contextmanager
def progress_bar(label: str):
    """A rich progress bar on stderr, shown only on a terminal (in a pipe it would put blank
    lines around error messages). Yields ``update(done, total)``."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    console = Console(stderr=True)
    with Progress(
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=console,
        transient=True,
        disable=not console.is_terminal,
    ) as progress:
        task = progress.add_task(label, total=None)

        def update(done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        yield update


def camera_options(func):
    """Options shared by every command that places a camera."""
    options = [
        click.option(
            "--size",
            nargs=2,
            type=int,
            default=None,
            metavar="W H",
            help="Image width and height in pixels.",
        ),
        click.option(
            "--view",
            default="iso",
            show_default=True,
            help=f"Named view: {', '.join(VIEWS)}; render also takes plan (a sheet of top, front, right).",
        ),
        click.option(
            "--azimuth", type=float, default=None, help="Degrees from the front, towards the right."
        ),
        click.option("--elevation", type=float, default=None, help="Degrees above the horizon."),
        click.option(
            "--fov",
            type=float,
            default=30.0,
            show_default=True,
            help="Vertical field of view, degrees.",
        ),
        click.option("--ortho", is_flag=True, help="Orthographic projection (plan views)."),
        click.option(
            "--include",
            default=None,
            metavar="GLOBS",
            help="Draw only these parts (name globs or indices, comma-separated); keeps environment meshes.",
        ),
        click.option(
            "--exclude",
            default=None,
            metavar="GLOBS",
            help="Leave these parts out (environment meshes like skyboxes are left out by default).",
        ),
        click.option(
            "--up",
            type=click.Choice(["y", "z"]),
            default=None,
            help="Model up axis (default: z for STL/3MF, y for glTF; OBJ/PLY/OFF: guessed from a flat base).",
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def camera_kwargs(size, view, azimuth, elevation, fov, ortho, up, default_size, plan=False):
    names = [*VIEWS, "plan"] if plan else list(VIEWS)
    if view not in names:
        raise InputError(f"unknown view {view!r} (choose {', '.join(names)})")
    return dict(
        size=tuple(size) if size else default_size,
        view=view,
        azimuth=azimuth,
        elevation=elevation,
        fov=fov,
        ortho=ortho,
        up=up,
    )
