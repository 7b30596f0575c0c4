"""Pipelines on files: a model, an image or a video in; PNG, NPZ or video out; turntables.

The command line (``blueprint pipeline run``, ``blueprint turntable``) is a thin shell over
``run_pipeline`` and ``turntable``; every option is an argument of the same name.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from blueprint.errors import InputError
from blueprint.export.files import atomic_write, check_output, save_png
from blueprint.pipeline.executor import Result, executor_for
from blueprint.pipeline.media import VIDEO_FORMATS, VideoWriter, read_video, video_info
from blueprint.pipeline.spec import PipelineSpec, load_pipeline, with_file
from blueprint.scene.camera import Camera, fit_camera

PICTURE_SUFFIXES = (".png", ".npz")


def parse_assignments(pairs, what: str) -> dict[str, str]:
    """``["NAME=VALUE", ...]`` to a dict (``what`` names the option in errors)."""
    out = {}
    for pair in pairs or ():
        name, sep, value = str(pair).partition("=")
        if not sep or not name.strip():
            raise InputError(f"{what} takes NAME=VALUE, got {pair!r}")
        out[name.strip()] = value.strip()
    return out


def parse_value(text: str):
    """A --set value: a TOML number, boolean or quoted string, else the text itself."""
    import tomllib

    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def _spec(pipeline, images: dict[str, str]) -> PipelineSpec:
    spec = pipeline if isinstance(pipeline, PipelineSpec) else load_pipeline(str(pipeline))
    for name, path in images.items():
        spec = with_file(spec, name, Path(path))
    return spec


def _to_8bit(array: np.ndarray, result: Result, name: str) -> np.ndarray:
    if array.dtype != np.uint8:
        raise InputError(f"{name} is {result.format if name == 'output' else 'not 8-bit'}: write it as .npz")
    if result.premultiplied and array.shape[-1] == 4 and name == "output":
        return result.image
    return array


def save_array(path: Path, array: np.ndarray, fmt: str) -> Path:
    """NPZ with ``data`` (the array, row 0 at the top) and ``format``."""

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, data=array, format=np.array(fmt))

    return atomic_write(path, write)


def _picture(array: np.ndarray) -> np.ndarray:
    return array[..., 0] if array.shape[-1] == 1 else array


def write_dumps(result: Result, output: Path, formats: dict[str, str]) -> list[Path]:
    """Each dump beside ``output``: ``STEM.NAME.png`` (8-bit; ``STEM.NAME.K.png`` per layer
    for per-layer targets) or ``STEM.NAME.npz`` (float and integer data, all layers)."""
    written = []
    for name, array in result.dumps.items():
        if array.dtype == np.uint8:
            if array.ndim == 4:
                for k, layer in enumerate(array):
                    written.append(
                        save_png(output.with_name(f"{output.stem}.{name}.{k}.png"), _picture(layer))
                    )
            else:
                written.append(save_png(output.with_name(f"{output.stem}.{name}.png"), _picture(array)))
        else:
            written.append(save_array(output.with_name(f"{output.stem}.{name}.npz"), array, formats[name]))
    return written


def run_pipeline(
    pipeline,
    input: str | os.PathLike | None = None,
    output: str | os.PathLike | None = None,
    *,
    size: tuple[int, int] | None = None,
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    set: dict | None = None,
    image: dict[str, str] | None = None,
    dump: tuple[str, ...] = (),
    max_layers: int | None = None,
    frames: int | None = None,
    renderer=None,
    progress: Callable[[int, int], None] | None = None,
) -> Result:
    """Run a pipeline file (or preset) on a model, an image or a video and write the output.

    ``input`` is the model when the pipeline renders attributes; otherwise it fills the first
    image the pipeline declares without a file. A video input is filtered frame by frame into
    a video ``output`` (at most ``frames`` frames). ``set`` overrides variables, ``image``
    gives image files by name, ``dump`` names targets to write beside the output. Returns the
    last frame's result.
    """
    from blueprint.api import default_renderer
    from blueprint.scene.loader import load_model

    renderer = renderer or default_renderer()
    images = {k: str(v) for k, v in (image or {}).items()}
    spec = _spec(pipeline, images)
    variables = {k: parse_value(v) if isinstance(v, str) else v for k, v in (set or {}).items()}
    ex = executor_for(renderer)
    plan = ex.plan(spec, variables, tuple(dump))
    model = None
    if input is not None:
        if plan.peel:
            model = load_model(input, up=up)
        else:
            free = [n for n in plan.images if spec.bind(variables).images[n].file is None]
            if not free:
                raise InputError(
                    f"{spec.source}: this pipeline takes no input file "
                    "(it reads no attributes and names its images)"
                )
            spec = with_file(spec, free[0], Path(input))
            plan = ex.plan(spec, variables, tuple(dump))
    elif plan.peel:
        raise InputError(
            f"{spec.source}: this pipeline renders attributes ({', '.join(plan.attributes)}): give a model"
        )
    bound = plan.bound
    videos = [n for n in plan.images if bound.images[n].video]
    if output is None:
        raise InputError("give an output file (-o)")
    output = check_output(output, tuple(VIDEO_FORMATS) if videos else PICTURE_SUFFIXES)
    formats = {d: bound.format_of(plan.resolve(d)) for d in dump}
    if max_layers is not None and not 0 <= max_layers <= 256:
        raise InputError(f"max-layers must be between 0 (all) and 256, got {max_layers}")
    options = dict(variables=variables, dumps=tuple(dump))
    if max_layers is not None:
        options["max_layers"] = max_layers or None
    camera = None
    if model is not None:
        w, h = size or bound.size or (1024, 1024)
        camera = fit_camera(model, (w, h), view, azimuth=azimuth, elevation=elevation, fov=fov, ortho=ortho)
        size = (w, h)
    if videos:
        return _run_video(ex, spec, videos, model, camera, size, output, frames, options, progress)
    result = ex.run(spec, model, camera, size=size, **options)
    if output.suffix.lower() == ".npz":
        save_array(output, result.output, result.format)
    else:
        array = result.output[0] if result.output.ndim == 4 else result.output
        picture = (
            result.image[0]
            if result.output.ndim == 4 and result.premultiplied
            else _to_8bit(array, result, "output")
        )
        save_png(output, _picture(picture))
    write_dumps(result, output, formats)
    return result


def _run_video(ex, spec, videos, model, camera, size, output, frames, options, progress) -> Result:
    infos = {n: video_info(spec.bind(options["variables"]).images[n].file) for n in videos}
    first = infos[videos[0]]
    count = min(info[2] for info in infos.values())
    if frames is not None:
        count = min(count, frames)
    if count <= 0:
        raise InputError(f"{spec.bind(options['variables']).images[videos[0]].file}: the video has no frames")
    bound = spec.bind(options["variables"])
    readers = {n: read_video(bound.images[n].file) for n in videos}
    result = None
    writer = None
    try:
        for index in range(count):
            frame_images = {n: next(r) for n, r in readers.items()}
            result = ex.run(spec, model, camera, size=size, images=frame_images, frame=index, **options)
            picture = result.image
            picture = picture[0] if picture.ndim == 4 else picture
            if writer is None:
                writer = VideoWriter(output, (picture.shape[1], picture.shape[0]), fps=first[1])
                writer.__enter__()
            writer.write(picture)
            if progress is not None:
                progress(index + 1, count)
    except BaseException as exc:
        if writer is not None:
            writer.__exit__(type(exc), exc, exc.__traceback__)
        raise
    finally:
        for r in readers.values():
            r.close()
    writer.__exit__(None, None, None)
    return result


def orbit(
    model,
    frames: int,
    size: tuple[int, int],
    *,
    elevation: float | None = None,
    azimuth: float = 0.0,
    fov: float = 30.0,
    ortho: bool = False,
) -> list[Camera]:
    """``frames`` cameras a full turn around the model's up axis, all at one distance (the
    farthest any single view needs), so the model neither grows nor shrinks as it turns."""
    if frames < 1:
        raise InputError(f"frames must be at least 1, got {frames}")
    el = elevation if elevation is not None else 25.0
    cams = [
        fit_camera(
            model, size, "front", azimuth=azimuth + 360.0 * i / frames, elevation=el, fov=fov, ortho=ortho
        )
        for i in range(frames)
    ]

    def distance(c: Camera) -> float:
        return math.dist(c.eye, c.target)

    far = max(distance(c) for c in cams)
    height = max(c.height for c in cams)
    out = []
    for c in cams:
        d = distance(c)
        direction = (np.asarray(c.eye) - np.asarray(c.target)) / d
        eye = tuple(float(v) for v in np.asarray(c.target) + direction * far)
        shift = far - d
        out.append(dataclasses.replace(c, eye=eye, near=c.near + shift, far=c.far + shift, height=height))
    return out


def turntable(
    model,
    output: str | os.PathLike,
    *,
    frames: int = 60,
    fps: float = 30.0,
    size: tuple[int, int] = (640, 480),
    pipeline="blueprint",
    elevation: float | None = None,
    azimuth: float = 0.0,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    set: dict | None = None,
    crf: int = 18,
    renderer=None,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Orbit the camera once around ``model`` and write ``frames`` frames of ``pipeline``
    (default: the blueprint) as a video, atomically."""
    from blueprint.api import default_renderer
    from blueprint.scene.loader import load_model
    from blueprint.scene.model import Model

    output = check_output(output, tuple(VIDEO_FORMATS))
    if not 0 < fps <= 240:
        raise InputError(f"fps must be in (0, 240], got {fps}")
    if not 0 <= crf <= 51:
        raise InputError(f"crf must be in [0, 51], got {crf}")
    renderer = renderer or default_renderer()
    spec = _spec(pipeline, {})
    variables = {k: parse_value(v) if isinstance(v, str) else v for k, v in (set or {}).items()}
    ex = executor_for(renderer)
    plan = ex.plan(spec, variables)
    if not plan.peel:
        raise InputError(f"{spec.source}: a turntable needs a pipeline that renders the model's attributes")
    model = model if isinstance(model, Model) else load_model(model, up=up)
    size = tuple(int(v) for v in size)
    from blueprint.render.renderer import check_size

    check_size(size, 1, renderer.max_texture)
    cameras = orbit(model, frames, size, elevation=elevation, azimuth=azimuth, fov=fov, ortho=ortho)
    with VideoWriter(output, size, fps=fps, crf=crf) as writer:
        for index, camera in enumerate(cameras):
            result = ex.run(spec, model, camera, size=size, variables=variables, frame=index)
            picture = result.image
            picture = picture[0] if picture.ndim == 4 else picture
            if picture.shape[-1] == 4:
                # composite over white where the pipeline leaves the background transparent
                alpha = picture[..., 3:4].astype(np.float32) / 255.0
                picture = np.round(picture[..., :3] * alpha + 255.0 * (1.0 - alpha)).astype(np.uint8)
            writer.write(picture)
            if progress is not None:
                progress(index + 1, frames)
    return output
