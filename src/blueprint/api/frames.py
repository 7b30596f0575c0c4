"""Frames: ``render``, ``render_frame`` and ``peel`` on a file or a Model, plan sheets included."""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from blueprint.api.renderer import Renderer
from blueprint.api.sections import Section, render_section, section_of
from blueprint.compose.glyphs import Glyphs, load_glyphs, render_with_glyphs
from blueprint.compose.style import Style, get_style
from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.render.renderer import Frame, Layers
from blueprint.scene.camera import SHEET_CELLS, Camera, fit_camera, sheet_cameras
from blueprint.scene.environment import PartGlobs
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model
from blueprint.scene.parts import designated_parts

#: The view name of a drawing sheet: top, front and right orthographic views plus an iso view.
PLAN = "plan"

#: Parts chosen by name globs and indices (a comma-separated string or a sequence), by a second
#: model lying on them, or as one flag per part (see ``blueprint.scene.parts.designated_parts``).
PartSpec = str | int | Sequence[str | int] | Model | np.ndarray


def shared(renderer: Renderer | None) -> Renderer:
    """``renderer``, or the shared one when it is None (``blueprint.api.default_renderer``)."""
    if renderer is not None:
        return renderer
    # looked up when called: the package holds the shared renderer (where callers swap it) and
    # imports this module
    from blueprint.api import default_renderer

    return default_renderer()


def _as_model(model: Model | str | os.PathLike, up: str | None, include=None, exclude=None) -> Model:
    return model if isinstance(model, Model) else load_model(model, up=up, include=include, exclude=exclude)


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
    include: PartGlobs = None,
    exclude: PartGlobs = None,
    camera: Camera | None = None,
    style: str | Style = "blueprint",
    grid: float | None = None,
    max_layers: int | None = 8,
    min_fraction: float = 0.0,
    crease_angle: float = 30.0,
    line_width: float = 1.0,
    supersample: int = 2,
    depth_threshold: float = 4.0,
    part_edges: bool = True,
    id_silhouettes: bool = False,
    highlight: PartSpec | None = None,
    reveal: float | None = None,
    shade: PartSpec | None = None,
    shade_opacity: float = 1.0,
    glyphs: Glyphs | str | os.PathLike | None = None,
    section: str | None = None,
    section_plane: str | Sequence[float] | None = None,
    section_keep: PartSpec | None = None,
    profile: bool = False,
    renderer: Renderer | None = None,
) -> Frame:
    """Draw the blueprint of a model, as ``render`` does, and return the whole frame.

    Parameters
    ----------
    model : Model, str or PathLike
        A loaded model or a model file.
    size : (int, int)
        Width and height in pixels.
    view : str
        ``iso``, ``front``, ``back``, ``left``, ``right``, ``top``, ``bottom``, or ``plan``: a
        sheet of orthographic top, front and right views at one scale plus iso, each a quarter
        of ``size``.
    azimuth, elevation : float, optional
        Degrees from the front towards the right, and above the horizon, overriding ``view``'s.
    fov : float
        Vertical field of view in degrees.
    ortho : bool
        Orthographic projection.
    up : {'y', 'z'}, optional
        The model file's up axis (default: z for STL and 3MF, y for glTF, guessed from the
        shape for OBJ, PLY and OFF).
    include, exclude : str or sequence, optional
        A model file's parts to keep and to leave out (name globs or indices); without
        ``include`` its environment meshes (skyboxes, huge ground planes) are left out.
    camera : Camera, optional
        A ready camera; the view arguments are then unused.
    style : str or Style
        A style of ``blueprint.compose.style.STYLES`` by name (``blueprint``, ``paper``,
        ``transparent``, ``wireframe``), or a ``Style``.
    grid : float, optional
        The style's grid spacing in pixels, overridden (0: no grid).
    max_layers : int or None
        Depth layers to peel at most; None peels until a pass draws nothing.
    min_fraction : float
        Stop once a layer covers fewer than this fraction of layer 0's pixels.
    crease_angle : float
        Degrees: normals are smoothed across smaller angles, larger ones draw creases.
    line_width : float
        Line width in output pixels, in [1, 16].
    supersample : int
        G-buffer and edges are computed at this multiple of ``size``, then filtered down.
    depth_threshold : float
        The depth jump, in pixel footprints, that draws a silhouette edge, in [0.1, 1000].
    part_edges : bool
        Draw the boundaries between parts.
    id_silhouettes : bool
        Also draw triangle-ID silhouettes in every layer's edge map.
    highlight : str, int, sequence, Model or (P,) bool, optional
        Parts to outline in the highlight ink: name globs (``"Piston*"``) and indices, or a
        second model lying on the parts to designate.
    reveal : float, optional
        Depth masking: peel only until this fraction of the highlighted parts is uncovered, as
        deep as that takes (``max_layers`` does not cap it).
    shade : str, int, sequence, Model or (P,) bool, optional
        Parts drawn shaded inside the blueprint, in depth order.
    shade_opacity : float
        Opacity of the shading, in (0, 1]: 1 hides the edges behind the shaded parts.
    glyphs : Glyphs, str or PathLike, optional
        Boxes, arrows, paths and labels in model coordinates (a TOML or JSON file, see
        ``blueprint.compose.glyphs``), drawn depth-correctly: dimmed, dashed or left out where
        a surface hides them. Not on a plan sheet.
    section : str, optional
        A section view: ``"x=VALUE"`` (or ``y=``, ``z=``, model units) removes the model in front
        of that plane as the camera sees it; the cut faces are hatched, outlined heavy.
    section_plane : str or 6 floats, optional
        A section by any plane: a point of it and a normal towards the side removed
        (``"PX,PY,PZ,NX,NY,NZ"``).
    section_keep : str, int, sequence, Model or (P,) bool, optional
        Parts drawn whole in a section (shafts, bolts, pins).
    profile : bool
        Synchronise after each stage to fill ``Frame.stages`` (slower).
    renderer : Renderer, optional
        Draw with this renderer instead of the shared one.

    Returns
    -------
    Frame
        The (H, W, 4) uint8 image, the layers drawn, the camera and the timings.
    """
    if glyphs is not None and not isinstance(glyphs, Glyphs):
        glyphs = load_glyphs(glyphs)
    chosen = get_style(style, grid)
    model = _as_model(model, up, include, exclude)
    renderer = shared(renderer)
    size = tuple(int(v) for v in size)
    check_size(size, int(supersample), renderer.max_texture)
    options = dict(
        style=chosen,
        max_layers=max_layers,
        min_fraction=min_fraction,
        crease_angle=crease_angle,
        line_width=line_width,
        supersample=supersample,
        depth_threshold=depth_threshold,
        part_edges=part_edges,
        id_silhouettes=id_silhouettes,
        highlight=None if highlight is None else designated_parts(model, highlight),
        reveal=reveal,
        shade=None if shade is None else designated_parts(model, shade),
        shade_opacity=shade_opacity,
        profile=profile,
    )
    cut = section_of(model, section, section_plane, section_keep)
    if view == PLAN and camera is None:
        if glyphs is not None:
            raise InputError("glyphs need one view; the plan sheet draws four")
        return _plan_frame(model, size, fov, renderer, options, cut)
    cam = _camera(model, size, view, azimuth, elevation, fov, ortho, camera)
    if cut is not None:
        frame = render_section(renderer, model, cam, size, cut, options)
    else:
        frame = renderer.render(model, cam, size=size, **options)
    if glyphs is not None:
        t0 = time.perf_counter()
        image = render_with_glyphs(renderer, model, frame.camera, size, glyphs, frame.image)
        spent = (time.perf_counter() - t0) * 1e3
        frame = replace(frame, image=image, ms=frame.ms + spent, stages={**frame.stages, "glyphs": spent})
    return frame


def _plan_frame(
    model: Model, size: tuple[int, int], fov: float, renderer: Renderer, options, section: Section | None
) -> Frame:
    """A drawing sheet in third-angle projection: top view above the front view, right view
    beside it, all orthographic at one scale, and an iso view in the free corner; a section
    cuts the model as the front view sees it, in every view."""
    w, h = size[0] // 2, size[1] // 2
    if w < 1 or h < 1:
        raise InputError(f"size {size[0]}x{size[1]} is too small for a plan sheet (at least 2x2)")
    cameras = sheet_cameras(model, (w, h), fov)
    image = np.zeros((size[1], size[0], 4), np.uint8)
    frames = {}
    if section is not None:
        section = Section(section.plane.facing(cameras["front"].eye, cameras["front"].target), section.keep)
    for name, (col, row) in SHEET_CELLS.items():
        if section is not None:
            frames[name] = render_section(renderer, model, cameras[name], (w, h), section, options)
        else:
            frames[name] = renderer.render(model, cameras[name], size=(w, h), **options)
        image[row * h : (row + 1) * h, col * w : (col + 1) * w] = frames[name].image
    if size[0] % 2 or size[1] % 2:
        # odd sizes leave a last row or column: continue the paper there
        image[2 * h :, :] = image[2 * h - 1 : 2 * h, :]
        image[:, 2 * w :] = image[:, 2 * w - 1 : 2 * w]
    front = frames["front"]
    layers = max(f.layers for f in frames.values())
    return Frame(
        image=image,
        layers=layers,
        layers_left=max(f.layers + f.layers_left for f in frames.values()) - layers,
        layer_pixels=front.layer_pixels,
        camera=cameras["front"],
        ms=sum(f.ms for f in frames.values()),
        draws=sum(f.draws for f in frames.values()),
        stages={},
    )


def render(
    model: Model | str | os.PathLike,
    *,
    size: tuple[int, int] = (1024, 1024),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    include: PartGlobs = None,
    exclude: PartGlobs = None,
    camera: Camera | None = None,
    style: str | Style = "blueprint",
    grid: float | None = None,
    max_layers: int | None = 8,
    min_fraction: float = 0.0,
    crease_angle: float = 30.0,
    line_width: float = 1.0,
    supersample: int = 2,
    depth_threshold: float = 4.0,
    part_edges: bool = True,
    id_silhouettes: bool = False,
    highlight: PartSpec | None = None,
    reveal: float | None = None,
    shade: PartSpec | None = None,
    shade_opacity: float = 1.0,
    glyphs: Glyphs | str | os.PathLike | None = None,
    section: str | None = None,
    section_plane: str | Sequence[float] | None = None,
    section_keep: PartSpec | None = None,
    profile: bool = False,
    renderer: Renderer | None = None,
) -> np.ndarray:
    """Draw the blueprint of a model: every visible and hidden edge of every part.

    Parameters
    ----------
    model : Model, str or PathLike
        A loaded model or a model file.
    size, view, azimuth, elevation, fov, ortho, up, camera
        Where the camera looks from (see ``render_frame``); ``view="plan"`` draws a sheet of
        orthographic top, front and right views at one scale plus iso.
    style, grid
        A style of ``blueprint.compose.style.STYLES`` by name or a ``Style``, and its grid
        spacing in pixels, overridden.
    max_layers, min_fraction, crease_angle, line_width, supersample
        How many layers are peeled and how their edges are drawn (see ``render_frame``).
    depth_threshold, part_edges, id_silhouettes
        Which edges are drawn: silhouettes from this depth jump, boundaries between parts,
        triangle-ID silhouettes (see ``render_frame``).
    highlight : str, int, sequence, Model or (P,) bool, optional
        Parts to outline in the highlight ink: name globs (``"Piston*"``) and indices, or a
        second model lying on the parts to designate.
    reveal : float, optional
        Depth masking: peel only until this fraction of the highlighted parts is uncovered.
    shade : str, int, sequence, Model or (P,) bool, optional
        Parts drawn shaded inside the blueprint, in depth order (``shade_opacity`` 1: opaque).
    shade_opacity : float
        Opacity of the shading, in (0, 1].
    glyphs : Glyphs, str or PathLike, optional
        Boxes, arrows, paths and labels in model coordinates (a TOML or JSON file, see
        ``blueprint.compose.glyphs``), drawn depth-correctly: dimmed, dashed or left out where
        a surface hides them.
    section, section_plane, section_keep : optional
        A section view: the plane (``"x=VALUE"``, or a point and a normal towards the side
        removed) and the parts left uncut (see ``render_frame``).
    profile : bool
        Synchronise after each stage (for timings; slower).
    renderer : Renderer, optional
        Draw with this renderer instead of the shared one.

    Returns
    -------
    (H, W, 4) uint8
        RGBA image, row 0 at the top.
    """
    return render_frame(
        model,
        size=size,
        view=view,
        azimuth=azimuth,
        elevation=elevation,
        fov=fov,
        ortho=ortho,
        up=up,
        include=include,
        exclude=exclude,
        camera=camera,
        style=style,
        grid=grid,
        max_layers=max_layers,
        min_fraction=min_fraction,
        crease_angle=crease_angle,
        line_width=line_width,
        supersample=supersample,
        depth_threshold=depth_threshold,
        part_edges=part_edges,
        id_silhouettes=id_silhouettes,
        highlight=highlight,
        reveal=reveal,
        shade=shade,
        shade_opacity=shade_opacity,
        glyphs=glyphs,
        section=section,
        section_plane=section_plane,
        section_keep=section_keep,
        profile=profile,
        renderer=renderer,
    ).image


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
    include: PartGlobs = None,
    exclude: PartGlobs = None,
    camera: Camera | None = None,
    max_layers: int | None = None,
    min_fraction: float = 0.0,
    crease_angle: float = 30.0,
    normals: bool = True,
    renderer: Renderer | None = None,
) -> Layers:
    """Peel the depth layers of a model and read them back.

    Parameters
    ----------
    model : Model, str or PathLike
        A loaded model or a model file.
    size, view, azimuth, elevation, fov, ortho, up, camera
        Where the camera looks from, as for ``render_frame`` (no plan sheet).
    max_layers : int or None
        Layers to peel at most; None peels until a pass draws nothing.
    min_fraction : float
        Stop once a layer covers fewer than this fraction of layer 0's pixels.
    crease_angle : float
        Degrees: normals are smoothed across smaller angles.
    normals : bool
        Read the layers' normals too; without them ``Layers.normal`` is None.
    renderer : Renderer, optional
        Peel with this renderer instead of the shared one.

    Returns
    -------
    Layers
        depth (L, H, W) float32, triangle and part (L, H, W) int32, normal (L, H, W, 3) float32
        or None, and the view and projection matrices (4, 4) float64.
    """
    model = _as_model(model, up, include, exclude)
    renderer = shared(renderer)
    size = tuple(int(v) for v in size)
    check_size(size, 1, renderer.max_texture)
    cam = _camera(model, size, view, azimuth, elevation, fov, ortho, camera)
    return renderer.peel(
        model,
        cam,
        size=size,
        max_layers=max_layers,
        min_fraction=min_fraction,
        crease_angle=crease_angle,
        normals=normals,
    )
