"""Silhouette pictures and videos from a model file: ``blueprint silhouettes`` over the Python
API. A module of its own so that the GPU silhouette methods (``blueprint.gpu_silhouettes`` and
the operations it declares) load for this workflow only, not with every drawing."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from blueprint.api.files import choose_writer
from blueprint.api.frames import as_model, shared
from blueprint.api.options import DrawOptions, takes_options
from blueprint.api.renderer import Renderer
from blueprint.errors import InputError
from blueprint.export.writers import WRITERS, Kind
from blueprint.gpu_silhouettes import (
    DEFAULT_LAYERS,
    DEFAULT_METHOD,
    MAX_LAYERS,
    animate_silhouettes,
    render_silhouettes,
)
from blueprint.scene.camera import VIEWS
from blueprint.scene.model import Model
from blueprint.settings import FRAME_LIMIT

__all__ = ["render_silhouettes_file"]


# What a silhouette picture takes of the options: where the camera looks from and the parts.
SILHOUETTE_OPTIONS = ("size", "view", "azimuth", "elevation", "fov", "ortho", "up", "include", "exclude")


@takes_options(*SILHOUETTE_OPTIONS, size=(800, 600))
def render_silhouettes_file(
    model: Model | str | os.PathLike,
    output: str | os.PathLike,
    options: DrawOptions,
    *,
    method: str = DEFAULT_METHOD,
    layers: int = DEFAULT_LAYERS,
    animate: str | None = None,
    frames: int = 60,
    fps: float = 30.0,
    split_at: float = 0.5,
    renderer: Renderer | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """From a model (file or ``Model``) to a PNG of its silhouettes or, with
    ``animate`` (``twist`` or ``wave``), to an MP4 of ``frames`` frames of them as the model
    deforms, splitting in two after ``split_at`` of the animation (see
    ``blueprint.gpu_silhouettes.render_silhouettes`` and ``animate_silhouettes``). ``options``
    (``DrawOptions``, its fields ``size``, ``view``, ``azimuth``, ``elevation``, ``fov``,
    ``ortho``, ``up``, ``include`` and ``exclude`` keywords too) place the camera and load the
    model. Arguments are checked before the model is loaded or the GPU touched.

    Returns
    -------
    dict
        ``path``, ``frames``, ``width``, ``height``, ``triangles``, ``method`` and ``ms``: the
        still's time, or the median time of a frame's silhouettes; a still's ``chunks`` too
        (those its mesh was drawn in where it did not fit the GPU whole, else 0).
    """
    if options.view not in VIEWS:
        raise InputError(f"unknown view {options.view!r} (choose {', '.join(VIEWS)})")
    if animate is None and WRITERS.find(Path(output).suffix, Kind.VIDEO):
        raise InputError(f"{output}: a video needs --animate twist or --animate wave")
    output, write = choose_writer(output, Kind.VIDEO if animate else Kind.IMAGE)
    if frames < 1:
        raise InputError(f"frames must be at least 1, got {frames}")
    if frames > FRAME_LIMIT:
        raise InputError(f"frames must be at most {FRAME_LIMIT} (the limit), got {frames}")
    if not 0 < fps <= 240:
        raise InputError(f"fps must be in (0, 240], got {fps:g}")
    if not 1 <= layers <= MAX_LAYERS:
        raise InputError(f"layers must be an integer from 1 to {MAX_LAYERS}, got {layers}")
    size = options.size
    camera = dict(
        view=options.view,
        azimuth=options.azimuth,
        elevation=options.elevation,
        fov=options.fov,
        ortho=options.ortho,
    )
    loaded = as_model(model, options)
    renderer = shared(renderer)
    summary = {
        "path": str(output),
        "width": size[0],
        "height": size[1],
        "triangles": loaded.triangle_count,
        "method": method,
    }
    if animate is None:
        t0 = time.perf_counter()
        image = render_silhouettes(
            loaded, method=method, layers=layers, size=size, renderer=renderer, **camera
        )
        ms = (time.perf_counter() - t0) * 1e3
        write(output, image)
        return {**summary, "frames": 1, "ms": ms, "chunks": renderer.capturer.chunks(loaded)}

    times: list[float] = []
    pictures = animate_silhouettes(
        loaded,
        animate=animate,
        frames=frames,
        split_at=split_at,
        method=method,
        layers=layers,
        size=size,
        renderer=renderer,
        **camera,
    )

    def tracked():
        for done, (image, ms) in enumerate(pictures, start=1):
            times.append(ms)
            yield image
            if progress is not None:
                progress(done, frames)

    write(output, tracked(), fps=fps)
    return {**summary, "frames": len(times), "ms": float(np.median(times))}
