"""The Python API: ``render`` and ``peel`` on a file or a Model, with a shared renderer."""

from __future__ import annotations

import os

import numpy as np

from blueprint.render.renderer import Frame, Layers, Renderer
from blueprint.scene.camera import Camera
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model

_renderer: Renderer | None = None


def default_renderer() -> Renderer:
    """The renderer ``render`` and ``peel`` use when none is given (created on first use)."""
    global _renderer
    if _renderer is None:
        _renderer = Renderer()
    return _renderer


def _as_model(model: Model | str | os.PathLike, up: str | None) -> Model:
    return model if isinstance(model, Model) else load_model(model, up=up)


def _camera(model: Model, size, view, azimuth, elevation, fov, ortho, camera) -> Camera | None:
    if camera is not None:
        return camera
    return Camera.fit(
        model.positions,
        view,
        azimuth=azimuth,
        elevation=elevation,
        fov=fov,
        ortho=ortho,
        aspect=size[0] / size[1] if size[1] else 1.0,
        up=model.up,
    )


def render_frame(
    model: Model | str | os.PathLike,
    *,
    size: tuple[int, int] = (1024, 1024),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    camera: Camera | None = None,
    renderer: Renderer | None = None,
    **options,
) -> Frame:
    """Like ``render`` but returns the whole ``Frame`` (image, layers used, timings)."""
    model = _as_model(model, up)
    renderer = renderer or default_renderer()
    size = tuple(int(v) for v in size)
    from blueprint.render.renderer import check_size

    check_size(size, int(options.get("supersample", 2)), renderer.max_texture)
    cam = _camera(model, size, view, azimuth, elevation, fov, ortho, camera)
    return renderer.render(model, cam, size=size, **options)


def render(model: Model | str | os.PathLike, **kwargs) -> np.ndarray:
    """Draw the blueprint of a model: every visible and hidden edge of every part.

    Parameters
    ----------
    model : Model, str or PathLike
        A loaded model or a model file.
    size : (int, int)
        Width and height in pixels (default 1024 x 1024).
    view : str
        ``iso`` (default), ``front``, ``back``, ``left``, ``right``, ``top``, ``bottom``.
    azimuth, elevation, fov, ortho, up, camera
        Camera overrides (degrees; orthographic projection; model up axis; a ready Camera).
    style : str or Style
        ``blueprint`` (default), ``paper``, ``transparent`` or ``wireframe``.
    max_layers, min_fraction, crease_angle, line_width, supersample, depth_threshold, part_edges
        See ``Renderer.render``.

    Returns
    -------
    (H, W, 4) uint8
        RGBA image, row 0 at the top.
    """
    return render_frame(model, **kwargs).image


def peel(
    model: Model | str | os.PathLike,
    *,
    size: tuple[int, int] = (512, 512),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    camera: Camera | None = None,
    renderer: Renderer | None = None,
    **options,
) -> Layers:
    """Peel the depth layers of a model and return them (see ``Layers``)."""
    model = _as_model(model, up)
    renderer = renderer or default_renderer()
    size = tuple(int(v) for v in size)
    from blueprint.render.renderer import check_size

    check_size(size, 1, renderer.max_texture)
    cam = _camera(model, size, view, azimuth, elevation, fov, ortho, camera)
    return renderer.peel(model, cam, size=size, **options)
