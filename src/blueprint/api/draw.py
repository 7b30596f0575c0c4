"""``draw``: objects of the Python ecosystem in (a file, a trimesh mesh or scene, arrays), a
``Drawing`` out that shows itself in Jupyter and saves to any format by suffix."""

from __future__ import annotations

import logging
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from blueprint.api.frames import PLAN, PartSpec, render_frame, shared
from blueprint.api.renderer import Renderer
from blueprint.compose.style import Style
from blueprint.errors import InputError
from blueprint.render.renderer import Frame
from blueprint.scene.camera import VIEWS, fit_camera
from blueprint.scene.dimension import UNITS_MM, dimension_margin
from blueprint.scene.environment import PartGlobs
from blueprint.scene.loader import load_model, model_from_object
from blueprint.scene.model import Model
from blueprint.scene.sheet import paper_size
from blueprint.scene.units import check_units, drawing_unit, warn_if_assumed

if TYPE_CHECKING:
    from blueprint.compose.glyphs import Glyphs
    from blueprint.export.writers import Kind, Writer

log = logging.getLogger("blueprint")

__all__ = ["Drawing", "draw", "output_writer", "to_model"]

# The options a vector drawing takes; the others are the raster drawing's alone.
_VECTOR_OPTIONS = (
    "size",
    "view",
    "azimuth",
    "elevation",
    "fov",
    "ortho",
    "style",
    "max_layers",
    "crease_angle",
    "line_width",
    "highlight",
    "reveal",
    "glyphs",
    "shade",
    "shade_opacity",
    "units",
    "section",
    "section_plane",
    "section_keep",
    "title",
    "dimensions",
)
_VECTOR_ONLY = ("scale", "sheet")


def output_writer(path: str | os.PathLike, *kinds: Kind) -> tuple[Path, Writer]:
    """The writer of ``path``'s suffix among those that take ``kinds`` (in that order), the path
    checked writable first: how the API and the command line pick every output format
    (``blueprint.export.writers.WRITERS``; also ``blueprint.api.files.choose_writer``). The
    vector drawings' and videos' writers load only for their suffixes.

    Returns the path and its ``blueprint.export.writers.Writer``; raises ``InputError`` in one
    line naming the suffixes allowed where the suffix has none of ``kinds``.
    """
    from blueprint.export.writers import WRITERS

    return WRITERS.choose(path, *kinds)


def to_model(obj, up: str | None = None, include: PartGlobs = None, exclude: PartGlobs = None) -> Model:
    """``obj`` as a ``Model``: a model file's path, a ``Model``, a ``trimesh.Trimesh``, a
    ``trimesh.Scene`` (a part per mesh instance, transforms applied) or ``(vertices, faces)``,
    with the parts ``include`` and ``exclude`` choose (name globs or indices, as ``--include``).

    Raises ``InputError`` with the one-line message the command line would print.
    """
    if isinstance(obj, str | os.PathLike):
        return load_model(obj, up=up, include=include, exclude=exclude)
    return model_from_object(obj, up=up, include=include, exclude=exclude)


class Drawing:
    """A blueprint of a model: the image as a NumPy array (``image``, or ``np.asarray``),
    shown inline by Jupyter, saved to any format by suffix (``save``).

    A vector drawing (``draw(..., vector=True)``) shows as SVG; its raster image is drawn
    when first asked for. Made by :func:`draw`.
    """

    def __init__(self, model: Model, options: dict, vector: bool, renderer: Renderer | None) -> None:
        self.model = model
        self.options = options
        self.vector = vector
        self._renderer = renderer
        self._frame: Frame | None = None
        self._lines = None
        if vector:
            self.lines  # noqa: B018 - drawn now, so that bad options fail in draw() as they would on the CLI
        else:
            self._frame = self.frame

    @property
    def frame(self) -> Frame:
        """The raster frame: image, layers drawn, camera, timings (drawn on first use)."""
        if self._frame is None:
            raster = {k: v for k, v in self.options.items() if k not in _VECTOR_ONLY}
            self._frame = render_frame(self.model, renderer=self._renderer, **raster)
        return self._frame

    @property
    def image(self) -> np.ndarray:
        """(H, W, 4) uint8 RGBA, row 0 at the top."""
        return self.frame.image

    @property
    def layers(self) -> int:
        """Depth layers peeled."""
        return self.lines.layers if self.vector else self.frame.layers

    @property
    def lines(self):
        """The vector drawing (``blueprint.vector.drawing.Drawing``: polylines with their
        occlusion levels and parts), drawn on first use with this drawing's options."""
        if self._lines is None:
            self._lines = vector_drawing(self.model, renderer=self._renderer, **self._vector_options())
        return self._lines

    def _vector_options(self) -> dict:
        keys = _VECTOR_OPTIONS + _VECTOR_ONLY
        return {k: self.options[k] for k in keys if k in self.options}

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        return self.image if dtype is None else self.image.astype(dtype)

    def save(self, path: str | os.PathLike) -> Path:
        """Write the drawing to ``path`` atomically, in the format its suffix names: a picture
        (``.png``) or vector lines (``.svg``, ``.pdf``, ``.dxf``). Returns the path written."""
        from blueprint.export.writers import Kind

        path, write = output_writer(path, Kind.IMAGE, Kind.DRAWING)
        if write.kind is Kind.DRAWING:
            return write(path, self.lines)
        given = [k for k in _VECTOR_ONLY if self.options.get(k) is not None]
        if given:
            verb = "is" if len(given) == 1 else "are"
            raise InputError(f"{path}: {' and '.join(given)} {verb} for vector drawings (.svg, .pdf, .dxf)")
        return write(path, self.image)

    def png(self) -> bytes:
        """The image as PNG bytes (with alpha)."""
        from blueprint.export.files import png_bytes

        return png_bytes(self.image)

    def svg(self) -> str:
        """The vector lines as an SVG document."""
        from blueprint.vector.svg import svg_bytes

        return svg_bytes(self.lines).decode("utf-8")

    def _repr_png_(self) -> bytes | None:
        # a vector drawing shows as SVG alone: Jupyter would otherwise also rasterise it
        return None if self.vector else self.png()

    def _repr_svg_(self) -> str | None:
        return self.svg() if self.vector else None

    def __repr__(self) -> str:
        kind = "vector" if self.vector else "raster"
        size = self.options.get("size", (1024, 1024))
        return (
            f"<Drawing {kind} {size[0]}x{size[1]} of {self.model.source or 'a model'}: "
            f"{self.model.triangle_count} triangles, {len(self.model.part_names)} parts>"
        )


def check_vector_options(style, scale: str | float | None, units: str | None):
    """The ``VectorStyle`` that ``style`` names, with ``scale`` and ``units`` checked: what a
    vector drawing can refuse before any model is read. Raises ``InputError``."""
    from blueprint.vector.drawing import parse_scale
    from blueprint.vector.style import vector_style

    if scale is not None:
        parse_scale(scale)
    if units is not None:
        check_units(units)
    return vector_style(style)


def vector_drawing(
    model: Model,
    *,
    size: tuple[int, int] = (1024, 1024),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    style="blueprint",
    max_layers: int | None = 8,
    crease_angle: float = 30.0,
    line_width: float = 1.0,
    highlight: PartSpec | None = None,
    reveal: float | None = None,
    scale: str | float | None = None,
    units: str | None = None,
    section: str | None = None,
    section_plane: str | Sequence[float] | None = None,
    section_keep=None,
    sheet: str | None = None,
    title: str | None = None,
    dimensions: bool = False,
    glyphs: Glyphs | str | os.PathLike | None = None,
    shade: PartSpec | None = None,
    shade_opacity: float = 1.0,
    renderer: Renderer | None = None,
):
    """The vector lines of ``model`` as ``render_vector_file`` draws them (one view or the
    plan sheet, cut by a section where asked, a glyph file's dimensions added), not written
    anywhere: a ``blueprint.vector.drawing.Drawing``."""
    from blueprint.api.sections import section_of
    from blueprint.gpu.device import check_size
    from blueprint.vector.drawing import draw_vector, draw_vector_sheet

    vstyle = check_vector_options(style, scale, units)
    if scale is not None and not ortho and view != PLAN:
        # one scale across the page needs parallel projection: said, not done silently
        log.warning(
            "--scale %s draws the %s view orthographic (a drawing to scale has no perspective)", scale, view
        )
    ortho = ortho or scale is not None
    renderer = shared(renderer)
    size = check_size(size, 1, renderer.max_texture)
    options = dict(
        style=vstyle,
        max_layers=max_layers or None,
        crease_angle=crease_angle,
        line_width=line_width,
        highlight=highlight,
        reveal=reveal,
        renderer=renderer,
        title=title,
        dimensions=dimensions,
        glyphs=glyphs,
        shade=shade,
        shade_opacity=shade_opacity,
    )
    cut = section_of(model, section, section_plane, section_keep)
    if sheet is not None and view != PLAN:
        raise InputError(f"--sheet {sheet} sets the paper of a plan sheet: give --view plan")
    if glyphs is not None:
        from blueprint.compose.glyphs import Glyphs, load_glyphs  # loaded for drawings with glyphs

        if not isinstance(glyphs, Glyphs):
            glyphs = load_glyphs(glyphs)
    measures = scale is not None or dimensions or sheet is not None
    measures = measures or (glyphs is not None and bool(glyphs.dimensions))
    # the views are given the unit resolved: an assumed one is warned about here alone
    given, units = units, drawing_unit(model, units)
    if view == PLAN:
        if glyphs is not None:
            raise InputError("glyphs need one view; the plan sheet draws four")
        plane = None if cut is None else (cut.plane, cut.keep)
        drawing = draw_vector_sheet(
            model, size, fov=fov, scale=scale, units=units, sheet=sheet, section=plane, **options
        )
        if measures:
            warn_if_assumed(model, given)
        return drawing
    # room for the dimensions below and right of the model
    margin = dimension_margin(size, 96.0 / 25.4) if dimensions else 0.05
    camera = fit_camera(
        model, size, view, azimuth=azimuth, elevation=elevation, fov=fov, ortho=ortho, margin=margin
    )
    if cut is not None:
        made = cut.cut(model, camera)
        drawing = draw_vector(made.model, camera, size, scale=scale, units=units, section=made, **options)
    else:
        drawing = draw_vector(model, camera, size, scale=scale, units=units, **options)
    if glyphs is not None:
        from blueprint.vector.dimension import with_dimension_glyphs

        drawing = with_dimension_glyphs(drawing, glyphs, UNITS_MM[units])
    if measures:
        warn_if_assumed(model, given)
    return drawing


def draw(
    obj,
    *,
    vector: bool = False,
    size: tuple[int, int] = (1024, 1024),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    include: PartGlobs = None,
    exclude: PartGlobs = None,
    style: str | os.PathLike | Style = "blueprint",
    grid: float | None = None,
    max_layers: int | None = 8,
    min_fraction: float = 0.0,
    crease_angle: float = 30.0,
    line_width: float = 1.0,
    supersample: int = 2,
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
    scale: str | float | None = None,
    sheet: str | None = None,
    renderer: Renderer | None = None,
) -> Drawing:
    """Draw the blueprint of ``obj`` and return it as a ``Drawing``.

    Every option of ``blueprint render`` that draws is an argument of the same name
    (``--highlight-model FILE`` is ``highlight=blueprint.load_model(FILE)``).

    Parameters
    ----------
    obj : str, PathLike, Model, trimesh.Trimesh, trimesh.Scene or (vertices, faces)
        A model file, or a model in memory: a scene gives one part per mesh instance, named
        from its node and geometry names, node transforms applied; ``(vertices, faces)`` is a
        (V, 3) float array and a (F, 3) integer array.
    vector : bool
        Draw vector lines (shown as SVG in Jupyter); otherwise a raster image (shown as PNG).
        Either kind saves to every format: ``Drawing.save`` draws the other when needed.
    size : (int, int)
        Width and height in pixels.
    view : str
        ``iso``, ``front``, ``back``, ``left``, ``right``, ``top``, ``bottom``, or ``plan`` (a
        sheet of top, front and right orthographic views and an iso view, with a border and a
        title block).
    azimuth, elevation : float, optional
        Degrees, overriding the view's.
    fov : float
        Vertical field of view in degrees.
    ortho : bool
        Orthographic projection.
    up : {'y', 'z'}, optional
        The model's up axis (default: the file format's, y for objects).
    include, exclude : str or sequence of str and int, optional
        Parts to draw, and parts to leave out: name globs or indices (a string may hold several,
        comma-separated); without ``include``, environment meshes (skyboxes, huge ground planes)
        are left out.
    style : str, PathLike or Style
        ``blueprint``, ``paper``, ``transparent``, ``wireframe``, a ``Style``, or a line style
        file (``.toml``, ``.json``: colour, width, dash and opacity per occlusion level).
    grid : float, optional
        Grid spacing in pixels (0: none), overriding the style's.
    max_layers : int or None
        Depth layers to peel at most; None peels all.
    min_fraction : float
        Stop once a layer covers less than this fraction of the first layer's pixels.
    crease_angle : float
        Degrees: sharper edges are drawn as creases.
    line_width : float
        Line width in pixels, in [1, 16].
    supersample : int
        Edges are computed at this multiple of ``size`` (1-4).
    id_silhouettes : bool
        Also draw triangle-ID silhouettes.
    highlight : str, int, sequence, Model or (P,) bool, optional
        Parts outlined in the highlight ink: name globs and indices, or a second model lying on them.
    reveal : float, optional
        Depth masking: peel until this fraction of the highlighted parts shows.
    shade : str, int, sequence, Model or (P,) bool, optional
        Parts drawn shaded inside the drawing (in vectors: filled polygons in depth order).
    shade_opacity : float
        Opacity of the shading, in (0, 1].
    glyphs : Glyphs, str or PathLike, optional
        Boxes, arrows, paths, labels and dimensions in model coordinates (in vectors: dashed or
        dimmed where hidden). Not on a plan sheet.
    section : str, optional
        A section view: ``"x=VALUE"`` (or ``y=``, ``z=``, model units) removes the model in front
        of that plane as the camera sees it; cut faces are hatched and outlined heavy.
    section_plane : str or 6 floats, optional
        A section by any plane: a point of it and a normal towards the side removed
        (``"PX,PY,PZ,NX,NY,NZ"``).
    section_keep : str, int, sequence, Model or (P,) bool, optional
        Parts drawn whole in a section (shafts, bolts, pins).
    dimensions : bool
        Overall width and height and circle diameters of an orthographic view (or of a plan
        sheet's orthographic views), after ISO 129, in millimetres.
    units : str, optional
        The model's length unit (``mm``, ``in``, ``m`` ...), over the one its file states:
        for dimensions, ``scale`` and a plan sheet's title block. Default ``Model.unit``
        (glTF and STEP: ``m``; 3MF: its own), else ``mm``, with a warning.
    title : str, optional
        A plan sheet's title (default: the model's name).
    scale : str or float, optional
        ``'1:50'``: a vector page laid out in millimetres, orthographic. Vector drawings only.
    sheet : str, optional
        ``A4`` ... ``A0`` (landscape): the paper of a vector plan sheet, the scale fitted to it
        unless ``scale`` is given. Vector drawings only.
    renderer : Renderer, optional
        Draw with this renderer instead of the shared one.

    Returns
    -------
    Drawing

    Raises
    ------
    InputError
        A file or object that cannot be drawn (a point cloud, an empty scene, NaN vertices),
        or bad options: the one-line message the command line prints.
    """
    views = (*VIEWS, PLAN)
    if view not in views:
        raise InputError(f"unknown view {view!r} (choose {', '.join(views)})")
    if sheet is not None:
        # a raster drawing draws its sheet only when saved as vectors: refused now all the same
        paper_size(sheet)
        if view != PLAN:
            raise InputError(f"--sheet {sheet} sets the paper of a plan sheet: give --view plan")
    if scale is not None and not vector:
        check_vector_options("blueprint", scale, None)
    model = to_model(obj, up, include, exclude)
    options = dict(
        size=tuple(int(v) for v in size),
        view=view,
        azimuth=azimuth,
        elevation=elevation,
        fov=fov,
        ortho=ortho,
        style=style,
        grid=grid,
        max_layers=max_layers or None,
        min_fraction=min_fraction,
        crease_angle=crease_angle,
        line_width=line_width,
        supersample=supersample,
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
        scale=scale,
        sheet=sheet,
    )
    return Drawing(model, options, vector, renderer)
