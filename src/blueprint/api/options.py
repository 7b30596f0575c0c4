"""``DrawOptions``: every drawing option as one frozen value, checked once where it is made.

The public entry points (``render``, ``render_frame``, ``draw``, ``peel`` and the file
workflows) take the options as typed keywords made from the fields (``takes_options``) and pass
the value down; the command line makes its options from the same fields
(``blueprint.cli.options.drawing_options``), so that a new option is one field here. Errors
name the API argument (``line_width must be in [1, 16] pixels, got 20``); the command line
names its flag instead (``--line-width``).
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import math
import os
import sys
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from blueprint.compose.style import FILE_SUFFIXES, STYLES, Style
from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.render.stop import HARD_MAX_LAYERS
from blueprint.scene.camera import VIEWS, Camera
from blueprint.scene.model import Model
from blueprint.scene.units import check_units

if TYPE_CHECKING:
    from blueprint.compose.glyphs import Glyphs
    from blueprint.compose.linestyle import VectorStyle
    from blueprint.scene.section import SectionPlane

__all__ = ["GROUPS", "PLAN", "DrawOptions", "PartSpec", "option_fields", "options_but", "takes_options"]

#: The view name of a drawing sheet: top, front and right orthographic views plus an iso view.
PLAN = "plan"

#: Parts chosen by name globs and indices (a comma-separated string or a sequence), by a second
#: model lying on them, or as one flag per part (see ``blueprint.scene.parts.designated_parts``).
PartSpec = str | int | Sequence[str | int] | Model | np.ndarray

#: The groups of options, in the order the fields list them.
GROUPS = ("camera", "model", "size", "layers", "style", "masking", "section", "sheet", "glyphs", "output")


def _option(
    default,
    group: str,
    help: str,
    *,
    cli: bool = True,
    kind: Any = None,
    metavar: str | None = None,
    nargs: int | None = None,
    choices: tuple[str, ...] | None = None,
) -> Any:
    """A field of ``DrawOptions`` with what the command line makes of it: ``help``, the flag
    (``--`` and the name, dashed), the click type ``kind`` (default: the default's type;
    ``"switch"``: a flag and its ``--no-`` form, neither given leaving the default None) and
    ``metavar``, ``nargs`` and ``choices``; ``cli=False`` keeps it out of the command line."""
    assert group in GROUPS, group
    metadata = {"group": group, "help": help, "cli": cli, "kind": kind, "metavar": metavar}
    metadata.update(nargs=nargs, choices=choices)
    return field(default=default, metadata=metadata)


@dataclass(frozen=True)
class DrawOptions:
    """Every option of a drawing, checked when the value is made (``InputError`` in one line,
    naming the argument); make variants with ``dataclasses.replace``.

    Parameters
    ----------
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
    camera : Camera, optional
        A ready camera; the view arguments are then unused.
    up : {'y', 'z'}, optional
        A model file's up axis (default: z for STL and 3MF, y for glTF, guessed from the shape
        for OBJ, PLY and OFF).
    include, exclude : str or sequence, optional
        A model file's parts to keep and to leave out (name globs or indices); without
        ``include`` its environment meshes (skyboxes, huge ground planes) are left out.
    size : (int, int) or None
        Width and height in pixels (None: a pipeline's own size; a drawing needs one).
    supersample : int
        G-buffer and edges are computed at this multiple of ``size`` (1-4), then filtered down.
    max_layers : int or None
        Depth layers to peel at most (1-256); None peels until a pass draws nothing.
    min_fraction : float
        Stop once a layer covers fewer than this fraction of layer 0's pixels.
    reveal : float, optional
        Depth masking: peel only until this fraction of the highlighted parts is uncovered, as
        deep as that takes (``max_layers`` does not cap it). Needs ``highlight``.
    style : str, PathLike, Style or VectorStyle
        A style of ``blueprint.compose.style.STYLES`` by name (``blueprint``, ``paper``,
        ``transparent``, ``wireframe``), a line style file (``.toml``, ``.json``: colour, width,
        dash and opacity per occlusion level), a ``Style`` or a ``VectorStyle``.
    grid : float, optional
        The style's grid spacing in pixels, overridden (0: no grid).
    line_width : float
        Line width in output pixels, in [1, 16] (multiples of 0.25 mm on a drawing to scale).
    crease_angle : float
        Degrees: normals are smoothed across smaller angles, larger ones draw creases.
    depth_threshold : float
        The depth jump, in pixel footprints, that draws a silhouette edge, in [0.1, 1000].
    part_edges : bool
        Draw the boundaries between parts.
    id_silhouettes : bool
        Also draw triangle-ID silhouettes in every layer's edge map.
    smooth_contours : bool, optional
        In pictures, draw the outline of smooth surfaces as lines along the contour of their
        interpolated normals (``blueprint.vector.contour_ink``), each in the layer of its
        occlusion level, instead of the edges of the mesh's own outline there: vector drawings
        always do. A scan's outline then runs smooth, without the specks of its noise's folds,
        for a pass over the mesh (on the GPU for a dense mesh, where the renderer can; else
        the mesh's outline stays there) and one more capture of the faces near the lines a
        view. None (the default): a picture (``render``, ``draw``, ``blueprint render``) of
        one mesh draws them (``blueprint.api.picture.smooth_contours_wanted``); a renderer's
        frames (``Renderer.render``, streams) and the viewer draw none.
    highlight : str, int, sequence, Model or (P,) bool, optional
        Parts to outline in the highlight ink: name globs (``"Piston*"``) and indices, or a
        second model lying on the parts to designate.
    shade : str, int, sequence, Model or (P,) bool, optional
        Parts drawn shaded inside the drawing, in depth order (in vectors: filled polygons).
    shade_opacity : float
        Opacity of the shading, in (0, 1]: 1 hides the edges behind the shaded parts.
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
        in millimetres.
    units : str, optional
        The model's length unit (``mm``, ``in``, ``m`` ...), over the one its file states: the
        dimensions' values, ``scale`` and a plan sheet's title block. Default ``Model.unit``
        (glTF and STEP: ``m``; 3MF: its own), else ``mm``, with a warning.
    title : str, optional
        A plan sheet's title (default: the model's name); a vector view's title line.
    scale : str or float, optional
        ``'1:50'``: a vector page laid out in millimetres, orthographic. Vector drawings only.
    sheet : str, optional
        ``A4`` ... ``A0`` (landscape): the paper of a vector plan sheet, the scale fitted to it
        unless ``scale`` is given. Vector drawings only.
    glyphs : Glyphs, str or PathLike, optional
        Boxes, arrows, paths and labels in model coordinates (a TOML or JSON file, see
        ``blueprint.compose.glyphs``), drawn depth-correctly: dimmed, dashed or left out where
        a surface hides them; ``[[dimension]]`` entries are drawn after ISO 129 on top. Not on a
        plan sheet. A file is read when the options are made.
    profile : bool
        Synchronise after each stage to fill ``Frame.stages`` (slower).
    """

    # -- camera
    view: str = _option(
        "iso",
        "camera",
        f"Named view: {', '.join(VIEWS)}; render also takes {PLAN} (a sheet of top, front, right).",
    )
    azimuth: float | None = _option(None, "camera", "Degrees from the front, towards the right.", kind=float)
    elevation: float | None = _option(None, "camera", "Degrees above the horizon.", kind=float)
    fov: float = _option(30.0, "camera", "Vertical field of view, degrees.")
    ortho: bool = _option(False, "camera", "Orthographic projection (plan views).")
    camera: Camera | None = _option(None, "camera", "A ready camera.", cli=False)
    # -- model
    up: str | None = _option(
        None,
        "model",
        "Model up axis (default: z for STL/3MF, y for glTF; OBJ/PLY/OFF: guessed from a flat base).",
        choices=("y", "z"),
    )
    include: str | Sequence[str | int] | None = _option(
        None,
        "model",
        "Draw only these parts (name globs or indices, comma-separated); keeps environment meshes.",
        metavar="GLOBS",
    )
    exclude: str | Sequence[str | int] | None = _option(
        None,
        "model",
        "Leave these parts out (environment meshes like skyboxes are left out by default).",
        metavar="GLOBS",
    )
    # -- size
    size: tuple[int, int] | None = _option(
        (1024, 1024), "size", "Image width and height in pixels.", kind=int, metavar="W H", nargs=2
    )
    supersample: int = _option(2, "size", "Anti-aliasing factor (1-4).")
    # -- layers
    max_layers: int | None = _option(
        8, "layers", "Depth layers to peel at most (0: all; --reveal peels as deep as it needs).", kind=int
    )
    min_fraction: float = _option(
        0.0, "layers", "Stop when a layer covers less than this fraction of the first."
    )
    reveal: float | None = _option(
        None, "layers", "Depth masking: peel until this fraction of the highlighted parts shows.", kind=float
    )
    # -- style
    style: str | os.PathLike | Style | VectorStyle = _option(
        "blueprint",
        "style",
        f"One of {', '.join(STYLES)}, or a line style file ({' or '.join(FILE_SUFFIXES)}: colour, width, "
        "dash and opacity per occlusion level; pictures draw no dashes).",
    )
    grid: float | None = _option(None, "style", "Grid spacing in pixels (0: none).", kind=float)
    line_width: float = _option(1.0, "style", "Pixels.")
    crease_angle: float = _option(30.0, "style", "Degrees.")
    depth_threshold: float = _option(4.0, "style", "Pixel footprints.", cli=False)
    part_edges: bool = _option(True, "style", "Draw the boundaries between parts.", cli=False)
    id_silhouettes: bool = _option(False, "style", "Add triangle-ID silhouettes to every layer's edges.")
    smooth_contours: bool | None = _option(
        None,
        "style",
        "Pictures: outline smooth surfaces by the contour of their interpolated normals, as vector "
        "drawings do (scans: no zigzag, fewer specks; a pass over the mesh a view, on the GPU for "
        "dense meshes). Default: pictures of one mesh.",
        kind="switch",
    )
    # -- masking
    highlight: PartSpec | None = _option(
        None, "masking", "Parts to outline: name globs or indices, comma-separated.", kind=str
    )
    shade: PartSpec | None = _option(
        None, "masking", "Parts to draw shaded inside the drawing: globs or indices.", kind=str
    )
    shade_opacity: float = _option(1.0, "masking", "1 opaque, less see-through.")
    # -- section
    section: str | None = _option(
        None,
        "section",
        "Section view: x=VALUE, y=VALUE or z=VALUE (model units); the side facing the camera is removed.",
        kind=str,
    )
    section_plane: str | Sequence[float] | None = _option(
        None,
        "section",
        "Section by any plane: a point of it and a normal towards the side removed.",
        kind=str,
        metavar="PX,PY,PZ,NX,NY,NZ",
    )
    section_keep: PartSpec | None = _option(
        None, "section", "Parts drawn uncut in a section: globs or indices.", kind=str
    )
    # -- sheet
    dimensions: bool = _option(
        False,
        "sheet",
        "Overall dimensions and circle diameters of orthographic views and plan sheets (ISO 129, mm).",
    )
    units: str | None = _option(
        None,
        "sheet",
        "The model's length unit for --scale, dimensions and plan sheets (um, mm, cm, m, km, in, ft); "
        "default: the file's (glTF, STEP: m; 3MF: its own), else mm, with a warning.",
        kind=str,
    )
    title: str | None = _option(
        None, "sheet", "Title of a plan sheet's title block (default: the model's name).", kind=str
    )
    scale: str | float | None = _option(
        None, "sheet", "Vector plan views to scale, e.g. 1:50 (orthographic, page in mm).", kind=str
    )
    sheet: str | None = _option(
        None,
        "sheet",
        "Paper of a vector plan sheet: A4, A3, A2, A1 or A0 (landscape); the scale fits it unless --scale.",
        kind=str,
    )
    # -- glyphs
    glyphs: Glyphs | str | os.PathLike | None = _option(
        None,
        "glyphs",
        "TOML or JSON file of boxes, arrows, paths, labels and dimensions in model coordinates.",
        kind="path",
    )
    # -- output
    profile: bool = _option(False, "output", "Synchronise after each stage (slower).", cli=False)

    def __post_init__(self) -> None:
        views = (*VIEWS, PLAN)
        if self.view not in views:
            raise InputError(f"unknown view {self.view!r} (choose {', '.join(views)})")
        if self.size is not None:
            # the size's own checks; the GPU's limit is checked where the size is drawn
            object.__setattr__(self, "size", check_size(self.size, self.supersample, sys.maxsize))
        elif not 1 <= self.supersample <= 4:
            raise InputError(f"supersample must be 1, 2, 3 or 4, got {self.supersample}")
        if self.max_layers is not None and not 1 <= self.max_layers <= HARD_MAX_LAYERS:
            raise InputError(f"max_layers must be between 1 and {HARD_MAX_LAYERS}, got {self.max_layers}")
        _within("min_fraction", self.min_fraction, 0.0, 1.0)
        if self.reveal is not None:
            if self.highlight is None:
                raise InputError("reveal needs parts to reveal: give highlight as well")
            _within("reveal", self.reveal, 0.0, 1.0, lo_open=True)
        self._check_style()
        _within("line_width", self.line_width, 1.0, 16.0, " pixels")
        _within("crease_angle", self.crease_angle, 0.0, 180.0, " degrees")
        _within("depth_threshold", self.depth_threshold, 0.1, 1000.0, " pixel footprints")
        _within("shade_opacity", self.shade_opacity, 0.0, 1.0, lo_open=True)
        object.__setattr__(self, "_plane", self._section_plane())
        if self.units is not None:
            check_units(self.units)
        if self.scale is not None or self.sheet is not None:
            # the sheet's module loads with the drawings to scale and on paper
            from blueprint.scene.sheet import paper_size, parse_scale

            if self.scale is not None:
                parse_scale(self.scale)
            if self.sheet is not None:
                paper_size(self.sheet)
                if self.view != PLAN:
                    raise InputError(f"--sheet {self.sheet} sets the paper of a plan sheet: give --view plan")
        if self.glyphs is not None:
            if self.view == PLAN:
                raise InputError("glyphs need one view; the plan sheet draws four")
            object.__setattr__(self, "glyphs", _read_glyphs(self.glyphs))

    def _check_style(self) -> None:
        """A style name of ``STYLES``, a line style file (read now) or a style object; and the
        grid spacing that overrides the style's."""
        style, lines = self.style, None
        # a style by name or object, most drawings' case, does without the line style module
        if not (isinstance(style, Style) or (isinstance(style, str) and style in STYLES)):
            from blueprint.compose.linestyle import VectorStyle, is_style_file, load_vector_style

            if isinstance(style, os.PathLike) or is_style_file(style):
                lines = load_vector_style(style)
            elif isinstance(style, VectorStyle):
                lines = style
            else:
                raise InputError(f"unknown style {style!r} (choose {', '.join(STYLES)} or a line style file)")
        object.__setattr__(self, "_lines", lines)
        if self.grid is not None and not (math.isfinite(self.grid) and self.grid >= 0):
            raise InputError(f"grid must be a spacing of pixels >= 0, got {self.grid}")

    def _section_plane(self) -> SectionPlane | None:
        if self.section is None and self.section_plane is None:
            if self.section_keep is not None:
                raise InputError("--section-keep names parts left uncut: give --section or --section-plane")
            return None
        # the section's module loads with the drawings that have one
        from blueprint.scene.section import parse_section

        return parse_section(self.section, self.section_plane)

    @property
    def plane(self) -> SectionPlane | None:
        """The section's cutting plane (``section`` or ``section_plane`` parsed), or None."""
        return self._plane

    @cached_property
    def raster_style(self) -> Style:
        """The picture's ``Style``: ``style`` by name or object, a line style's raster
        counterpart (``blueprint.compose.linestyle.raster_style``), ``grid`` applied."""
        if self._lines is not None:
            from blueprint.compose.linestyle import VectorStyle, raster_style

            # a file's errors name it
            where = None if isinstance(self.style, VectorStyle) else str(self.style)
            chosen = raster_style(self._lines, where)
        else:
            chosen = self.style if isinstance(self.style, Style) else STYLES[self.style]
        return chosen if self.grid is None else chosen.with_options(grid=float(self.grid))

    @cached_property
    def vector_style(self) -> VectorStyle:
        """The vector drawing's ``VectorStyle`` (``blueprint.compose.linestyle.vector_style``)."""
        from blueprint.compose.linestyle import vector_style

        return self._lines if self._lines is not None else vector_style(self.style)

    def frame_keywords(self, model: Model) -> dict:
        """``blueprint.pipeline.blueprint.render_blueprint``'s drawing options: the style
        resolved and the highlighted and shaded parts of ``model`` as flags, (P,) bool; those
        of the last model asked for are kept, for a stream's frames (not the model itself)."""
        held = self.__dict__.get("_keywords")
        if held is not None and held[0]() is model:
            return dict(held[1])
        from blueprint.scene.parts import designated_parts

        def flags(spec):
            return None if spec is None else designated_parts(model, spec)

        keywords = dict(
            size=self.size,
            view=self.view,
            style=self.raster_style,
            max_layers=self.max_layers,
            min_fraction=self.min_fraction,
            crease_angle=self.crease_angle,
            line_width=self.line_width,
            supersample=self.supersample,
            depth_threshold=self.depth_threshold,
            part_edges=self.part_edges,
            id_silhouettes=self.id_silhouettes,
            highlight=flags(self.highlight),
            reveal=self.reveal,
            shade=flags(self.shade),
            shade_opacity=self.shade_opacity,
        )
        object.__setattr__(self, "_keywords", (weakref.ref(model), keywords))
        return dict(keywords)

    def fit_camera(self, model: Model, size: tuple[int, int] | None = None, margin: float = 0.05) -> Camera:
        """``camera``, or the camera of ``view``, ``azimuth``, ``elevation``, ``fov`` and
        ``ortho`` fitted to ``model`` at ``size`` (default ``self.size``)."""
        if self.camera is not None:
            return self.camera
        from blueprint.scene.camera import fit_camera

        return fit_camera(
            model,
            size or self.size,
            self.view,
            azimuth=self.azimuth,
            elevation=self.elevation,
            fov=self.fov,
            ortho=self.ortho,
            margin=margin,
        )


def _within(name: str, value, lo: float, hi: float, unit: str = "", lo_open: bool = False) -> None:
    low = lo < value if lo_open else lo <= value
    if not (low and value <= hi):
        raise InputError(f"{name} must be in {'(' if lo_open else '['}{lo:g}, {hi:g}]{unit}, got {value}")


def _read_glyphs(glyphs) -> Glyphs:
    """``glyphs``, read from its file where it is one (the glyph package loads only then)."""
    from blueprint.compose.glyphs import Glyphs, load_glyphs

    return glyphs if isinstance(glyphs, Glyphs) else load_glyphs(glyphs)


def option_fields() -> dict[str, dataclasses.Field]:
    """The fields of ``DrawOptions`` by name, in their order."""
    return {f.name: f for f in fields(DrawOptions)}


def options_but(*left_out: str) -> tuple[str, ...]:
    """The names of ``DrawOptions``' fields, in their order, but ``left_out``."""
    assert set(left_out) <= set(option_fields()), left_out
    return tuple(name for name in option_fields() if name not in left_out)


class _LastOptions:
    """The ``DrawOptions`` a function's last call made, with what made it: a stream of frames
    asks for the same options every frame, and checking them again costs each frame more than
    its compositing. Only for values that are hashable, so taken to be unchanging, and that read
    no file (a style or glyph file may have changed since). The pair is one value, read and set
    whole: threads of a batch call the same function."""

    __slots__ = ("held",)

    def __init__(self) -> None:
        self.held: tuple | None = None

    @staticmethod
    def _key(base, values: dict):
        if values.get("glyphs") is not None:
            return None
        style = values.get("style")
        named = isinstance(style, Style) or (isinstance(style, str) and style in STYLES)
        if style is not None and not named:
            return None
        key = (base, *values.items())
        try:
            hash(key)
        except TypeError:
            return None
        return key

    def get(self, base, values: dict):
        held = self.held
        if held is None or len(held[0]) != len(values) + 1 or held[0][0] is not base:
            return None
        return held[1] if held[0] == self._key(base, values) else None

    def keep(self, base, values: dict, options) -> None:
        key = self._key(base, values)
        self.held = None if key is None else (key, options)


def takes_options(
    *names: str, prepare: Callable[[dict], dict] | None = None, **defaults
) -> Callable[[Callable], Callable]:
    """Give ``function(*positional, options, *, **own)`` its public signature: its positional
    parameters, then as keywords ``options`` (a ``DrawOptions``, optional), the fields
    ``names`` (every field when none is named) typed, with ``defaults`` over the fields' own,
    and its own keyword-only parameters.

    A call makes the ``DrawOptions`` once, from the fields given (``prepare`` may rewrite them
    first) over ``options`` where it is given, else over those defaults, and passes it on.
    """
    known = option_fields()
    chosen = names or tuple(known)
    unknown = set(chosen) - set(known) | set(defaults) - set(chosen)
    assert not unknown, unknown
    keyword = inspect.Parameter.KEYWORD_ONLY

    def decorate(function: Callable) -> Callable:
        params = list(inspect.signature(function).parameters.values())
        at = [p.name for p in params].index("options")
        own = params[at + 1 :]
        option_params = [
            inspect.Parameter(
                name,
                keyword,
                default=defaults.get(name, known[name].default),
                annotation=known[name].type,
            )
            for name in chosen
        ]
        given = inspect.Parameter("options", keyword, default=None, annotation="DrawOptions | None")
        public = inspect.signature(function).replace(parameters=[*params[:at], given, *option_params, *own])

        keywords = frozenset(["options", *chosen, *(p.name for p in own)])
        last = _LastOptions()

        @functools.wraps(function)
        def wrapper(*args, **kwargs):
            # the usual call (every positional given so, keywords the signature's) is bound by
            # hand: the signature's bind costs a streamed frame hundreds of calls
            if len(args) == at and keywords.issuperset(kwargs):
                arguments, positional = kwargs, args
            else:
                arguments = public.bind(*args, **kwargs).arguments
                positional = [arguments.pop(p.name, p.default) for p in params[:at]]
            base = arguments.pop("options", None)
            values = {n: arguments.pop(n) for n in chosen if n in arguments}
            if base is None:
                values = {**{n: defaults[n] for n in defaults if n not in values}, **values}
            if prepare is not None:
                values = prepare(values)
            options = last.get(base, values)
            if options is None:
                options = DrawOptions(**values) if base is None else replace(base, **values)
                last.keep(base, values, options)
            return function(*positional, options, **arguments)

        wrapper.__signature__ = public
        return wrapper

    return decorate


def zero_layers_are_all(values: dict) -> dict:
    """``max_layers`` 0 as None (every layer): how the command line, ``draw`` and the vector
    workflows take it."""
    if values.get("max_layers") == 0:
        return {**values, "max_layers": None}
    return values
