"""Frames: ``render``, ``render_frame`` and ``peel`` on a file or a Model, plan sheets included."""

from __future__ import annotations

import os
import time
from dataclasses import replace

import numpy as np

from blueprint.api.renderer import Renderer
from blueprint.compose.glyphs import Glyphs, load_glyphs, render_with_glyphs
from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.render.renderer import Frame, Layers
from blueprint.scene.camera import SHEET_CELLS, Camera, fit_camera, sheet_cameras
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model
from blueprint.scene.parts import designated_parts

#: The view name of a drawing sheet: top, front and right orthographic views plus an iso view.
PLAN = "plan"


def shared(renderer: Renderer | None) -> Renderer:
    """``renderer``, or the shared one when it is None (``blueprint.api.default_renderer``)."""
    if renderer is not None:
        return renderer
    # looked up when called: the package holds the shared renderer (where callers swap it) and
    # imports this module
    from blueprint.api import default_renderer

    return default_renderer()


def _as_model(model: Model | str | os.PathLike, up: str | None) -> Model:
    return model if isinstance(model, Model) else load_model(model, up=up)


def _camera(model: Model, size, view, azimuth, elevation, fov, ortho, camera) -> Camera | None:
    if camera is not None:
        return camera
    return fit_camera(model, size, view, azimuth=azimuth, elevation=elevation, fov=fov, ortho=ortho)


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
    renderer = shared(renderer)
    size = tuple(int(v) for v in size)
    check_size(size, int(options.get("supersample", 2)), renderer.max_texture)
    for key in ("highlight", "shade"):
        if options.get(key) is not None:
            options[key] = designated_parts(model, options[key])
    glyphs = options.pop("glyphs", None)
    if glyphs is not None and not isinstance(glyphs, Glyphs):
        glyphs = load_glyphs(glyphs)
    if view == PLAN and camera is None:
        if glyphs is not None:
            raise InputError("glyphs need one view; the plan sheet draws four")
        return _plan_frame(model, size, fov, renderer, options)
    cam = _camera(model, size, view, azimuth, elevation, fov, ortho, camera)
    frame = renderer.render(model, cam, size=size, **options)
    if glyphs is not None:
        t0 = time.perf_counter()
        image = render_with_glyphs(renderer, model, frame.camera, size, glyphs, frame.image)
        spent = (time.perf_counter() - t0) * 1e3
        frame = replace(frame, image=image, ms=frame.ms + spent, stages={**frame.stages, "glyphs": spent})
    return frame


def _plan_frame(model: Model, size: tuple[int, int], fov: float, renderer: Renderer, options) -> Frame:
    """A drawing sheet in third-angle projection: top view above the front view, right view
    beside it, all orthographic at one scale, and an iso view in the free corner."""
    w, h = size[0] // 2, size[1] // 2
    if w < 1 or h < 1:
        raise InputError(f"size {size[0]}x{size[1]} is too small for a plan sheet (at least 2x2)")
    cameras = sheet_cameras(model, (w, h), fov)
    image = np.zeros((size[1], size[0], 4), np.uint8)
    frames = {}
    for name, (col, row) in SHEET_CELLS.items():
        frames[name] = renderer.render(model, cameras[name], size=(w, h), **options)
        image[row * h : (row + 1) * h, col * w : (col + 1) * w] = frames[name].image
    if size[0] % 2 or size[1] % 2:
        # odd sizes leave a last row or column: continue the paper there
        image[2 * h :, :] = image[2 * h - 1 : 2 * h, :]
        image[:, 2 * w :] = image[:, 2 * w - 1 : 2 * w]
    front = frames["front"]
    return Frame(
        image=image,
        layers=max(f.layers for f in frames.values()),
        layer_pixels=front.layer_pixels,
        camera=cameras["front"],
        ms=sum(f.ms for f in frames.values()),
        draws=sum(f.draws for f in frames.values()),
        stages={},
    )


def render(model: Model | str | os.PathLike, **kwargs) -> np.ndarray:
    """Draw the blueprint of a model: every visible and hidden edge of every part.

    Parameters
    ----------
    model : Model, str or PathLike
        A loaded model or a model file.
    size : (int, int)
        Width and height in pixels (default 1024 x 1024).
    view : str
        ``iso`` (default), ``front``, ``back``, ``left``, ``right``, ``top``, ``bottom``, or
        ``plan``: a sheet of orthographic top, front and right views at one scale plus iso.
    azimuth, elevation, fov, ortho, up, camera
        Camera overrides (degrees; orthographic projection; model up axis; a ready Camera).
    style : str or Style
        ``blueprint`` (default), ``paper``, ``transparent`` or ``wireframe``.
    max_layers, min_fraction, crease_angle, line_width, supersample, depth_threshold, part_edges
        See ``Renderer.render``.
    highlight : str, sequence, Model or (P,) bool, optional
        Parts to outline in the highlight ink: name globs (``"Piston*"``) and indices, or a
        second model lying on the parts to designate.
    reveal : float, optional
        Depth masking: peel only until this fraction of the highlighted parts is uncovered.
    shade : str, sequence, Model or (P,) bool, optional
        Parts drawn shaded inside the blueprint, in depth order (``shade_opacity`` 1: opaque).
    glyphs : Glyphs, str or PathLike, optional
        Boxes, arrows, paths and labels in model coordinates (a TOML or JSON file, see
        ``blueprint.compose.glyphs``), drawn depth-correctly: dimmed, dashed or left out where
        a surface hides them.

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
    renderer = shared(renderer)
    size = tuple(int(v) for v in size)
    check_size(size, 1, renderer.max_texture)
    cam = _camera(model, size, view, azimuth, elevation, fov, ortho, camera)
    return renderer.peel(model, cam, size=size, **options)
