"""The ``view`` entry: a model file opened in the viewer (``blueprint view MODEL``; the click
command is ``blueprint.cli.view``)."""

from __future__ import annotations

import os
from pathlib import Path

from blueprint.api.options import DrawOptions
from blueprint.compose.style import STYLES
from blueprint.scene.headers import pictures_only
from blueprint.viewer.loop import Viewer
from blueprint.viewer.pacing import MOVING_FPS
from blueprint.viewer.snapshots import DUMP_ENV
from blueprint.viewer.state import Options, ViewState
from blueprint.viewer.window import import_glfw


def run_viewer(
    model_path: str | os.PathLike,
    options: DrawOptions | None = None,
    *,
    styles: tuple[str, ...] = tuple(STYLES),
    interactive_scale: float = 0.0,
    moving_fps: float = MOVING_FPS,
    frames: int = 0,
    still_frames: int | None = None,
) -> dict | None:
    """Open the viewer on a model file; returns when the window closes (see ``Viewer.run``).

    ``options`` (default: a window of 800 x 600 peeling 5 layers) give the window's size, the
    first view and style, the model file's ``up``, ``include`` and ``exclude``, and the
    frames' settings (``grid``, ``max_layers``, ``min_fraction``, ``crease_angle``,
    ``line_width``, ``supersample``); ``styles`` are those the S key cycles through. While the
    view moves, frames keep ``moving_fps`` (see ``viewer.pacing``), or with
    ``interactive_scale`` > 0 are drawn at that fraction of the window. ``frames`` > 0
    measures: that many turntable frames, then ``still_frames`` full drawings, and returns
    their frame rates instead of waiting for the window to close.
    """
    from blueprint.scene.loader import load_model

    import_glfw()  # no display: say so before loading anything
    options = options or DrawOptions(size=(800, 600), max_layers=5)
    camera = (options.view, options.azimuth, options.elevation, options.fov, options.ortho)
    state = ViewState.start(styles, options.style, *camera, options.max_layers)
    frames_options = Options(
        grid=options.grid,
        min_fraction=options.min_fraction,
        crease_angle=options.crease_angle,
        line_width=options.line_width,
        supersample=options.supersample,
        # only where asked: the CPU pass a view would hold the window each time the view rests
        smooth_contours=bool(options.smooth_contours),
        interactive_scale=interactive_scale,
        moving_fps=moving_fps,
    )
    # the viewer draws pictures alone: weighed as one (its coarse meshes are a fraction of it)
    with pictures_only():
        model = load_model(model_path, up=options.up, include=options.include, exclude=options.exclude)
    viewer = Viewer(
        model,
        Path(model_path),
        state,
        size=options.size,
        options=frames_options,
        dump=os.environ.get(DUMP_ENV),
    )
    return viewer.run(frames=frames, still_frames=still_frames)
