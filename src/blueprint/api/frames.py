"""Frames: ``render``, ``render_frame`` and ``peel`` on a file or a Model, plan sheets included.

Each takes its options as ``DrawOptions`` (``blueprint.api.options``): a ready value
(``options=``) and its fields as keywords, checked once when the value is made."""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from blueprint.api.options import PLAN, DrawOptions, PartSpec, options_but, takes_options
from blueprint.api.picture import blueprint_frame, smooth_contours_wanted
from blueprint.api.renderer import Renderer
from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.render.renderer import Frame, Layers
from blueprint.scene.camera import SHEET_CELLS, Camera, sheet_cameras
from blueprint.scene.headers import pictures_only
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model
from blueprint.scene.units import UNITS_MM, drawing_unit, warn_if_assumed

if TYPE_CHECKING:
    from blueprint.api.sections import Section

# Sections, glyphs, marks, dimensions and plan sheets are imported where a frame has them: a
# plain drawing's start-up (benchmarks/startup.py) loads none of them.

__all__ = ["PLAN", "PartSpec", "peel", "render", "render_frame"]

# The options of a picture: every one but the vector drawings' own.
FRAME_OPTIONS = options_but("scale", "sheet")


def shared(renderer: Renderer | None) -> Renderer:
    """``renderer``, or the shared one when it is None (``blueprint.api.default_renderer``)."""
    if renderer is not None:
        return renderer
    # looked up when called: the package holds the shared renderer (where callers swap it) and
    # imports this module
    from blueprint.api import default_renderer

    return default_renderer()


def as_model(model: Model | str | os.PathLike, options: DrawOptions, *, pictures: bool = False) -> Model:
    """``model``, or the model file it names loaded with ``options``' ``up``, ``include`` and
    ``exclude``; weighed by the memory guard as a model drawn only as ``pictures`` where so
    (``headers.pictures_only``), else as one a vector drawing may be made of."""
    if isinstance(model, Model):
        return model
    with pictures_only() if pictures else contextlib.nullcontext():
        return load_model(model, up=options.up, include=options.include, exclude=options.exclude)


@takes_options(*FRAME_OPTIONS)
def render_frame(
    model: Model | str | os.PathLike, options: DrawOptions, *, renderer: Renderer | None = None
) -> Frame:
    """Draw the blueprint of a model, as ``render`` does, and return the whole frame.

    Parameters
    ----------
    model : Model, str or PathLike
        A loaded model or a model file.
    options : DrawOptions, optional
        The drawing's options (``blueprint.api.options.DrawOptions``: camera, size, layers,
        style, masking, section, sheet, glyphs). Each of its fields but ``scale`` and
        ``sheet`` (a vector drawing's) is a keyword too, over ``options`` where both are given:
        ``size``, ``view`` (``plan``: a sheet of orthographic top, front and right views at one
        scale plus iso, with a border and a title block), ``style``, ``highlight`` ...
    renderer : Renderer, optional
        Draw with this renderer instead of the shared one.

    Returns
    -------
    Frame
        The (H, W, 4) uint8 image, the layers drawn, the camera and the timings.
    """
    options.raster_style  # noqa: B018 - a line style file a picture cannot take fails before the model loads
    model = as_model(model, options, pictures=True)
    renderer = shared(renderer)
    check_size(options.size, options.supersample, renderer.max_texture)
    # the parts and the style resolved once, for every view and cut of this model
    options = replace(
        options,
        style=options.raster_style,
        grid=None,
        highlight=_parts(model, options.highlight),
        shade=_parts(model, options.shade),
        smooth_contours=smooth_contours_wanted(model, options),
    )
    section = _section_of(model, options)
    if options.view == PLAN and options.camera is None:
        frame = _plan_frame(model, options, renderer, section)
        warn_if_assumed(model, options.units)  # its title block names the unit
        return frame
    if options.title is not None:
        raise InputError("--title names a plan sheet's title block: give --view plan")
    glyphs, dimensions, size = options.glyphs, options.dimensions, options.size
    if glyphs is not None and any(d.edges for d in glyphs.dimensions):
        # the edges are the loaded model's, numbered before any section cuts it
        from blueprint.vector.anchors import anchor_glyphs

        glyphs = anchor_glyphs(glyphs, model)
    measures = dimensions or (glyphs is not None and bool(glyphs.dimensions))
    mm_per_model = UNITS_MM[drawing_unit(model, options.units)]
    margin = 0.05
    if dimensions:
        from blueprint.scene.dimension import dimension_margin
        from blueprint.scene.sheet import picture_per_mm

        # room for the dimensions below and right of the model
        margin = dimension_margin(size, picture_per_mm(size))
    cam = options.fit_camera(model, margin=margin)
    if dimensions and not cam.ortho:
        raise InputError("dimensions need an orthographic view (--ortho, or --view plan)")
    drawn = model
    if section is not None:
        from blueprint.api.sections import render_section

        cut = section.cut(model, cam)
        drawn = cut.model
        frame = render_section(renderer, cut, cam, options)
    else:
        frame = blueprint_frame(renderer, model, cam, options)
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
        marks, _ = _dimensions(drawn, cam, size, mm_per_model, options.crease_angle)
        image = frame.image.copy()
        draw_marks(image, marks, options.style.ink, options.line_width)
        spent = (time.perf_counter() - t0) * 1e3
        frame = replace(
            frame, image=image, ms=frame.ms + spent, stages={**frame.stages, "dimensions": spent}, marks=marks
        )
    if measures:
        warn_if_assumed(model, options.units)
    return frame


def _parts(model: Model, spec: PartSpec | None) -> np.ndarray | None:
    """The parts of ``model`` that ``spec`` designates, (P,) bool, or None."""
    if spec is None:
        return None
    from blueprint.scene.parts import designated_parts

    return designated_parts(model, spec)


def _section_of(model: Model, options: DrawOptions) -> Section | None:
    """``blueprint.api.sections.section_of``, its modules loaded only where a section is asked for."""
    if options.plane is None:
        return None
    from blueprint.api.sections import section_of

    return section_of(model, options)


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
    from blueprint.scene.sheet import picture_per_mm
    from blueprint.vector.dimension import dimension_marks, find_circles

    view, projection = camera.view_matrix(), camera.projection_matrix()
    if circles is None:
        circles = find_circles(model, view, projection, size, crease_angle)
    # on a picture, ISO's measures as its sheet takes them
    mm_per_px = 1.0 / picture_per_mm(sheet_size or size)
    marks = dimension_marks(model, view, projection, size, mm_per_model, mm_per_px, crease_angle, circles)
    return marks, circles


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
        px = cam.to_pixels(used, cell)
        lo = np.clip(np.floor(px.min(axis=0)) - _CROP_PAD, 0, cell)
        hi = np.clip(np.ceil(px.max(axis=0)) + _CROP_PAD, 0, cell)
        boxes[name] = np.array([lo, hi])
    return boxes


def _plan_layout(model: Model, drawn: Model, options: DrawOptions, unit: str, rows: int):
    """The cell size, cameras, crop boxes, dimension marks and layout of a plan sheet ``size``
    pixels large: the views are drawn at one cell size, scaled until, laid out, they fill the
    room the border and title block leave (the gaps, labels and border scale with the cell;
    the title block and the dimensions' measures do not, hence the steps)."""
    from blueprint.scene.sheet import lay_out_sheet

    circles: dict[str, list] = {}
    size, crease_angle = options.size, options.crease_angle

    def attempt(cell):
        cameras = sheet_cameras(model, cell, options.fov)
        boxes = _crop_boxes(drawn, cameras, cell)
        extents = dict(boxes)
        marks = {}
        if options.dimensions:
            for name in ("top", "front", "right"):
                marks[name], circles[name] = _dimensions(
                    drawn, cameras[name], cell, UNITS_MM[unit], crease_angle, circles.get(name), size
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


def _plan_frame(model: Model, options: DrawOptions, renderer: Renderer, section: Section | None) -> Frame:
    """A drawing sheet in third-angle projection: top view above the front view, right view
    beside it, all orthographic at one scale, and an iso view in the free corner, laid out by
    ``blueprint.scene.sheet.lay_out_sheet`` (as the vector sheet is) with their labels, a border
    and a title block; a section cuts the model as the front view sees it, in every view."""
    from blueprint.compose.glyphs.marks import draw_marks
    from blueprint.compose.sheet import over, paper_image
    from blueprint.scene.sheet import Marks, model_name, sheet_fields

    size = options.size
    if size[0] < 2 or size[1] < 2:
        raise InputError(f"size {size[0]}x{size[1]} is too small for a plan sheet (at least 2x2)")
    style = options.style
    cut = None
    if section is not None:
        from blueprint.api.sections import render_section

        front = sheet_cameras(model, (size[0] // 2, size[1] // 2), options.fov)["front"]
        cut = section.cut(model, front)
    drawn = model if cut is None else cut.model
    unit = drawing_unit(model, options.units)
    title = options.title if options.title is not None else model_name(model)
    fields = sheet_fields(title, None, unit, f"{size[0]} x {size[1]} px")
    cell, cameras, boxes, marks, layout = _plan_layout(model, drawn, options, unit, len(fields))

    image = paper_image(style, size)
    frames = {}
    all_marks = [layout.marks(fields)]
    for name in SHEET_CELLS:
        # the views are drawn on no paper and laid over the sheet's, so that its grid runs on
        view = replace(options, size=cell, style=replace(style, paper=None, grid=0.0))
        if cut is not None:
            frames[name] = render_section(renderer, cut, cameras[name], view)
        else:
            frames[name] = blueprint_frame(renderer, model, cameras[name], view)
        (x0, y0), (x1, y1) = boxes[name].astype(int)
        shift = np.round(layout.shifts[name]).astype(int)
        over(image, frames[name].image[y0:y1, x0:x1], x0 + int(shift[0]), y0 + int(shift[1]))
        if name in marks:
            all_marks.append(marks[name].shifted(shift.astype(np.float64)))
    drawn_marks = Marks.concatenate(all_marks)
    draw_marks(image, drawn_marks, style.ink, float(options.line_width))
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


@takes_options(*FRAME_OPTIONS)
def render(
    model: Model | str | os.PathLike, options: DrawOptions, *, renderer: Renderer | None = None
) -> np.ndarray:
    """Draw the blueprint of a model: every visible and hidden edge of every part.

    Takes what ``render_frame`` takes: ``options`` (a ``DrawOptions``) and each of its fields
    as a keyword (``size``, ``view``, ``style``, ``highlight``, ``section`` ...), and
    ``renderer``.

    Returns
    -------
    (H, W, 4) uint8
        RGBA image, row 0 at the top.
    """
    return render_frame(model, options=options, renderer=renderer).image


# what a peel takes of the options: where the camera looks from and how deep it peels
PEEL_OPTIONS = (
    "view", "azimuth", "elevation", "fov", "ortho", "camera", "up", "include", "exclude", "size",
    "max_layers", "min_fraction", "crease_angle",
)  # fmt: skip


@takes_options(*PEEL_OPTIONS, size=(512, 512), max_layers=None)
def peel(
    model: Model | str | os.PathLike,
    options: DrawOptions,
    *,
    normals: bool = True,
    renderer: Renderer | None = None,
) -> Layers:
    """Peel the depth layers of a model and read them back.

    Parameters
    ----------
    model : Model, str or PathLike
        A loaded model or a model file.
    options : DrawOptions, optional
        Where the camera looks from (``size``, default 512 x 512, ``view`` but ``plan``,
        ``azimuth``, ``elevation``, ``fov``, ``ortho``, ``camera``), the model file's ``up``,
        ``include`` and ``exclude``, and how deep to peel: ``max_layers`` (default None: until a
        pass draws nothing), ``min_fraction``, ``crease_angle`` (normals are smoothed across
        smaller angles). Each is a keyword too, over ``options`` where both are given.
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
    model = as_model(model, options, pictures=True)
    renderer = shared(renderer)
    size = check_size(options.size, 1, renderer.max_texture)
    return renderer.peel(
        model,
        options.fit_camera(model),
        size=size,
        max_layers=options.max_layers,
        min_fraction=options.min_fraction,
        crease_angle=options.crease_angle,
        normals=normals,
    )
