"""Pipelines on files, the parts: ``--set`` and ``--image`` values, a result written as PNG or
NPZ with its dumps, a video filtered frame by frame, the cameras of a turntable.

The workflows from an input file to an output file, with the shared renderer when none is
given, are ``blueprint.api.files.run_pipeline`` and ``turntable``.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from blueprint.errors import InputError
from blueprint.export.files import atomic_write, save_png
from blueprint.pipeline.media import VideoWriter, read_video, video_info
from blueprint.pipeline.spec import PipelineSpec, load_pipeline, with_file
from blueprint.pipeline.state import Result
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


def parse_variables(values: dict | None) -> dict:
    """``--set`` values by name, text parsed as ``parse_value`` does, anything else as it is."""
    return {k: parse_value(v) if isinstance(v, str) else v for k, v in (values or {}).items()}


def with_images(pipeline, images: dict[str, str]) -> PipelineSpec:
    """A pipeline (a spec, a .toml file or a preset name) with image files given by name."""
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


def write_dumps(
    result: Result, output: Path, formats: dict[str, str], written: list[Path] | None = None
) -> list[Path]:
    """Each dump beside ``output``: ``STEM.NAME.png`` (8-bit; ``STEM.NAME.K.png`` per layer
    for per-layer targets) or ``STEM.NAME.npz`` (float and integer data, all layers). Each
    path is appended to ``written`` as it is written, which a caller keeps if one fails."""
    written = [] if written is None else written
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


def save_result(result: Result, output: Path, formats: dict[str, str]) -> None:
    """A result's output as ``output`` (NPZ, or PNG of 8-bit data), its dumps beside it: the
    dumps first and the output last, and the dumps written removed again where one fails, so
    that a failed run leaves no output."""

    def write_output() -> None:
        if output.suffix.lower() == ".npz":
            save_array(output, result.output, result.format)
            return
        array = result.output[0] if result.output.ndim == 4 else result.output
        picture = (
            result.image[0]
            if result.output.ndim == 4 and result.premultiplied
            else _to_8bit(array, result, "output")
        )
        save_png(output, _picture(picture))

    written: list[Path] = []
    try:
        write_dumps(result, output, formats, written)
        write_output()
    except BaseException:
        for path in written:
            path.unlink(missing_ok=True)
        raise


def run_video(ex, spec, videos, model, camera, size, output, frames, options, progress) -> Result:
    """Filter the video images ``videos`` of ``spec`` frame by frame into the video ``output``
    (at most ``frames`` frames); returns the last frame's result."""
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
