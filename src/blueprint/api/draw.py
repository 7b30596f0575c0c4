"""``draw``: objects of the Python ecosystem in (a file, a trimesh mesh or scene, arrays), a
``Drawing`` out that shows itself in Jupyter and saves to any format by suffix."""

from __future__ import annotations

import logging
import os
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from blueprint.api.frames import render_frame, shared
from blueprint.api.options import PLAN, DrawOptions, options_but, takes_options, zero_layers_are_all
from blueprint.api.renderer import Renderer
from blueprint.errors import InputError
from blueprint.render.renderer import Frame
from blueprint.scene.environment import PartGlobs
from blueprint.scene.loader import load_model, model_from_object
from blueprint.scene.model import Model
from blueprint.scene.units import UNITS_MM, drawing_unit, warn_if_assumed

if TYPE_CHECKING:
    from blueprint.export.writers import Kind, Writer

log = logging.getLogger("blueprint")

__all__ = ["Drawing", "draw", "output_writer", "to_model", "vector_drawing"]

# The options a vector drawing alone takes: a picture refuses them when saved.
_VECTOR_ONLY = ("scale", "sheet")
# The options ``draw`` takes: every one but a ready camera and the picture's edge tuning.
DRAW_OPTIONS = options_but("camera", "depth_threshold", "part_edges", "profile")


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

    def __init__(self, model: Model, options: DrawOptions, vector: bool, renderer: Renderer | None) -> None:
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
            self._frame = render_frame(self.model, options=self.options, renderer=self._renderer)
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
        """The vector drawing (``blueprint.vector.VectorDrawing``: polylines with their parts,
        kinds, occlusion levels and source edges, as arrays in its ``lines``, a
        ``blueprint.Lines``), drawn on first use with this drawing's options."""
        if self._lines is None:
            self._lines = vector_drawing(self.model, self.options, shared(self._renderer))
        return self._lines

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        return self.image if dtype is None else self.image.astype(dtype)

    def save(self, path: str | os.PathLike) -> Path:
        """Write the drawing to ``path`` atomically, in the format its suffix names: a picture
        (``.png``) or vector lines (``.svg``, ``.pdf``, ``.dxf``). Returns the path written."""
        from blueprint.export.writers import Kind

        path, write = output_writer(path, Kind.IMAGE, Kind.DRAWING)
        if write.kind is Kind.DRAWING:
            return write(path, self.lines)
        given = [k for k in _VECTOR_ONLY if getattr(self.options, k) is not None]
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
        size = self.options.size
        return (
            f"<Drawing {kind} {size[0]}x{size[1]} of {self.model.source or 'a model'}: "
            f"{self.model.triangle_count} triangles, {len(self.model.part_names)} parts>"
        )


def vector_drawing(model: Model, options: DrawOptions, renderer: Renderer):
    """The vector lines of ``model`` as ``render_vector_file`` draws them (one view or the
    plan sheet, cut by a section where asked, a glyph file's dimensions added), not written
    anywhere: a ``blueprint.vector.drawing.Drawing``."""
    from blueprint.api.sections import section_of
    from blueprint.gpu.device import check_size
    from blueprint.vector.drawing import VectorOptions, draw_lines, draw_sheet

    scale, view = options.scale, options.view
    if scale is not None and not options.ortho:
        if view != PLAN:
            # one scale across the page needs parallel projection: said, not done silently
            said = "--scale %s draws the %s view orthographic (a drawing to scale has no perspective)"
            log.warning(said, scale, view)
        options = replace(options, ortho=True, style=options.vector_style)
    size = check_size(options.size, 1, renderer.max_texture)
    # the views are given the unit resolved: an assumed one is warned about here alone
    units = drawing_unit(model, options.units)
    lines = VectorOptions(
        view=view,
        style=options.vector_style,
        max_layers=options.max_layers,
        crease_angle=options.crease_angle,
        line_width=options.line_width,
        scale=scale,
        units=units,
        highlight=options.highlight,
        reveal=options.reveal,
        title=options.title,
        dimensions=options.dimensions,
        glyphs=options.glyphs,
        shade=options.shade,
        shade_opacity=options.shade_opacity,
    )
    cut = section_of(model, options)
    glyphs = options.glyphs
    if glyphs is not None and any(d.edges for d in glyphs.dimensions):
        # the edges are the loaded model's, numbered before any section cuts it
        from blueprint.vector.anchors import anchor_glyphs

        glyphs = anchor_glyphs(glyphs, model)
    measures = scale is not None or options.dimensions or options.sheet is not None
    measures = measures or (glyphs is not None and bool(glyphs.dimensions))
    if view == PLAN:
        plane = None if cut is None else (cut.plane, cut.keep)
        drawing = draw_sheet(
            model, size, renderer, lines, fov=options.fov, sheet=options.sheet, section=plane
        )
        if measures:
            warn_if_assumed(model, options.units)
        return drawing
    margin = 0.05
    if options.dimensions:
        # the dimensions' module loads with the drawings that have them
        from blueprint.scene.dimension import dimension_margin

        # room for the dimensions below and right of the model
        margin = dimension_margin(size, 96.0 / 25.4)
    camera = options.fit_camera(model, size, margin=margin)
    if cut is not None:
        made = cut.cut(model, camera)
        drawing = draw_lines(made.model, camera, size, renderer, replace(lines, section=made))
    else:
        drawing = draw_lines(model, camera, size, renderer, lines)
    if glyphs is not None:
        from blueprint.vector.dimension import with_dimension_glyphs

        drawing = with_dimension_glyphs(drawing, glyphs, UNITS_MM[units])
    if measures:
        warn_if_assumed(model, options.units)
    return drawing


@takes_options(*DRAW_OPTIONS, prepare=zero_layers_are_all)
def draw(obj, options: DrawOptions, *, vector: bool = False, renderer: Renderer | None = None) -> Drawing:
    """Draw the blueprint of ``obj`` and return it as a ``Drawing``.

    Every option of ``blueprint render`` that draws is an argument of the same name
    (``--highlight-model FILE`` is ``highlight=blueprint.load_model(FILE)``).

    Parameters
    ----------
    obj : str, PathLike, Model, trimesh.Trimesh, trimesh.Scene or (vertices, faces)
        A model file, or a model in memory: a scene gives one part per mesh instance, named
        from its node and geometry names, node transforms applied; ``(vertices, faces)`` is a
        (V, 3) float array and a (F, 3) integer array.
    options : DrawOptions, optional
        The drawing's options (``blueprint.api.options.DrawOptions``); each of its fields but
        ``camera``, ``depth_threshold``, ``part_edges`` and ``profile`` is a keyword too, over
        ``options`` where both are given: ``size``, ``view`` (``plan``: a sheet of top, front
        and right orthographic views and an iso view, with a border and a title block),
        ``style`` (a name, a ``Style`` or a line style file), ``max_layers`` (0 or None: all),
        ``highlight``, ``shade``, ``section``, ``dimensions``, ``glyphs`` ...; ``scale`` and
        ``sheet`` are for vector drawings only.
    vector : bool
        Draw vector lines (shown as SVG in Jupyter); otherwise a raster image (shown as PNG).
        Either kind saves to every format: ``Drawing.save`` draws the other when needed.
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
    model = to_model(obj, options.up, options.include, options.exclude)
    return Drawing(model, options, vector, renderer)
