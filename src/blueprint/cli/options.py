"""What every command shares: the drawing options, made from the fields of the API's
``DrawOptions`` (``drawing_options``, ``drawing_values``; the camera's are ``camera_options``),
the flags that name the API's arguments in its errors (``with_flags``) and the progress bar;
and, from ``blueprint.cli.shell``, the one-line warnings and ``run``, which makes a click
command a program whose user errors are one line and exit code 2."""

from __future__ import annotations

import contextlib
import re
from pathlib import Path

import click

from blueprint.compose.style import STYLES

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


# what the progress display says as each stage of one drawing begins (blueprint.api.stages)
PHASES = {
    "read": "reading the model",
    "prepare_upload": "preparing and uploading the mesh",
    "contours": "finding the contour lines",
    "capture_edges": "drawing",
    "lines": "finding the lines",
    "write": "writing",
}


@contextlib.contextmanager
def phase_bar():
    """The phases of one drawing (``PHASES``: the stages ``blueprint.api.stages`` tells as they
    begin) with the time each has taken so far and how far it has come where it tells that (a
    mesh drawn in chunks), on stderr, shown only on a terminal as ``progress_bar`` is; in a
    pipe no stage is listened to."""
    import sys

    if not sys.stderr.isatty():
        yield
        return
    from rich.console import Console
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    from blueprint.api import stages

    console = Console(stderr=True)
    if not console.is_terminal:
        yield
        return
    with Progress(
        SpinnerColumn(),
        TextColumn("{task.description}"),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    ) as progress:
        shown = {"task": None, "phase": None}

        def told(name: str, detail: str | None = None) -> None:
            if name not in PHASES:
                return
            if name != shown["phase"]:
                if shown["task"] is not None:
                    progress.remove_task(shown["task"])
                shown["task"], shown["phase"] = progress.add_task(PHASES[name], total=None), name
            if detail is not None:
                progress.update(shown["task"], description=f"{PHASES[name]} ({detail})")

        with stages.listen(told):
            yield


# The options of every command that places a camera, as DrawOptions names them.
CAMERA_OPTIONS = ("size", "view", "azimuth", "elevation", "fov", "ortho", "include", "exclude", "up")


def drawing_options(*names: str, helps: dict[str, str] | None = None, **defaults):
    """The click options of ``DrawOptions``' fields ``names``, made from the fields: the flag
    (``--`` and the name, dashed), help (``helps`` over the field's own, where a command takes
    less), type, metavar and default (``defaults`` over the field's own), in the order named.
    ``drawing_values`` makes the values the API's."""
    from blueprint.api.options import option_fields

    made = []
    for name in names:
        f = option_fields()[name]
        meta, default = dict(f.metadata), defaults.get(name, f.default)
        meta["help"] = (helps or {}).get(name, meta["help"])
        assert meta["cli"], f"{name} is no option of the command line"
        if isinstance(f.default, bool):
            made.append(click.option(flag(name), is_flag=True, default=default, help=meta["help"]))
            continue
        if meta["kind"] == "switch":
            # on, off, or the API's own choice where neither is given
            on_off = f"{flag(name)}/--no-{flag(name)[2:]}"
            made.append(click.option(on_off, default=default, help=meta["help"]))
            continue
        kind = meta["kind"] or (str if f.default is None else type(f.default))
        if kind == "path":
            kind = click.Path(path_type=Path)
        elif meta["choices"]:
            kind = click.Choice(meta["choices"])
        shown = default is not None and not meta["nargs"]
        made.append(
            click.option(
                flag(name),
                type=kind,
                nargs=meta["nargs"] or 1,
                default=default,
                show_default=shown,
                metavar=meta["metavar"],
                help=meta["help"],
            )
        )

    def decorate(func):
        for option in reversed(made):
            func = option(func)
        return func

    return decorate


def camera_options(func):
    """Options shared by every command that places a camera (``--size`` defaults to None: the
    command's own)."""
    return drawing_options(*CAMERA_OPTIONS, size=None)(func)


def drawing_values(values: dict) -> dict:
    """Take the values of ``DrawOptions``' fields out of a command's ``values`` (click's, by
    parameter name) as the API takes them: ``--max-layers 0`` is every layer (None), ``--size``
    a tuple, an option not given left out (the field's default then)."""
    from blueprint.api.options import option_fields, zero_layers_are_all

    taken = {name: values.pop(name) for name in option_fields() if name in values}
    if taken.get("size") is not None:
        taken["size"] = tuple(taken["size"])
    return zero_layers_are_all({k: v for k, v in taken.items() if v is not None or k == "max_layers"})


def flag(name: str) -> str:
    """The command line's flag of an API argument: ``line_width`` is ``--line-width``."""
    return "--" + name.replace("_", "-")


_ARGUMENT = re.compile(r"(?<![\w./-])([a-z]+(?:_[a-z]+)+)(?![\w./-])")


def with_flags(message: str) -> str:
    """``message`` (an API error) with the arguments of ``DrawOptions`` it names as the command
    line's flags: ``line_width must be ...`` is ``--line-width must be ...``. Names spelled the
    same either way (``supersample``) are left as they are."""
    from blueprint.api.options import option_fields

    known = {name for name, f in option_fields().items() if f.metadata["cli"] and "_" in name}
    return _ARGUMENT.sub(lambda m: flag(m.group(1)) if m.group(1) in known else m.group(1), message)
