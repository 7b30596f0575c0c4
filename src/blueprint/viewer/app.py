"""The ``view`` entry: a model file opened in the viewer (``blueprint view MODEL``; the click
command is ``blueprint.cli.view``)."""

from __future__ import annotations

import os
from pathlib import Path

from blueprint.compose.style import STYLES, get_style
from blueprint.viewer.loop import Options, Viewer
from blueprint.viewer.snapshots import DUMP_ENV
from blueprint.viewer.state import ViewState
from blueprint.viewer.window import import_glfw


def run_viewer(
    model_path: str | os.PathLike,
    *,
    size: tuple[int, int] = (800, 600),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    include: str | None = None,
    exclude: str | None = None,
    style: str = "blueprint",
    styles: tuple[str, ...] = tuple(STYLES),
    max_layers: int | None = 5,
    options: Options | None = None,
    frames: int = 0,
) -> dict | None:
    """Open the viewer on a model file; returns when the window closes (see ``Viewer.run``)."""
    from blueprint.scene.loader import load_model

    import_glfw()  # no display: say so before loading anything
    state = ViewState.start(styles, style, view, azimuth, elevation, fov, ortho, max_layers)
    options = options or Options()
    get_style(style, options.grid)
    model = load_model(model_path, up=up, include=include, exclude=exclude)
    viewer = Viewer(model, Path(model_path), state, size=size, options=options, dump=os.environ.get(DUMP_ENV))
    return viewer.run(frames=frames)
