"""Frames: ``render``, ``render_frame`` and ``peel`` on a file or a Model, plan sheets included."""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from blueprint.api.renderer import Renderer
from blueprint.compose.sheet import over, paper_image
from blueprint.compose.style import Style, get_style
from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.render.renderer import Frame, Layers
from blueprint.scene.camera import SHEET_CELLS, Camera, fit_camera, sheet_cameras
from blueprint.scene.dimension import UNITS_MM, dimension_margin, screen_points
from blueprint.scene.environment import PartGlobs
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model
from blueprint.scene.parts import designated_parts
from blueprint.scene.sheet import Marks, lay_out_sheet, model_name, picture_per_mm, sheet_fields
from blueprint.scene.units import check_units, drawing_unit, warn_if_assumed

if TYPE_CHECKING:
    from blueprint.api.sections import Section
    from blueprint.compose.glyphs import Glyphs

# Sections, glyphs and marks are imported where a frame has them: a plain drawing's start-up
# (benchmarks/startup.py) loads none of them.

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


def _camera(model: Model, size, view, azimuth, elevation, fov, ortho, camera, margin=0.05) -> Camera | None:
    if camera is not None:
        return camera
    return fit_camera(
        model, size, view, azimuth=azimuth, elevation=elevation, fov=fov, ortho=ortho, margin=margin
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
    dimensions: bool = False,
    units: str | None = None,
    title: str | None = None,
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
        sheet of orthographic top, front and right views at one scale plus iso, labelled and
        laid out with even gaps fitted to their sizes, with a border and a title block.
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
        a surface hides them; ``[[dimension]]`` entries are drawn after ISO 129 on top. Not on a
        plan sheet.
    section : str, optional
        A section view: ``"x=VALUE"`` (or ``y=``, ``z=``, model units) removes the model in front
        of that plane as the camera sees it; the cut faces are hatched, outlined heavy.
    section_plane : str or 6 floats, optional
        A section by any plane: a point of it and a normal towards the side removed
        (``"PX,PY,PZ,NX,NY,NZ"``).
    section_keep : str, int, sequence, Model or (P,) bool, optional
        Parts drawn whole in a section (shafts, bolts, pins).
    dimensions : bool
        Draw the overall width and height of an orthographic view (or of a plan sheet's
        orthographic views) and the diameters of the circles its lines find, after ISO 129,
        in millimetres: the vector drawing's marks and numbers.
    units : str, optional
        The model's length unit (``mm``, ``in``, ``m`` ...), over the one its file states:
        the dimensions' values (glyph file dimensions' too) and a plan sheet's units. Default
        ``Model.unit`` (glTF and STEP: ``m``; 3MF: its own), else ``mm``, with a warning.
    title : str, optional
        A plan sheet's title (default: the model's name).
    profile : bool
        Synchronise after each stage to fill ``Frame.stages`` (slower).
    renderer : Renderer, optional
        Draw with this renderer instead of the shared one.

    Returns
    -------
    Frame
        The (H, W, 4) uint8 image, the layers drawn, the camera and the timings.
    """
    if glyphs is not None:
        glyphs = _glyphs(glyphs)
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
    section_asked = _section_of(model, section, section_plane, section_keep)
    if units is not None:
        check_units(units)
    if view == PLAN and camera is None:
        if glyphs is not None:
            raise InputError("glyphs need one view; the plan sheet draws four")
        sheet = _SheetAsked(dimensions, drawing_unit(model, units), title)
        frame = _plan_frame(model, size, fov, renderer, options, section_asked, sheet)
        warn_if_assumed(model, units)  # its title block names the unit
        return frame
    if title is not None:
        raise InputError("--title names a plan sheet's title block: give --view plan")
    measures = dimensions or (glyphs is not None and bool(glyphs.dimensions))
    mm_per_model = UNITS_MM[drawing_unit(model, units)]
    # room for the dimensions below and right of the model
    margin = dimension_margin(size, picture_per_mm(size)) if dimensions else 0.05
    cam = _camera(model, size, view, azimuth, elevation, fov, ortho, camera, margin)
    if dimensions and not cam.ortho:
        raise InputError("dimensions need an orthographic view (--ortho, or --view plan)")
    drawn = model
    if section_asked is not None:
        from blueprint.api.sections import render_section

        cut = section_asked.cut(model, cam)
        drawn = cut.model
        frame = render_section(renderer, cut, cam, size, options)
    else:
        frame = renderer.render(model, cam, size=size, **options)
    if glyphs is not None:
        from blueprint.compose.glyphs import render_with_glyphs

        t0 = time.perf_counter()
        image = render_with_glyphs(
            renderer, model, frame.camera, size, glyphs, frame.image, mm_per_model=mm_per_model
        )
        spent = (time.perf_counter() - t0) * 1e3
        frame = replace(frame, image=image, ms=frame.ms + spent, stages={**frame.stages, "glyphs": spent})
    if dimensions:
        from blueprint.compose.glyphs.marks import draw_marks

        t0 = time.perf_counter()
        marks, _ = _dimensions(drawn, cam, size, mm_per_model, crease_angle)
        image = frame.image.copy()
        draw_marks(image, marks, chosen.ink, line_width)
        spent = (time.perf_counter() - t0) * 1e3
        frame = replace(
            frame, image=image, ms=frame.ms + spent, stages={**frame.stages, "dimensions": spent}, marks=marks
        )
    if measures:
        warn_if_assumed(model, units)
    return frame


def _glyphs(glyphs: Glyphs | str | os.PathLike) -> Glyphs:
    """``glyphs``, read from its file where it is one."""
    from blueprint.compose.glyphs import Glyphs, load_glyphs

    return glyphs if isinstance(glyphs, Glyphs) else load_glyphs(glyphs)


def _section_of(model: Model, section, section_plane, section_keep) -> Section | None:
    """``blueprint.api.sections.section_of``, its modules loaded only where a section is asked for."""
    if section is None and section_plane is None and section_keep is None:
        return None
    from blueprint.api.sections import section_of

    return section_of(model, section, section_plane, section_keep)


def _dimensions(
    model: Model,
    camera: Camera,
    size,
    mm_per_model: float,
    crease_angle: float,
    circles=None,
    sheet_size=None,
):
    """The dimensions of an orthographic view in its pixels (``Marks``), as the vector drawing
    has them, and the circles its lines find."""
    # the vector lines find the circles; they load only where a drawing has dimensions
    from blueprint.vector.dimension import dimension_marks, find_circles

    view, projection = camera.view_matrix(), camera.projection_matrix()
    if circles is None:
        circles = find_circles(model, view, projection, size, crease_angle)
    # on a picture, ISO's measures as its sheet takes them
    mm_per_px = 1.0 / picture_per_mm(sheet_size or size)
    marks = dimension_marks(model, view, projection, size, mm_per_model, mm_per_px, crease_angle, circles)
    return marks, circles


@dataclass(frozen=True)
class _SheetAsked:
    """What a plan sheet draws beyond its views: dimensions (values in mm from the model's
    ``unit``) and its title (None: the model's name)."""

    dimensions: bool
    unit: str
    title: str | None

    @property
    def mm_per_model(self) -> float:
        return UNITS_MM[self.unit]


# Pixels of paper left around a view's lines where a plan sheet crops its picture: the lines'
# half width and their anti-aliasing.
_CROP_PAD = 3
# A plan sheet's cells grow or shrink until its views fill at least this much of the room the
# border and title block leave them, in so many steps at most.
_FILL = 0.97
_FIT_STEPS = 8


def _crop_boxes(drawn: Model, cameras: dict[str, Camera], cell: tuple[int, int]) -> dict[str, np.ndarray]:
    """Each view's box in its cell's pixels: its model's used vertices projected, a few pixels
    around them, within the cell."""
    used = drawn.positions[np.unique(drawn.faces)].astype(np.float64)
    boxes = {}
    for name, cam in cameras.items():
        px = screen_points(used, cam.view_matrix(), cam.projection_matrix(), cell)
        lo = np.clip(np.floor(px.min(axis=0)) - _CROP_PAD, 0, cell)
        hi = np.clip(np.ceil(px.max(axis=0)) + _CROP_PAD, 0, cell)
        boxes[name] = np.array([lo, hi])
    return boxes


def _plan_layout(
    model: Model, drawn: Model, size, fov: float, sheet: _SheetAsked, rows: int, crease_angle: float
):
    """The cell size, cameras, crop boxes, dimension marks and layout of a plan sheet ``size``
    pixels large: the views are drawn at one cell size, scaled until, laid out, they fill the
    room the border and title block leave (the gaps, labels and border scale with the cell;
    the title block and the dimensions' measures do not, hence the steps)."""
    circles: dict[str, list] = {}

    def attempt(cell):
        cameras = sheet_cameras(model, cell, fov)
        boxes = _crop_boxes(drawn, cameras, cell)
        extents = dict(boxes)
        marks = {}
        if sheet.dimensions:
            for name in ("top", "front", "right"):
                marks[name], circles[name] = _dimensions(
                    drawn, cameras[name], cell, sheet.mm_per_model, crease_angle, circles.get(name), size
                )
                lines = np.concatenate([boxes[name], marks[name].lines.reshape(-1, 2)])
                extents[name] = np.array([lines.min(axis=0), lines.max(axis=0)])
        return cell, cameras, boxes, marks, lay_out_sheet(extents, rows, cell, None, size)

    tried = attempt((max(size[0] // 2, 1), max(size[1] // 2, 1)))
    for _ in range(_FIT_STEPS):
        cell, overflow = tried[0], tried[-1].overflow
        if overflow <= 1.0 and (overflow >= _FILL or cell == tuple(size)):
            break
        # a little under what fits where it does not, at most twice as large where it does
        factor = min((0.99 if overflow > 1.0 else 1.0) / overflow, 2.0)
        scaled = tuple(int(min(max(v * factor, 1), limit)) for v, limit in zip(cell, size, strict=True))
        if scaled == cell:
            break
        tried = attempt(scaled)
    while tried[-1].overflow > 1.0 and min(tried[0]) > 1:
        tried = attempt(tuple(max(int(v * 0.95), 1) for v in tried[0]))
    return tried


def _plan_frame(
    model: Model,
    size: tuple[int, int],
    fov: float,
    renderer: Renderer,
    options,
    section: Section | None,
    sheet: _SheetAsked,
) -> Frame:
    """A drawing sheet in third-angle projection: top view above the front view, right view
    beside it, all orthographic at one scale, and an iso view in the free corner, laid out by
    ``blueprint.scene.sheet.lay_out_sheet`` (as the vector sheet is) with their labels, a border
    and a title block; a section cuts the model as the front view sees it, in every view."""
    from blueprint.compose.glyphs.marks import draw_marks

    if size[0] < 2 or size[1] < 2:
        raise InputError(f"size {size[0]}x{size[1]} is too small for a plan sheet (at least 2x2)")
    style: Style = options["style"]
    cut = None
    if section is not None:
        from blueprint.api.sections import render_section

        front = sheet_cameras(model, (size[0] // 2, size[1] // 2), fov)["front"]
        cut = section.cut(model, front)
    drawn = model if cut is None else cut.model
    title = sheet.title if sheet.title is not None else model_name(model)
    fields = sheet_fields(title, None, sheet.unit, f"{size[0]} x {size[1]} px")
    crease = float(options["crease_angle"])
    cell, cameras, boxes, marks, layout = _plan_layout(model, drawn, size, fov, sheet, len(fields), crease)

    # the views are drawn on no paper and laid over the sheet's, so that its grid runs on
    clear = dict(options, style=replace(style, paper=None, grid=0.0))
    image = paper_image(style, size)
    frames = {}
    all_marks = [layout.marks(fields)]
    for name in SHEET_CELLS:
        if cut is not None:
            frames[name] = render_section(renderer, cut, cameras[name], cell, clear)
        else:
            frames[name] = renderer.render(model, cameras[name], size=cell, **clear)
        (x0, y0), (x1, y1) = boxes[name].astype(int)
        shift = np.round(layout.shifts[name]).astype(int)
        over(image, frames[name].image[y0:y1, x0:x1], x0 + int(shift[0]), y0 + int(shift[1]))
        if name in marks:
            all_marks.append(marks[name].shifted(shift.astype(np.float64)))
    drawn_marks = Marks.concatenate(all_marks)
    draw_marks(image, drawn_marks, style.ink, float(options["line_width"]))
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
        marks=drawn_marks,
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
    dimensions: bool = False,
    units: str | None = None,
    title: str | None = None,
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
    dimensions, units, title : optional
        ISO 129 dimensions of orthographic views, the model's length unit, a plan sheet's
        title (see ``render_frame``).
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
        dimensions=dimensions,
        units=units,
        title=title,
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
