"""``blueprint silhouettes MODEL``: triangle-ID silhouettes of a still model or of a deforming one.

The click command is registered in ``blueprint.cli`` by the lead; ``main`` runs it on its own
with the CLI's error handling (one line, exit code 2).
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from pathlib import Path

import click
import numpy as np

from blueprint.cli import camera_options, progress_bar
from blueprint.errors import InputError
from blueprint.scene.camera import VIEWS

from .deform import KINDS
from .gpu import MAX_LAYERS, STILL_METHODS

DEFAULT_SIZE = (800, 600)


def write_video(path: str | Path, frames: Iterable[np.ndarray], fps: float = 30.0) -> int:
    """Encode (H, W, 3) uint8 frames as H.264 MP4, written atomically; returns the frame count.

    Odd widths and heights are padded by one pixel (players expect 4:2:0 chroma, which needs
    even sizes) with the colour of the frame's edge.
    """
    from blueprint.pipeline.media import VideoWriter

    def even(frame: np.ndarray) -> np.ndarray:
        h, w = frame.shape[:2]
        return np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")

    frames = iter(frames)
    first = next(frames, None)
    if first is None:
        raise InputError(f"{path}: no frames to write")
    first = even(first)
    with VideoWriter(Path(path), (first.shape[1], first.shape[0]), fps) as video:
        video.write(first)
        for frame in frames:
            video.write(even(frame))
    return video.frames


@click.command("silhouettes")
@click.argument("model", type=click.Path(path_type=Path))
@click.option(
    "-o",
    "--output",
    type=click.Path(path_type=Path),
    required=True,
    help="PNG to write, or MP4 with --animate.",
)
@camera_options
@click.option(
    "--method",
    type=click.Choice(STILL_METHODS),
    default="gpu-vertex",
    show_default=True,
    help="gpu-vertex: triangle IDs + vertex storage (no preprocessing); gpu-idlist: triangle IDs + "
    "precomputed adjacency lists; cpu: object-space edges (weld, connect, orient, classify), "
    "hidden ones included.",
)
@click.option(
    "--layers",
    type=int,
    default=1,
    show_default=True,
    help="Depth layers (GPU methods): 1 draws what is visible, more add hidden silhouettes, fainter.",
)
@click.option("--animate", type=click.Choice(KINDS), default=None, help="Deform the model every frame.")
@click.option("--frames", type=int, default=60, show_default=True, help="Frames of the animation.")
@click.option("--fps", type=float, default=30.0, show_default=True, help="Frames per second of the video.")
@click.option(
    "--split-at",
    type=float,
    default=0.5,
    show_default=True,
    help="Fraction of the animation after which the model splits into two pieces (1: never).",
)
def silhouettes(
    model,
    output,
    size,
    view,
    azimuth,
    elevation,
    fov,
    ortho,
    up,
    method,
    layers,
    animate,
    frames,
    fps,
    split_at,
):
    """Draw MODEL's silhouettes from a triangle-ID buffer into a PNG, or, with --animate, the
    silhouettes of MODEL deforming (and splitting in two part-way) into an MP4."""

    from blueprint.api import default_renderer
    from blueprint.export.files import check_output, save_png
    from blueprint.scene.loader import load_model

    from .gpu import animate_silhouettes, render_silhouettes

    if view not in VIEWS:
        raise InputError(f"unknown view {view!r} (choose {', '.join(VIEWS)})")
    if animate is None and Path(output).suffix.lower() == ".mp4":
        raise InputError(f"{output}: a video needs --animate twist or --animate wave")
    output = check_output(output, (".mp4",) if animate else (".png",))
    if frames < 1:
        raise InputError(f"frames must be at least 1, got {frames}")
    if not 0 < fps <= 240:
        raise InputError(f"fps must be in (0, 240], got {fps:g}")
    if not 1 <= layers <= MAX_LAYERS:
        raise InputError(f"layers must be an integer from 1 to {MAX_LAYERS}, got {layers}")
    size = tuple(size) if size else DEFAULT_SIZE
    camera = dict(view=view, azimuth=azimuth, elevation=elevation, fov=fov, ortho=ortho)
    loaded = load_model(model, up=up)
    renderer = default_renderer()

    if animate is None:
        t0 = time.perf_counter()
        image = render_silhouettes(
            loaded, method=method, layers=layers, size=size, renderer=renderer, **camera
        )
        ms = (time.perf_counter() - t0) * 1e3
        save_png(output, image)
        click.echo(
            f"{output}: {size[0]}x{size[1]}, {loaded.triangle_count} triangles, {method}, "
            f"{ms:.1f} ms on {renderer.info['renderer']}"
        )
        return

    times: list[float] = []
    pictures = animate_silhouettes(
        loaded,
        animate=animate,
        frames=frames,
        split_at=split_at,
        method=method,
        layers=layers,
        size=size,
        renderer=renderer,
        **camera,
    )
    with progress_bar(f"{animate} {method}") as progress:

        def tracked():
            for done, (image, ms) in enumerate(pictures, start=1):
                times.append(ms)
                yield image
                progress(done, frames)

        count = write_video(output, tracked(), fps)
    click.echo(
        f"{output}: {count} frames of {size[0]}x{size[1]}, {loaded.triangle_count} triangles, {method}, "
        f"{float(np.median(times)):.1f} ms per frame (median) on {renderer.info['renderer']}"
    )


def main(argv: list[str] | None = None) -> None:
    """``blueprint silhouettes`` as a program of its own."""
    from blueprint.cli import run

    run(silhouettes, argv, "blueprint silhouettes")


if __name__ == "__main__":
    main()
