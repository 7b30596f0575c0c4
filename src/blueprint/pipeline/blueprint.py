"""The blueprint frame: ``Renderer.render``'s arguments as the ``blueprint`` preset's variables
and part sets, run by the executor. Highlight, depth masking (reveal), shading and triangle-ID
silhouettes are passes, attributes and a stop rule of the preset, not code of their own."""

from __future__ import annotations

import operator
import weakref
from collections.abc import Iterable, Iterator

import numpy as np

from blueprint.compose.lookup import get_style
from blueprint.compose.style import Style
from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.pipeline.spec import PipelineSpec, load_pipeline
from blueprint.render.renderer import Frame
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model

_PRESETS: dict[str, PipelineSpec] = {}


def blueprint_preset() -> PipelineSpec:
    """The ``blueprint`` preset, parsed once."""
    spec = _PRESETS.get("blueprint")
    if spec is None:
        spec = _PRESETS["blueprint"] = load_pipeline("blueprint")
    return spec


def render_blueprint(
    renderer,
    model: Model,
    camera: Camera | None = None,
    *,
    profile: bool = False,
    on_gpu: bool = False,
    contours=None,
    **options,
) -> Frame:
    """``Renderer.render`` through the ``blueprint`` preset, run by ``renderer``'s executor (a
    ``blueprint.Renderer``); ``options`` are its drawing options (``size``, ``style``,
    ``highlight``...: see there), as ``_run_arguments`` takes them. Their ranges are the API's
    to check (``blueprint.api.options.DrawOptions``), once. ``contours``: smooth contour lines
    of this camera at this size (``blueprint.vector.contour_ink``), drawn in place of the
    outline of the faces they stand for."""
    style, arguments = _last_arguments(renderer, model, options)
    if contours is not None:
        variables = {**arguments["variables"], "smooth_contours": True}
        arguments = {**arguments, "contours": contours, "variables": variables}
    result = renderer.executor.run(
        blueprint_preset(), model, camera, profile=profile, keep=on_gpu, **arguments
    )
    return _frame(result, style)


def stream_blueprint(renderer, model: Model, cameras: Iterable[Camera], **options) -> Iterator[Frame]:
    """Frames of ``model`` from each of ``cameras`` with ``render_blueprint``'s other options,
    streamed: a frame's picture is read back while the next one is drawn (``Executor.stream``),
    and ``Frame.ms`` is the interval between frames."""
    style, arguments = _run_arguments(renderer, model, **options)
    frames = ({"camera": camera} for camera in cameras)
    for result in renderer.executor.stream(blueprint_preset(), model, frames, **arguments):
        yield _frame(result, style)


# (renderer, model, options, the style and arguments made of them) of the last frame asked for
_LAST: list = [None]


def _last_arguments(renderer, model: Model, options: dict) -> tuple[Style, dict]:
    """``_run_arguments``, made once for frames asking for the same options (the same objects,
    as ``DrawOptions.frame_keywords`` gives them: a stream's frames) of one model on one
    renderer; never for parts given as arrays, which may change in place. The arguments are
    shared: read, never written."""
    last = _LAST[0]
    if (
        last is not None
        and last[0]() is renderer
        and last[1]() is model
        and last[2].keys() == options.keys()
        and all(map(operator.is_, last[2].values(), options.values()))
    ):
        return last[3]
    made = _run_arguments(renderer, model, **options)
    arrays = any(isinstance(value, np.ndarray) for value in options.values())
    # weakly held: a dropped model's memory is not kept for a frame that may never come
    _LAST[0] = None if arrays else (weakref.ref(renderer), weakref.ref(model), options, made)
    return made


def _run_arguments(
    renderer,
    model: Model,
    *,
    size: tuple[int, int] = (1024, 1024),
    view: str = "iso",
    style: str | Style = "blueprint",
    max_layers: int | None = 8,
    min_fraction: float = 0.0,
    crease_angle: float = 30.0,
    highlight: np.ndarray | None = None,
    reveal: float | None = None,
    shade: np.ndarray | None = None,
    **variables,
) -> tuple[Style, dict]:
    """The style and ``Executor.run``'s arguments of a blueprint frame: the peel's settings,
    the parts as the preset's part sets, and the other options (``supersample``,
    ``line_width``, ``depth_threshold``, ``part_edges``, ``id_silhouettes``,
    ``shade_opacity``) as the preset's variables of the same names, their defaults the
    preset's. The API's ``DrawOptions`` checks their ranges where the user gives them; the
    size is checked here against this GPU."""
    preset = blueprint_preset()
    style = get_style(style)
    unknown = sorted(set(variables) - set(preset.variables))
    if unknown:
        raise TypeError(f"a blueprint frame takes no option {unknown[0]!r}")
    # as the preset declares them: an int, a float or a bool
    variables = {name: type(preset.variables[name])(value) for name, value in variables.items()}
    supersample = variables.get("supersample", preset.variables["supersample"])
    w, h = check_size(size, supersample, renderer.max_texture)
    renderer.capturer.check_memory(model, w * h * supersample**2, max_layers, crease_angle)
    if reveal is not None and highlight is None:
        raise InputError("reveal needs parts to reveal: give highlight as well")
    parts = {}
    for name, flags in (("highlight", highlight), ("shade", shade)):
        if flags is not None:
            flags = np.asarray(flags, bool)
            if flags.shape != (len(model.part_names),):
                raise InputError(
                    f"{name} needs one flag per part ({len(model.part_names)}), got {flags.shape}"
                )
            parts[name] = flags
    variables.update(
        visible_width=float(style.width),
        hidden_width=float(style.hidden_width),
        highlight=highlight is not None,
        highlight_width=float(style.highlight_width),
        reveal=float(reveal or 0.0),
        shade=shade is not None,
    )
    return style, {
        "size": (w, h),
        "view": view,
        "variables": variables,
        "style": style,
        "max_layers": max_layers,
        "min_fraction": min_fraction,
        "crease_angle": crease_angle,
        "parts": parts,
    }


def _frame(result, style: Style) -> Frame:
    if result.texture is not None:
        image = None
    else:
        image = result.image if style.paper is None else result.output
    return Frame(
        image,
        result.layers,
        result.layer_pixels,
        result.camera,
        result.ms,
        result.draws,
        result.stages,
        result.revealed,
        result.layers_left,
        texture=result.texture,
    )
