"""Benchmark: median whole-frame time (image read back) after warm-up, as JSON records; and the
frame interval when frames stream (each read back while the next is drawn)."""

from __future__ import annotations

import statistics
from collections.abc import Iterator, Sequence
from pathlib import Path

from rich.console import Console
from rich.progress import Progress

from blueprint.api import default_renderer
from blueprint.api.renderer import Renderer
from blueprint.compose.style import Style
from blueprint.gpu.device import check_size
from blueprint.pipeline.blueprint import stream_blueprint
from blueprint.scene.camera import Camera, fit_camera
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model


def time_frames(
    renderer: Renderer,
    model: Model,
    camera: Camera,
    *,
    size: tuple[int, int],
    max_layers: int | None,
    supersample: int,
    style: str | Style,
    frames: int,
    warmup: int,
) -> dict:
    """Median and spread of ``frames`` timed renders after ``warmup`` untimed ones, the median
    frame interval of as many streamed (``stream_blueprint``), and one profiled frame
    (synchronised after every stage) for the per-stage split.

    Parameters
    ----------
    renderer : Renderer
    model : Model
    camera : Camera
    size, max_layers, supersample, style
        The frame, as ``Renderer.render`` takes them.
    frames : int
        Timed frames, at least 1.
    warmup : int
        Untimed frames before them.

    Returns
    -------
    dict
        ``layers``, ``ms`` (median), ``ms_min``, ``ms_max``, ``fps``, ``ms_streamed`` (median
        interval), ``fps_streamed``, ``draws``, ``stages`` (ms per stage of the profiled frame)
        and ``capture``: how the layers were found (``Capture.way``: peel, k-buffer, A-buffer),
        which explains most of a figure.
    """
    options = dict(size=size, max_layers=max_layers, supersample=supersample, style=style)
    for _ in range(warmup):
        renderer.render(model, camera, **options)
    times = []
    frame = None
    for _ in range(frames):
        frame = renderer.render(model, camera, **options)
        times.append(frame.ms)
    streamed = [f.ms for f in stream_blueprint(renderer, model, [camera] * (warmup + frames), **options)]
    streamed = streamed[warmup:]
    profiled = renderer.render(model, camera, profile=True, **options)
    capture = renderer.executor.last_run.groups[0].capture
    return {
        "layers": frame.layers,
        "ms": round(statistics.median(times), 3),
        "ms_min": round(min(times), 3),
        "ms_max": round(max(times), 3),
        "fps": round(1000.0 / statistics.median(times), 1),
        "ms_streamed": round(statistics.median(streamed), 3),
        "fps_streamed": round(1000.0 / statistics.median(streamed), 1),
        "draws": frame.draws,
        "stages": {k: round(v, 3) for k, v in profiled.stages.items()},
        "capture": capture.way,
    }


def run_bench(
    models: Sequence[str | Path],
    *,
    sizes: Sequence[tuple[int, int]] = ((512, 512), (1024, 1024)),
    layer_options: Sequence[int | None] = (5, None),
    frames: int = 20,
    warmup: int = 3,
    supersample: int = 2,
    style: str = "blueprint",
) -> Iterator[dict]:
    """Time every model at every size and layer limit (None: all layers) with the shared
    renderer; yields one record a configuration (``blueprint bench`` prints them as JSON):
    ``renderer``, ``model``, ``triangles``, ``width``, ``height``, ``max_layers``,
    ``supersample`` and ``time_frames``' figures."""
    renderer = default_renderer()
    jobs = [(m, s, n) for m in models for s in sizes for n in layer_options]
    for size in sizes:
        check_size(size, supersample, renderer.max_texture)
    console = Console(stderr=True)
    # only a terminal gets the bar: in a pipe it would leave blank lines around errors
    with Progress(transient=True, console=console, disable=not console.is_terminal) as progress:
        task = progress.add_task("benchmark", total=len(jobs))
        loaded: dict = {}
        for path, size, max_layers in jobs:
            if path not in loaded:
                for old in loaded.values():
                    renderer.forget(old)
                loaded = {path: load_model(path)}
            model = loaded[path]
            camera = fit_camera(model, size)
            progress.update(task, description=f"{Path(path).name} {size[0]}x{size[1]}")
            record = {
                "renderer": renderer.info["renderer"],
                "model": Path(path).name,
                "triangles": model.triangle_count,
                "width": size[0],
                "height": size[1],
                "max_layers": max_layers or "all",
                "supersample": supersample,
            }
            record.update(
                time_frames(
                    renderer,
                    model,
                    camera,
                    size=size,
                    max_layers=max_layers,
                    frames=frames,
                    warmup=warmup,
                    supersample=supersample,
                    style=style,
                )
            )
            progress.advance(task)
            yield record
