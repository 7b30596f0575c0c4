"""Vector drawings: object-space lines, occlusion levels from peeled layers, files.

``draw_vector`` builds a :class:`VectorDrawing` (2D polylines in pixels, each with its part and its
occlusion level); ``save_drawing`` writes it as SVG, PDF or DXF. The whole way from a model file
to a drawing file is ``blueprint.api.files.render_vector_file``.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from blueprint import parallel, settings
from blueprint.blas import one_blas_thread
from blueprint.compose.hatch import hatch_spacing_px
from blueprint.compose.style import STYLES, Style
from blueprint.errors import InputError
from blueprint.export.files import atomic_write
from blueprint.export.writers import WRITERS, Kind, Writers
from blueprint.gpu.device import check_size
from blueprint.gpu.tables import table_rows
from blueprint.render.gbuffer import depth_tolerance
from blueprint.render.renderer import LayerRenderer, Layers
from blueprint.scene.camera import SHEET_CELLS, Camera, fit_camera, sheet_cameras
from blueprint.scene.dimension import UNITS_MM
from blueprint.scene.model import Model
from blueprint.scene.parts import designated_parts
from blueprint.scene.section import Cut, SectionPlane, cut_model
from blueprint.scene.sheet import (
    BORDER_MM,
    LABEL_MM,
    TEXT_MM,
    Marks,
    fit_scale,
    lay_out_sheet,
    model_name,
    paper_size,
    parse_scale,
    sheet_fields,
)
from blueprint.scene.units import drawing_unit, warn_if_assumed

from .chain import chain_pieces, walked
from .dxf import write_dxf
from .instanced import face_parts, placing_weighed
from .lines import grazing_band, join_polylines, model_segments
from .linework import KINDS, Lines, runs_of
from .occlusion import (
    DepthTest,
    GpuLevels,
    PixelLayers,
    classify_samples,
    draw_faces,
    drop_phantoms,
    face_planes,
    gpu_levels,
    probe_pixels,
    sample_polylines,
    split_by_level,
    stack_levels,
    verify_creases,
)
from .occlusion.gpu import MAX_LAYERS
from .pdf import pdf_bytes
from .section import SectionLines, section_lines
from .shade import ShadedFaces, shaded_faces
from .simplify import douglas_peucker
from .style import VectorStyle, vector_style
from .svg import svg_bytes

if TYPE_CHECKING:
    from blueprint.compose.glyphs import Glyphs

    from .glyphs import GlyphLines

log = logging.getLogger("blueprint")

__all__ = [
    "FORMATS",
    "UNITS_MM",
    "Occlusion",
    "VectorDrawing",
    "Page",
    "VectorOptions",
    "ViewFrame",
    "draw_lines",
    "draw_sheet",
    "draw_vector",
    "draw_vector_sheet",
    "parse_scale",
    "save_drawing",
]

# Pen width of the base line on a drawing to scale, in paper millimetres (ISO 128 0.25 mm).
SCALED_PEN_MM = 0.25
# Hatch line spacing of a section on a drawing to scale, in paper millimetres (ISO 128-50).
SECTION_HATCH_MM = 2.5
# Polylines shorter than this on screen (edges seen end-on) are left out.
_MIN_LENGTH_PX = 0.05


@dataclass(frozen=True)
class Page:
    """Where pixels land on the page: ``page = pixel * factor`` in ``unit`` ('px' or 'mm').

    ``scale`` is the denominator of a drawing to scale (1:scale), ``model_unit`` the length
    unit of the model then; both ``None`` for a drawing in pixels.
    """

    width: float
    height: float
    unit: str = "px"
    factor: float = 1.0
    scale: float | None = None
    model_unit: str | None = None

    @property
    def scale_label(self) -> str | None:
        if self.scale is None:
            return None
        return f"1:{self.scale:g}" if self.scale >= 1 else f"{1 / self.scale:g}:1"


@dataclass
class VectorDrawing:
    """A vector drawing of one view.

    Attributes
    ----------
    width, height : int
        Image size in pixels; line coordinates are pixels (x right, y down, origin top-left).
    lines : Lines
        The polylines, each with its part, kind, occlusion level and source edges (the model's
        edges it was drawn from, rows of ``lines.edge_numbers``); ``points``, ``offsets``,
        ``part``, ``kind`` and ``level`` are its arrays.
    part_names : tuple of str
    layers : int
        Depth layers peeled: levels up to ``layers - 1`` are drawn.
    style : VectorStyle
    line_width : float
        Base line width: pixels, or multiples of 0.25 mm on a drawing to scale.
    page : Page
    highlight : frozenset of int
        Parts drawn in the highlight style.
    title : str or None
        Title line written under the drawing's lines (bottom left), if any.
    section : SectionLines or None
        A section's hatching and cut outline, drawn as their own group.
    marks : Marks or None
        A sheet's border, title block and view labels, drawn as their own group.
    glyphs : GlyphLines or None
        Boxes, arrows, paths and labels, drawn as their own group over the lines.
    shading : ShadedFaces or None
        Shaded parts' faces, filled back to front after the lines behind them (``lines.behind``).
    camera : Camera
    seconds : dict
        Time per stage.
    """

    width: int
    height: int
    lines: Lines
    part_names: tuple[str, ...]
    layers: int
    style: VectorStyle
    line_width: float
    page: Page
    camera: Camera
    highlight: frozenset[int] = frozenset()
    title: str | None = None
    section: SectionLines | None = None
    marks: Marks | None = None
    glyphs: GlyphLines | None = None
    shading: ShadedFaces | None = None
    name: str = "drawing"
    seconds: dict[str, float] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.lines)

    @property
    def points(self) -> np.ndarray:
        """(N, 2) float64: all polylines' points."""
        return self.lines.points

    @property
    def offsets(self) -> np.ndarray:
        """(P + 1,) int64: polyline ``i`` is ``points[offsets[i]:offsets[i + 1]]``."""
        return self.lines.offsets

    @property
    def part(self) -> np.ndarray:
        """(P,) int32: part index of each polyline (into ``part_names``)."""
        return self.lines.part

    @property
    def kind(self) -> np.ndarray:
        """(P,) uint8: kind code of each polyline (``linework.KINDS`` names them)."""
        return self.lines.kind

    @property
    def level(self) -> np.ndarray:
        """(P,) int32: occlusion level of each polyline, how many surfaces lie in front of it."""
        return self.lines.level

    @property
    def behind(self) -> np.ndarray | None:
        """With shading, (P,) bool: the polylines behind a shaded part's surface."""
        return self.lines.behind if self.shading is not None else None

    def lines_per_level(self) -> dict[int, int]:
        """Polylines per occlusion level."""
        levels, counts = np.unique(self.level, return_counts=True)
        return {int(k): int(c) for k, c in zip(levels, counts, strict=True)}

    def lines_per_kind(self) -> dict[str, int]:
        """Polylines per kind, by name."""
        counts = np.bincount(self.kind, minlength=len(KINDS))
        return {KINDS[k]: int(counts[k]) for k in np.flatnonzero(counts).tolist()}

    def groups(self, behind: bool | None = None) -> Iterable[tuple[int, int, int, np.ndarray]]:
        """(part, kind, level, polyline indices) in drawing order: parts in model order, within
        a part the deepest level first so that visible lines lie on top, and within a level
        the kinds by code. ``behind`` True or False keeps only the polylines behind the shading
        or only the others."""
        if len(self) == 0:
            return
        order = np.lexsort((self.kind, -self.level, self.part))
        if behind is not None:
            flags = self.behind if self.behind is not None else np.zeros(len(self), bool)
            order = order[flags[order] == behind]
            if len(order) == 0:
                return
        key = np.stack([self.part[order], self.level[order], self.kind[order]], axis=1)
        cut = np.flatnonzero(np.any(key[1:] != key[:-1], axis=1)) + 1
        # each run's part, kind and level as Python numbers at once: a drawing of many parts has
        # hundreds of thousands of runs
        first = order[np.r_[0, cut]]
        parts, kinds, levels = (values[first].tolist() for values in (self.part, self.kind, self.level))
        # views cut by slicing: np.split's machinery takes microseconds a run
        bounds = np.r_[0, cut, len(order)].tolist()
        runs = (order[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True))
        yield from zip(parts, kinds, levels, runs, strict=True)

    def polyline(self, i: int) -> np.ndarray:
        return self.lines.polyline(i)

    def page_width(self) -> float:
        """Base line width in page units."""
        return self.line_width * (SCALED_PEN_MM if self.page.unit == "mm" else 1.0)


def _page(size, camera: Camera, scale, units: str | None, model: Model) -> Page:
    w, h = size
    denominator = parse_scale(scale)
    if denominator is None:
        return Page(float(w), float(h))
    if not camera.ortho:
        raise InputError("a drawing to scale needs an orthographic view (ortho=True)")
    unit = drawing_unit(model, units)
    model_per_px = camera.height / h
    factor = model_per_px * UNITS_MM[unit] / denominator
    page = Page(w * factor, h * factor, "mm", factor, denominator, unit)
    if max(page.width, page.height) > 2000 or max(page.width, page.height) < 20:
        log.warning(
            "the page is %.4g x %.4g mm at %s with the model in %s: check the scale and units",
            page.width,
            page.height,
            page.scale_label,
            unit,
        )
    return page


def _revealing_layers(renderer, model, camera, size, chosen, reveal, max_layers) -> int:
    """How many layers the renderer's depth masking peels to uncover ``reveal`` of the parts."""
    if not chosen:
        raise InputError("reveal needs parts to reveal: give highlight as well")
    from blueprint.pipeline.blueprint import render_blueprint  # depth masking only: loaded here

    flags = np.zeros(len(model.part_names), bool)
    flags[sorted(chosen)] = True
    frame = render_blueprint(
        renderer,
        model,
        camera,
        size=size,
        supersample=1,
        max_layers=max_layers,
        highlight=flags,
        reveal=reveal,
    )
    return max(frame.layers, 1)


def _highlight(highlight, model: Model) -> frozenset[int]:
    """Part indices from a part spec (globs, names, indices, a second model, or flags)."""
    if highlight is None:
        return frozenset()
    if isinstance(highlight, int | np.integer):
        highlight = [int(highlight)]
    elif isinstance(highlight, set | frozenset):
        highlight = sorted(highlight)
    return frozenset(int(i) for i in np.flatnonzero(designated_parts(model, highlight)))


@dataclass(frozen=True)
class VectorOptions:
    """What a vector drawing of one view draws: ``draw_vector``'s options (see there), as one
    value. ``checked()`` checks the ones a caller gives ``draw_vector``; the API's
    ``DrawOptions`` has checked its own where it makes one (``blueprint.api.draw``)."""

    view: str = "iso"
    style: str | Style | VectorStyle = "blueprint"
    max_layers: int | None = 8
    crease_angle: float = 30.0
    line_width: float = 1.0
    scale: str | float | None = None
    units: str | None = None
    highlight: Iterable[str | int] | str | int | Model | None = None
    reveal: float | None = None
    intersections: bool = True
    spacing: float = 1.0
    tolerance: float = 0.25
    title: str | None = None
    section: Cut | None = None
    dimensions: bool = False
    glyphs: Glyphs | str | os.PathLike | None = None
    shade: Iterable[str | int] | str | int | Model | None = None
    shade_opacity: float = 1.0

    def checked(self) -> VectorOptions:
        """These options, their ranges checked; raises ``InputError`` naming the argument."""
        if not 0.0 < self.shade_opacity <= 1.0:
            raise InputError(f"shade_opacity must be in (0, 1], got {self.shade_opacity}")
        if not (0.1 <= self.spacing <= 16):
            raise InputError(f"spacing must be in [0.1, 16] pixels, got {self.spacing}")
        if not (0 <= self.tolerance <= 16):
            raise InputError(f"tolerance must be in [0, 16] pixels, got {self.tolerance}")
        if not 1.0 <= self.line_width <= 16.0:
            raise InputError(f"line_width must be in [1, 16] pixels, got {self.line_width}")
        if self.reveal is not None and not 0.0 < self.reveal <= 1.0:
            raise InputError(f"reveal must be in (0, 1], got {self.reveal}")
        return self


@one_blas_thread
def draw_vector(
    model: Model,
    camera: Camera | None = None,
    size: tuple[int, int] = (1024, 1024),
    *,
    renderer: LayerRenderer,
    layers: Layers | None = None,
    **options,
) -> VectorDrawing:
    """Draw the visible and hidden lines of a model as vectors, each with its occlusion level.

    ``options`` are the fields of ``VectorOptions`` as keywords, checked.

    Parameters
    ----------
    model : Model
    camera : Camera, optional
        Defaults to ``fit_camera`` from ``view`` at the image's size.
    size : (int, int)
        Width and height in pixels: the resolution at which occlusion is decided.
    style : str, Style or VectorStyle
        A raster style's name or object (its inks become level styles) or a ``VectorStyle``.
    max_layers : int or None
        Depth layers to peel; lines behind more surfaces than that are left out.
    crease_angle : float
        Degrees: edges whose faces meet at a sharper angle are drawn as creases.
    line_width : float
        Base line width, pixels (or multiples of 0.25 mm on a drawing to scale).
    scale, units : optional
        '1:50' and the model's length unit ('mm', 'm', ...; default ``model.unit``, else 'mm'):
        the page is laid out in millimetres at that scale. Needs an orthographic camera.
    highlight : part name globs, indices, a second Model or (P,) bool, optional
        Parts drawn in the style's highlight colour.
    reveal : float, optional
        Depth masking: peel only until this fraction of the highlighted parts is uncovered (as
        ``Renderer.render`` does), so lines behind more surfaces than that are left out.
    renderer : LayerRenderer
        Peels the layers (unless ``layers`` are given).
    layers : Layers, optional
        Layers already peeled for this camera and size (skips peeling).
    intersections : bool
        Draw the lines where parts cut through each other.
    spacing : float
        Pixels between occlusion samples along a line.
    tolerance : float
        Douglas–Peucker tolerance in pixels.
    title : str, optional
        A title line; drawings to scale get "<model> — <view> — 1:50 (mm)" by default.
    section : Cut, optional
        The cut that made ``model`` (``blueprint.scene.section.cut_model``): its cut faces are
        hatched (2.5 mm apart on a drawing to scale) and outlined heavy.
    dimensions : bool
        Draw the view's overall width and height (ISO 129, values in mm); orthographic views only.
    glyphs : Glyphs, str or PathLike, optional
        Boxes, arrows, paths and labels in model coordinates (a ``Glyphs`` or a glyph file, see
        ``blueprint.compose.glyphs``), drawn over the lines; their stretches behind the model's
        front surface are their own polylines, drawn as the glyphs' ``[hidden]`` mode says.
    shade : part name globs, indices, a second Model or (P,) bool, optional
        Parts drawn shaded: their faces as filled polygons, lit as the raster lights them, in
        depth order; the lines behind their surfaces are drawn before them, the rest after.
    shade_opacity : float
        Opacity of the shading, in (0, 1]: 1 hides the lines behind the shaded parts.
    """
    return draw_lines(model, camera, size, renderer, VectorOptions(**options).checked(), layers)


def draw_lines(
    model: Model,
    camera: Camera | None,
    size: tuple[int, int],
    renderer: LayerRenderer,
    options: VectorOptions,
    layers: Layers | None = None,
) -> VectorDrawing:
    """``draw_vector`` with its options as one value, checked already."""
    seconds: dict[str, float] = {}
    shaded_parts = None if options.shade is None else designated_parts(model, options.shade)
    glyphs = options.glyphs
    if glyphs is not None:
        # glyphs and dimensions load with the drawings that have them, not with every drawing
        from blueprint.compose.glyphs import Glyphs, load_glyphs

        if not isinstance(glyphs, Glyphs):
            glyphs = load_glyphs(glyphs)
    vstyle = vector_style(options.style)
    chosen = _highlight(options.highlight, model)
    frame = _frame(model, camera, size, renderer, options, layers, chosen)
    camera, size = frame.camera, frame.size
    if _placed_lines(model):
        _weighed(model, size)  # its drawn triangles, before any line is found
    page = _page(size, camera, options.scale, options.units, model)

    drawn = None
    if layers is None:
        _size_frame(renderer, model, frame)
        # the faces k-buffer drawn by the driver while the lines are found (its time is the peel's)
        drawn = draw_faces(renderer, model, camera, size, frame.max_layers)
    samples, line_part, planes, clock = _sampled_lines(model, frame, options, renderer, seconds)
    occlusion = Occlusion(renderer, model, frame, samples, planes, options.crease_angle, layers, drawn)
    levels, count = occlusion.levels(clock, seconds)
    behind = None
    if shaded_parts is not None:
        # the same count of surfaces in front, of the shaded parts' surfaces alone
        only_shaded = planes.copy()
        only_shaded[:-1][~shaded_parts[face_parts(model)]] = 0.0
        behind = occlusion.in_front(only_shaded) > 0
    ahead = occlusion.ahead
    # the faces' planes, the layers read back and the directions across lines: occlusion's alone
    del occlusion, planes
    samples.forget_across()
    pieces = split_by_level(samples, levels, line_part, max(count - 1, 0), behind=behind, renderer=renderer)
    pieces = _chained(pieces, count)
    seconds["occlusion"] = time.perf_counter() - clock - (seconds["peel"] - ahead)

    clock = time.perf_counter()
    pieces = _simplified(pieces, options.tolerance)
    seconds["simplify"] = time.perf_counter() - clock

    hatching = _hatching(frame, options, page)
    marks = _dimension_marks(model, frame, options, page)
    shading = None
    if shaded_parts is not None:
        faces = np.flatnonzero(shaded_parts[face_parts(model)])
        color = _shade_color(options.style)
        shading = shaded_faces(model, faces, frame.view, frame.projection, size, color, options.shade_opacity)
    glyph_drawing = None if glyphs is None else _glyph_lines(glyphs, model, frame, renderer, layers, seconds)
    if page.scale is not None or options.dimensions:
        warn_if_assumed(model, options.units)
    return VectorDrawing(
        width=size[0],
        height=size[1],
        lines=pieces,
        part_names=tuple(model.part_names),
        layers=count,
        style=vstyle,
        line_width=float(options.line_width),
        page=page,
        camera=camera,
        highlight=chosen,
        title=_title(options.title, model, camera, page),
        section=hatching,
        marks=marks,
        glyphs=glyph_drawing,
        shading=shading,
        name=Path(model.source).stem if model.source else "drawing",
        seconds=seconds,
    )


@dataclass(frozen=True)
class ViewFrame:
    """A vector drawing's camera and size (width, height) in pixels, its (4, 4) float64 view
    and projection matrices, and the layers it peels at most."""

    camera: Camera
    size: tuple[int, int]
    view: np.ndarray
    projection: np.ndarray
    max_layers: int | None

    @property
    def ortho(self) -> bool:
        return bool(np.isclose(self.projection[3, 3], 1.0))


def _sampled_lines(model: Model, frame: ViewFrame, options: VectorOptions, renderer, seconds: dict):
    """A drawing's lines found, joined and sampled, each step weighed against the memory budget
    before it holds its arrays (``_weighed``), its seconds into ``seconds["lines"]``: (the
    samples, each polyline's part, the faces' planes, the clock of occlusion's start)."""
    size = frame.size
    clock = time.perf_counter()
    # the intersections and the faces' planes read every corner of a flat model; a model kept
    # as instances places its meshes' instead (``instanced``)
    # told the segments placed so far as they are placed, then the samples before they are made
    placing = partial(_weighed, model, size)
    with model.holding_corners() if model.instances is None else placing_weighed(placing):
        segments = model_segments(
            model, frame.view, frame.projection, size, options.crease_angle, options.intersections, renderer
        )
        if _placed_lines(model):
            # all of them once more: intersections kept from an earlier drawing of the same
            # model are not placed again, so not counted as they are placed
            placing(len(segments))
        # the faces' planes found beside the joining, whose chain walk holds one core
        planes_found = parallel.begin(face_planes, model, frame.view)
        lines = join_polylines(segments)
        del segments  # a big assembly's placed segments: hundreds of megabytes
        weigh = partial(_weighed, model, size, 0)
        samples = sample_polylines(lines, frame.view, frame.projection, size, options.spacing, weigh)
        # the occlusion reads the samples alone, and the pieces each polyline's part
        line_part = lines.part
        del lines
        seconds["lines"] = time.perf_counter() - clock
        clock = time.perf_counter()
        planes = planes_found()
    return samples, line_part, planes, clock


def _placed_lines(model: Model) -> bool:
    """Whether ``model``'s lines are found once a mesh and placed an instance at a time
    (``instanced``): a model kept as instances."""
    return model.instances is not None


def _weighed(model: Model, size, segments: int = 0, samples: int = 0) -> None:
    """Refuse in one line a vector drawing of ``model`` at ``size`` whose drawn triangles, with
    the line ``segments`` placed and the ``samples`` made, pass the memory budget. A flat
    model's triangles weigh ``settings.TRIANGLE_BYTES`` each, its lines with them (its header
    was weighed so); a model kept as instances, whose lines are found once a mesh and placed an
    instance at a time, ``settings.PLACED_TRIANGLE_BYTES`` and each placed segment
    ``settings.SEGMENT_BYTES``. Samples, which follow the lines' length in pixels, not the
    triangles, weigh ``settings.SAMPLE_BYTES`` (the segments are let go by then)."""
    triangles = model.triangle_count
    rate = settings.PLACED_TRIANGLE_BYTES if _placed_lines(model) else settings.TRIANGLE_BYTES
    estimate = triangles * rate + segments * settings.SEGMENT_BYTES + samples * settings.SAMPLE_BYTES
    if estimate <= settings.MEMORY_BUDGET:
        return
    counts, rates = [f"{triangles} triangles"], [f"{rate} bytes a triangle"]
    if segments:
        counts.append(f"{segments} line segments placed so far")
        rates.append(f"{settings.SEGMENT_BYTES} a segment")
    if samples:
        counts.append(f"{samples} line samples")
        rates.append(f"{settings.SAMPLE_BYTES} a sample")
    smaller = "a smaller size takes fewer samples; " if samples else ""
    raise InputError(
        f"{model.source or 'the model'} as a vector drawing of {size[0]} x {size[1]} pixels: "
        f"{' and '.join(counts)} need about {settings.human_size(estimate)} of memory at "
        f"{' and '.join(rates)}, more than the memory budget of "
        f"{settings.human_size(settings.MEMORY_BUDGET)} ({smaller}{settings.MEMORY_ENV} sets the budget)"
    )


def _frame(model, camera, size, renderer, options: VectorOptions, layers, chosen) -> ViewFrame:
    """The frame of a drawing: from the camera (fitted from ``options.view`` where None) at
    ``size``, its layer cap found by depth masking where ``options.reveal`` asks; or from
    ``layers`` already peeled."""
    max_layers, reveal = options.max_layers, options.reveal
    if layers is None:
        w, h = check_size(size, 1, renderer.max_texture)
        if camera is None:
            camera = fit_camera(model, (w, h), options.view)
        view = np.asarray(camera.view_matrix(), np.float64)
        projection = np.asarray(camera.projection_matrix(), np.float64)
        if reveal is not None:
            max_layers = _revealing_layers(renderer, model, camera, (w, h), chosen, reveal, max_layers)
    elif reveal is not None:
        raise InputError("reveal decides how many layers to peel: give no layers with it")
    else:
        h, w = layers.depth.shape[1:]
        camera = camera or layers.camera
        view, projection = np.asarray(layers.view, np.float64), np.asarray(layers.projection, np.float64)
    return ViewFrame(camera, (int(w), int(h)), view, projection, max_layers)


def _size_frame(renderer, model: Model, frame: ViewFrame) -> None:
    """Size the drawing's GPU memory before anything is drawn (``Capturer.check_memory``): the
    capture's buffers at the drawing's size and layer cap, and beside them the occlusion's
    table of face planes and, where it peels a pass a layer, its copy of each layer's faces;
    the mesh drawn in chunks where it alone does not fit, the drawing refused where the rest
    does not."""
    w, h = frame.size
    extra = {"planes": 16 * table_rows(model.triangle_count + 1)}
    if frame.max_layers is not None:
        extra["layer copies"] = 4 * w * h * min(frame.max_layers, MAX_LAYERS)
    renderer.capturer.check_memory(model, w * h, frame.max_layers, None, extra)


class Occlusion:
    """Where a drawing's samples find the surfaces in front of them: the faces k-buffer read on
    the GPU (``gpu_levels``) where the renderer can, else the layers' faces read back at the
    pixels the tests probe (or the ``layers`` given) and classified on the CPU."""

    def __init__(
        self, renderer, model, frame: ViewFrame, samples, planes, crease_angle: float, layers, drawn
    ):
        self.renderer, self.model, self.frame, self.samples = renderer, model, frame, samples
        self.planes, self.layers, self.drawn = planes, layers, drawn
        self.crease_angle = crease_angle
        # surfaces the capture takes for one do not hide each other's lines, nor a smooth
        # surface's folds over its own contour the contour
        tolerance = depth_tolerance(frame.camera, model.bounds)
        band = grazing_band(model, frame.view, frame.projection, crease_angle)
        self.test = DepthTest(frame.ortho, frame.camera.pixel_angle(frame.size[1]), tolerance, band)
        self.peeled: PixelLayers | None = None
        # of the peel's seconds, those spent before the levels' ``clock``: setting the faces
        # k-buffer drawing (``draw_faces``), which ``gpu_levels`` counts with the peel
        self.ahead = 0.0

    def _on_gpu(self, planes):
        frame = self.frame
        return gpu_levels(
            self.renderer,
            self.model,
            frame.camera,
            self.samples,
            planes,
            frame.size,
            max_layers=frame.max_layers,
            test=self.test,
            drawn=self.drawn,
        )

    def levels(self, clock: float, seconds: dict[str, float]) -> tuple[np.ndarray, int]:
        """(S,) occlusion level of each sample (-1: left out) and the layers counted; the
        seconds of the peel (of those since ``clock``, and ``ahead`` of them) into
        ``seconds["peel"]``."""
        samples, planes, part, test = self.samples, self.planes, face_parts(self.model), self.test
        on_gpu = None if self.layers is not None else self._on_gpu(planes)
        if on_gpu is not None:
            seconds["peel"] = on_gpu.peel_seconds
            self.ahead = 0.0 if self.drawn is None else self.drawn.seconds
            return self._phantoms_dropped(on_gpu), on_gpu.layers
        frame = self.frame
        if self.layers is None:
            # occlusion needs only the layers' triangles, and only at the pixels it probes
            pixels = probe_pixels(samples, frame.size)
            faces = self.renderer.triangles_at(
                self.model, frame.camera, pixels, size=frame.size, max_layers=frame.max_layers
            )
            count = len(faces)
            w, h = frame.size
            self.peeled = PixelLayers(
                pixels, np.ascontiguousarray(faces.T), (faces >= 0).sum(axis=0), count, h, w
            )
        else:
            count = len(self.layers.depth)
            self.peeled = PixelLayers.from_layers(self.layers.triangle)
        seconds["peel"] = time.perf_counter() - clock
        on_gpu = stack_levels(self.renderer, samples, planes, self.peeled, test=test)
        if on_gpu is not None:
            return self._phantoms_dropped(on_gpu), count
        levels = classify_samples(samples, self.peeled, planes, test)
        levels = verify_creases(samples, levels, self.peeled, planes, part, test, self.crease_angle)
        return levels, count

    def _phantoms_dropped(self, on_gpu: GpuLevels) -> np.ndarray:
        """The levels the compute pass found, mesh edges that are no edges left out
        (``drop_phantoms`` with the faces it saw to either side)."""
        rows = np.flatnonzero(on_gpu.checked & (on_gpu.level >= 0))
        sides = on_gpu.sides[rows]
        part = face_parts(self.model)
        return drop_phantoms(
            self.samples,
            on_gpu.level,
            rows,
            sides[:, 0],
            sides[:, 1],
            self.planes,
            part,
            self.test,
            self.crease_angle,
        )

    def in_front(self, planes: np.ndarray) -> np.ndarray:
        """(S,) surfaces in front of each sample of those with ``planes`` (as ``face_planes``),
        after ``levels``, from the same layers: nothing has drawn since."""
        if self.peeled is None:
            return self._on_gpu(planes).level
        on_gpu = stack_levels(self.renderer, self.samples, planes, self.peeled, test=self.test)
        if on_gpu is not None:
            return on_gpu.level
        return classify_samples(self.samples, self.peeled, planes, self.test)


def _chained(pieces: Lines, count: int) -> Lines:
    """Pieces of one part, kind, level and side of the shading (of ``count`` levels) that meet
    end to end joined into one, keeping the edges of every piece in the order walked."""
    key = (
        (pieces.part.astype(np.int64) * 256 + pieces.kind) * (count + 1) + pieces.level
    ) * 2 + pieces.behind
    points, offsets, piece, reverse, lengths = chain_pieces(pieces.points, pieces.offsets, key)
    index, size, _ = walked(pieces.edge_offsets, piece, reverse)
    owner = np.repeat(np.repeat(np.arange(len(lengths)), lengths), size)
    edges, edge_offsets = runs_of(pieces.edges[index], owner, len(lengths))
    first = piece[np.cumsum(lengths) - lengths]
    return Lines(
        points,
        offsets,
        pieces.part[first],
        pieces.kind[first],
        pieces.level[first],
        edges,
        edge_offsets,
        pieces.behind[first],
    )


def _simplified(pieces: Lines, tolerance: float) -> Lines:
    """The pieces simplified (Douglas-Peucker, ``tolerance`` pixels), those no longer than
    ``_MIN_LENGTH_PX`` left out: lines along the view direction project to points, nothing to
    draw."""
    points, offsets, _ = douglas_peucker(pieces.points, pieces.offsets, tolerance)
    step = np.linalg.norm(np.diff(points, axis=0), axis=1) if len(points) > 1 else np.zeros(0)
    within = np.ones(len(step), bool)
    within[offsets[1:-1] - 1] = False  # steps between two polylines
    length = (
        np.add.reduceat(np.where(within, step, 0.0), offsets[:-1])
        if len(step)
        else np.zeros(len(offsets) - 1)
    )
    length[np.diff(offsets) < 2] = 0.0
    keep = length > _MIN_LENGTH_PX
    simple = Lines(
        points,
        offsets,
        pieces.part,
        pieces.kind,
        pieces.level,
        pieces.edges,
        pieces.edge_offsets,
        pieces.behind,
    )
    return simple.take(keep)


def _title(title: str | None, model: Model, camera: Camera, page: Page) -> str | None:
    """The title given, or on a drawing to scale "<model> — <view> view — 1:50 (mm)"."""
    if title is None and page.scale is not None:
        name = Path(model.source).stem if model.source and model.source != "generated" else "model"
        title = f"{name} — {camera.name} view — {page.scale_label} ({page.model_unit})"
    return title


def _hatching(frame: ViewFrame, options: VectorOptions, page: Page) -> SectionLines | None:
    """The cut faces' hatching and outline of a section view (2.5 mm apart to scale)."""
    if options.section is None:
        return None
    if page.unit == "mm":
        spacing_px = SECTION_HATCH_MM / page.factor
    else:
        spacing_px = hatch_spacing_px(frame.size, options.line_width)
    return section_lines(options.section, frame.view, frame.projection, frame.size, spacing_px)


def _dimension_marks(model: Model, frame: ViewFrame, options: VectorOptions, page: Page) -> Marks | None:
    """The view's dimensions, where asked: orthographic views only."""
    if not options.dimensions:
        return None
    if not frame.camera.ortho:
        raise InputError("dimensions need an orthographic view (--ortho, or --view plan)")
    unit = page.model_unit or drawing_unit(model, options.units)
    mm_per_px = page.factor if page.unit == "mm" else None
    from .dimension import dimension_marks

    return dimension_marks(
        model, frame.view, frame.projection, frame.size, UNITS_MM[unit], mm_per_px, options.crease_angle
    )


def _glyph_lines(glyphs: Glyphs, model: Model, frame: ViewFrame, renderer, layers, seconds) -> GlyphLines:
    """The glyphs as lines, their stretches behind the front surface apart."""
    from .glyphs import glyph_lines

    clock = time.perf_counter()
    # the front surface is all the depth test of glyphs needs
    front = (
        layers
        if layers is not None
        else renderer.peel(model, frame.camera, size=frame.size, max_layers=1, normals=False)
    )
    depth = front.depth[0] if len(front.depth) else None
    drawn = glyph_lines(glyphs, frame.camera, frame.size, depth)
    seconds["glyphs"] = time.perf_counter() - clock
    return drawn


def _shade_color(style) -> tuple[float, float, float]:
    """The shade colour of the raster style a drawing's style is or stands for (the blueprint
    style's for a line style of its own)."""
    if isinstance(style, Style):
        return style.shade[:3]
    name = style.name if isinstance(style, VectorStyle) else style
    return STYLES[name if isinstance(name, str) and name in STYLES else "blueprint"].shade[:3]


def draw_vector_sheet(
    model: Model,
    size: tuple[int, int] = (1024, 1024),
    *,
    renderer: LayerRenderer,
    fov: float = 30.0,
    sheet: str | None = None,
    section: tuple[SectionPlane, np.ndarray] | None = None,
    **options,
) -> VectorDrawing:
    """A drawing sheet: the orthographic top view above the front view, the right view beside
    it, all at one scale, and an iso view in the free corner, each drawn at a quarter of
    ``size``, labelled, and laid out with even gaps fitted to their sizes inside a border with
    a title block (ISO 7200: ``title``, default the model's name; scale; units; date; sheet).

    ``scale`` and ``units`` lay the page out in millimetres with the orthographic views to
    scale; ``sheet`` ('A4' ... 'A0', landscape) sets the paper, the scale then being the largest
    standard one at which the views fit unless ``scale`` gives it. ``section`` (a plane and the
    parts kept whole, (P,) bool) cuts the model as the front view sees it, in every view.
    ``options`` are ``VectorOptions``' fields, as :func:`draw_vector` takes them, for every view.
    """
    lines = VectorOptions(**options).checked()
    return draw_sheet(model, size, renderer, lines, fov=fov, sheet=sheet, section=section)


def draw_sheet(
    model: Model,
    size: tuple[int, int],
    renderer: LayerRenderer,
    options: VectorOptions,
    *,
    fov: float = 30.0,
    sheet: str | None = None,
    section: tuple[SectionPlane, np.ndarray] | None = None,
) -> VectorDrawing:
    """``draw_vector_sheet`` with its views' options as one value, checked already: its
    ``scale``, ``units``, ``title`` and ``dimensions`` are the sheet's."""
    for option in ("glyphs", "shade"):
        if getattr(options, option) is not None:
            raise InputError(f"--{option} draws on one view, not on a plan sheet: give another --view")
    w, h = size[0] // 2, size[1] // 2
    if w < 1 or h < 1:
        raise InputError(f"size {size[0]}x{size[1]} is too small for a plan sheet (at least 2x2)")
    scale, title, dimensions = options.scale, options.title, options.dimensions
    paper = None if sheet is None else paper_size(sheet)
    cameras = sheet_cameras(model, (w, h), fov)
    measures = scale is not None or paper is not None or dimensions
    given, units = options.units, drawing_unit(model, options.units)
    cut = None
    if section is not None:
        plane, keep = section
        cut = cut_model(model, plane.facing(cameras["front"].eye, cameras["front"].target), keep)
    view = replace(options, scale=None, units=None, title=None, dimensions=False, section=cut)
    drawn = model if cut is None else cut.model
    cells = {name: draw_lines(drawn, cameras[name], (w, h), renderer, view) for name in SHEET_CELLS}
    first = cells["top"]
    seconds: dict[str, float] = {}
    for cell in cells.values():
        for stage, spent in cell.seconds.items():
            seconds[stage] = seconds.get(stage, 0.0) + spent

    if paper is not None and scale is None:
        scale = _sheet_scale(cells, cameras["front"], (w, h), paper, units, model)
    quarter = _page((w, h), cameras["front"], scale, units, model)
    mm_per_px = quarter.factor if quarter.unit == "mm" else None
    if dimensions:
        # on the orthographic views, sized for the sheet's scale, known only now
        crease = options.crease_angle
        from .dimension import dimension_marks

        for name in ("top", "front", "right"):
            view_m, proj = cameras[name].view_matrix(), cameras[name].projection_matrix()
            marks = dimension_marks(drawn, view_m, proj, (w, h), UNITS_MM[units], mm_per_px, crease)
            cells[name] = replace(cells[name], marks=marks)
    extents = {name: _view_extent(cell, (w, h)) for name, cell in cells.items()}
    per_mm = 1.0 / mm_per_px if mm_per_px else 96.0 / 25.4
    room = None if paper is None else (paper[0] * per_mm, paper[1] * per_mm)
    layout = lay_out_sheet(extents, 5, (w, h), mm_per_px, room)
    width, height, shifts = layout.width, layout.height, layout.shifts

    page = replace(quarter, width=width * quarter.factor, height=height * quarter.factor)
    heading = title if title is not None else model_name(model)
    fields = sheet_fields(
        heading, page.scale_label, page.model_unit, sheet or f"{width:.0f} x {height:.0f} px"
    )
    marks = Marks.concatenate(
        [layout.marks(fields)]
        + [cells[n].marks.shifted(shifts[n]) for n in cells if cells[n].marks is not None]
    )
    order = list(cells)
    if measures:
        warn_if_assumed(model, given)
    return replace(
        first,
        width=int(math.ceil(width)),
        height=int(math.ceil(height)),
        lines=Lines.concatenate([cells[n].lines.shifted(shifts[n]) for n in order]),
        layers=max(c.layers for c in cells.values()),
        page=page,
        camera=cameras["front"],
        title=None,
        name=heading,
        marks=marks,
        section=None
        if cut is None
        else SectionLines.concatenate([cells[n].section.shifted(shifts[n]) for n in order]),
        seconds=seconds,
    )


def _view_extent(cell: VectorDrawing, size: tuple[int, int]) -> np.ndarray:
    """A view's lines' extent in its cell, its section's outline included."""
    points = cell.points
    if cell.section is not None and len(cell.section.outline):
        points = np.concatenate([points, cell.section.outline.reshape(-1, 2)])
    if cell.marks is not None:
        points = np.concatenate([points, cell.marks.lines.reshape(-1, 2)])
    if len(points) == 0:
        centre = np.array(size, np.float64) / 2
        return np.array([centre, centre])
    return np.array([points.min(axis=0), points.max(axis=0)])


def _sheet_scale(cells, camera: Camera, size, paper, units, model) -> float:
    """The largest standard scale at which a sheet's views fit on ``paper`` (mm)."""
    unit = drawing_unit(model, units)
    spans = {name: np.ptp(_view_extent(cell, size), axis=0) for name, cell in cells.items()}
    content_w = max(spans["top"][0], spans["front"][0]) + max(spans["right"][0], spans["iso"][0])
    content_h = max(spans["top"][1], spans["iso"][1]) + max(spans["front"][1], spans["right"][1])
    # the border, the title block, three gaps and two labels a way, in mm
    room_w = paper[0] - BORDER_MM[0] - BORDER_MM[1] - 3 * 10.0
    room_h = paper[1] - 2 * BORDER_MM[1] - 5 * 1.8 * TEXT_MM - 3 * 10.0 - 2 * 1.4 * LABEL_MM
    if room_w <= 0 or room_h <= 0:
        raise InputError(f"the sheet {paper[0]:g} x {paper[1]:g} mm has no room for views")
    factor = min(room_w / max(content_w, 1e-9), room_h / max(content_h, 1e-9))
    model_per_px = camera.height / size[1]
    return fit_scale(model_per_px * UNITS_MM[unit] / factor)


def save_drawing(path: str | os.PathLike, drawing: VectorDrawing, format: str | None = None) -> Path:
    """Write a drawing as SVG, PDF or DXF (from ``format`` or the file's suffix), atomically."""
    suffix = "." + format.lower().lstrip(".") if format else None
    path, writer = WRITERS.choose(path, Kind.DRAWING, suffix=suffix)
    return writer(path, drawing)


def _write_svg(path: Path, drawing: VectorDrawing) -> Path:
    data = svg_bytes(drawing)
    return atomic_write(path, lambda tmp: tmp.write_bytes(data))


def _write_pdf(path: Path, drawing: VectorDrawing) -> Path:
    data = pdf_bytes(drawing)
    return atomic_write(path, lambda tmp: tmp.write_bytes(data))


def _write_dxf(path: Path, drawing: VectorDrawing) -> Path:
    return atomic_write(path, lambda tmp: write_dxf(drawing, tmp))


_WRITERS = {".svg": _write_svg, ".pdf": _write_pdf, ".dxf": _write_dxf}
FORMATS = tuple(_WRITERS)


def register_writers(writers: Writers) -> None:
    """Add the vector drawings' writers to ``writers`` (``blueprint.export.writers.PROVIDERS``
    names this function)."""
    for suffix, write in _WRITERS.items():
        writers.add(suffix, Kind.DRAWING, write)
