"""File workflows: a model, an image or a video file in; a picture, drawing, video or data file
out (silhouettes: ``blueprint.api.silhouettes``). Each draws with ``renderer``, or with the
shared one (``blueprint.api.default_renderer``) when it is None. The command line is a thin
shell over these: every option is an argument of the same name.

Outputs are written by the writer their suffix names in ``blueprint.export.writers.WRITERS``
(``choose_writer``).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from blueprint.api import stages
from blueprint.api.draw import output_writer as choose_writer
from blueprint.api.draw import vector_drawing
from blueprint.api.frames import as_model, shared
from blueprint.api.options import DrawOptions, options_but, takes_options, zero_layers_are_all
from blueprint.api.renderer import Renderer
from blueprint.blas import one_blas_thread
from blueprint.errors import InputError, out_of_memory
from blueprint.export.files import check_output
from blueprint.export.writers import Kind
from blueprint.gpu.device import check_size
from blueprint.scene.model import Model
from blueprint.scene.parts import designated_parts
from blueprint.settings import FRAME_LIMIT

if TYPE_CHECKING:
    from blueprint.pipeline.state import Result

log = logging.getLogger("blueprint")

__all__ = ["choose_writer", "render_vector_file", "run_pipeline", "turntable"]


# What a pipeline takes of the options: where the camera looks from and the model file's parts.
PIPELINE_OPTIONS = ("size", "view", "azimuth", "elevation", "fov", "ortho", "up", "include", "exclude")


@takes_options(*PIPELINE_OPTIONS, size=None)
def run_pipeline(
    pipeline,
    input: str | os.PathLike | None = None,
    output: str | os.PathLike | None = None,
    options: DrawOptions | None = None,
    *,
    set: dict | None = None,
    image: dict[str, str] | None = None,
    parts: dict[str, str] | None = None,
    dump: tuple[str, ...] = (),
    max_layers: int | None = None,
    frames: int | None = None,
    renderer: Renderer | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Result:
    """Run a pipeline file (or preset) on a model, an image or a video and write the output.

    ``input`` is the model when the pipeline renders attributes; otherwise it fills the first
    image the pipeline declares without a file. A video input is filtered frame by frame into
    a video ``output`` (at most ``frames`` frames). ``set`` overrides variables, ``image``
    gives image files by name, ``parts`` the sets of parts that attributes of chosen parts
    name (``{"highlight": "gear*"}``: name globs or indices, as ``--highlight`` takes them),
    ``dump`` names targets to write beside the output. ``options`` (``DrawOptions``, its
    fields ``size``, default the pipeline's own, ``view``, ``azimuth``, ``elevation``, ``fov``,
    ``ortho``, ``up``, ``include`` and ``exclude`` keywords too) place the camera and load the
    model. Returns the last frame's result.
    """
    # the executor and its passes load for pipelines only, not for every drawing
    from blueprint.pipeline.run import PICTURE_SUFFIXES, parse_variables, run_video, save_result, with_images
    from blueprint.pipeline.spec import with_file

    images = {k: str(v) for k, v in (image or {}).items()}
    spec = with_images(pipeline, images)
    variables = parse_variables(set)
    ex = shared(renderer).executor
    plan = ex.plan(spec, variables, tuple(dump))
    model = None
    if input is not None:
        if plan.needs_model:
            model = as_model(input, options, pictures=True)
        else:
            free = [n for n in plan.images if spec.bind(variables).images[n].file is None]
            if not free:
                raise InputError(
                    f"{spec.source}: this pipeline takes no input file "
                    "(it reads no attributes and names its images)"
                )
            spec = with_file(spec, free[0], Path(input))
            plan = ex.plan(spec, variables, tuple(dump))
    elif plan.needs_model:
        raise InputError(
            f"{spec.source}: this pipeline renders attributes ({', '.join(plan.attributes)}): give a model"
        )
    bound = plan.bound
    videos = [n for n in plan.images if bound.images[n].video]
    if output is None:
        raise InputError("give an output file (-o)")
    # pipeline results are written by the pipeline (save_result, run_video), whose stills take
    # only its own suffixes
    if videos:
        output, _ = choose_writer(output, Kind.VIDEO)
    else:
        output = check_output(output, PICTURE_SUFFIXES)
    formats = {d: bound.format_of(plan.resolve(d)) for d in dump}
    if max_layers is not None and not 0 <= max_layers <= 256:
        raise InputError(f"max_layers must be between 0 (all) and 256, got {max_layers}")
    run = dict(variables=variables, dumps=tuple(dump))
    if parts:
        if model is None:
            raise InputError(f"{spec.source}: parts are parts of a model: give a model")
        run["parts"] = {name: designated_parts(model, chosen) for name, chosen in parts.items()}
    if max_layers is not None:
        run["max_layers"] = max_layers or None
    camera, size = None, options.size
    if model is not None:
        size = size or bound.size or (1024, 1024)
        camera = options.fit_camera(model, size)
    with out_of_memory(str(spec.source)):
        if videos:
            return run_video(ex, spec, videos, model, camera, size, output, frames, run, progress)
        result = ex.run(spec, model, camera, size=size, **run)
    save_result(result, output, formats)
    return result


# What a turntable takes of the options: the orbit's camera and the model file's parts.
TURNTABLE_OPTIONS = ("size", "elevation", "azimuth", "fov", "ortho", "up", "include", "exclude")


@takes_options(*TURNTABLE_OPTIONS, size=(640, 480), azimuth=0.0)
def turntable(
    model,
    output: str | os.PathLike,
    options: DrawOptions,
    *,
    frames: int = 60,
    fps: float = 30.0,
    pipeline="blueprint",
    set: dict | None = None,
    crf: int = 18,
    renderer: Renderer | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Orbit the camera once around ``model`` and write ``frames`` frames of ``pipeline``
    (default: the blueprint) as a video, atomically. ``options`` (``DrawOptions``, its fields
    ``size``, ``elevation``, ``azimuth`` (of the first frame), ``fov``, ``ortho``, ``up``,
    ``include`` and ``exclude`` keywords too) place the camera and load the model."""
    output, write = choose_writer(output, Kind.VIDEO)
    if frames < 1:
        raise InputError(f"frames must be at least 1, got {frames}")
    if frames > FRAME_LIMIT:
        raise InputError(f"frames must be at most {FRAME_LIMIT} (the limit), got {frames}")
    if not 0 < fps <= 240:
        raise InputError(f"fps must be in (0, 240], got {fps}")
    if not 0 <= crf <= 51:
        raise InputError(f"crf must be in [0, 51], got {crf}")
    from blueprint.pipeline.run import orbit, parse_variables, with_images

    renderer = shared(renderer)
    spec = with_images(pipeline, {})
    variables = parse_variables(set)
    ex = renderer.executor
    plan = ex.plan(spec, variables)
    if not plan.needs_model:
        raise InputError(f"{spec.source}: a turntable needs a pipeline that renders the model's attributes")
    model = as_model(model, options, pictures=True)
    size = check_size(options.size, 1, renderer.max_texture)
    turn = dict(elevation=options.elevation, azimuth=options.azimuth, fov=options.fov, ortho=options.ortho)
    cameras = orbit(model, frames, size, **turn)

    def pictures():
        # streamed: a frame is read back while the next one is drawn
        views = ({"camera": camera, "frame": index} for index, camera in enumerate(cameras))
        for index, result in enumerate(ex.stream(spec, model, views, size=size, variables=variables)):
            picture = result.image
            picture = picture[0] if picture.ndim == 4 else picture
            if picture.shape[-1] == 4:
                # composite over white where the pipeline leaves the background transparent
                alpha = picture[..., 3:4].astype(np.float32) / 255.0
                picture = np.round(picture[..., :3] * alpha + 255.0 * (1.0 - alpha)).astype(np.uint8)
            yield picture
            if progress is not None:
                progress(index + 1, frames)

    return write(output, pictures(), fps=fps, crf=crf)


# What a vector drawing file takes of the options: every one but the picture's own.
VECTOR_OPTIONS = options_but(
    "camera",
    "supersample",
    "min_fraction",
    "grid",
    "depth_threshold",
    "part_edges",
    "id_silhouettes",
    "smooth_contours",
    "profile",
)


@takes_options(*VECTOR_OPTIONS, prepare=zero_layers_are_all)
@one_blas_thread
def render_vector_file(
    model: Model | str | os.PathLike,
    output: str | os.PathLike,
    options: DrawOptions,
    *,
    renderer: Renderer | None = None,
) -> dict:
    """From a model (file or ``Model``) to a vector drawing file (.svg, .pdf or .dxf).

    Loads the model, peels its layers with ``renderer`` (default: the shared one), draws every
    line with its occlusion level and writes the file atomically. ``options`` (a
    ``DrawOptions``) and its fields as keywords, over it where both are given, say what is
    drawn: ``style`` is a raster style's name, a line style file or a ``VectorStyle`` (see
    ``blueprint.vector.style.vector_style``). A ``scale`` ('1:50') makes the view orthographic
    and lays the page out in millimetres (``units``: the model's length unit). ``max_layers``
    None or 0 peels every layer. ``section``, ``section_plane`` and ``section_keep`` draw a
    section view (as ``blueprint.render_frame`` does), its hatching and cut outline a group of
    their own. A plan sheet (``view="plan"``) is labelled, bordered and has a title block
    (``title``, default the model's name); ``sheet`` ('A4' ... 'A0') sets its paper.
    ``dimensions`` draws the overall width and height of orthographic views and the diameters
    of the circles their lines find (ISO 129, in mm). ``glyphs`` (a ``Glyphs`` or a glyph
    file) are drawn over one view, dashed or dimmed where hidden, its ``[[dimension]]``
    entries as dimensions; ``shade`` parts are filled polygons in depth order
    (``shade_opacity``), over the lines behind them.

    Returns
    -------
    dict
        ``path``, ``format``, ``bytes`` (file size), ``lines`` (polylines per occlusion level),
        ``points``, ``layers`` (peeled), ``up`` and ``up_reason`` (the model's up axis and where
        it came from), ``parts``, ``width``, ``height``, ``seconds`` (per stage
        and ``total``), ``chunks`` (those the model's mesh was drawn in where it did not fit
        the GPU whole, else 0: ``Capturer.chunks``).
    """
    start = time.perf_counter()
    output, write = choose_writer(output, Kind.DRAWING)
    options.vector_style  # noqa: B018 - a style the drawing cannot take fails before the model loads
    clock = time.perf_counter()
    stages.begin("read")
    loaded = as_model(model, options)
    load_s = time.perf_counter() - clock
    stages.begin("lines")
    renderer = shared(renderer)
    drawing = vector_drawing(loaded, options, renderer)
    clock = time.perf_counter()
    stages.begin("write")
    write(output, drawing)
    seconds = {"load": load_s, **drawing.seconds, "write": time.perf_counter() - clock}
    seconds["total"] = time.perf_counter() - start
    return {
        "path": str(output),
        "format": output.suffix.lower().lstrip("."),
        "bytes": output.stat().st_size,
        "lines": drawing.lines_per_level(),
        "points": int(len(drawing.points)),
        "layers": drawing.layers,
        "up": loaded.up,
        "up_reason": loaded.up_reason,
        "parts": len(drawing.part_names),
        "width": drawing.width,
        "height": drawing.height,
        "seconds": {k: round(v, 4) for k, v in seconds.items()},
        "chunks": renderer.capturer.chunks(loaded),
    }
