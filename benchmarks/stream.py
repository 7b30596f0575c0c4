"""Streamed drawings a second: ``stream_blueprint`` frames (each picture read back while the next
is drawn) of one model from one camera and on a turntable (a new camera every frame), with the
A-buffer's fragments listed by the graphics pipeline, by the compute rasteriser
(``ABufferRow.compute_from``) and as the renderer chooses, the ways taken in turns
for ``--rounds`` rounds so that a machine's drift falls on all of them alike. One JSON object
per model, size and way: ``ms`` (wall time a frame over the stream, each round), ``fps`` (of the
best round), ``layers`` drawn.

    python benchmarks/stream.py MODEL... [--size 512 2048] [--supersample 1 2] [--max-layers 5 0]

The issue's cases: the crank case is ``rocker-arm.obj --size 512 --supersample 1 --max-layers 5``,
cycloidal ``--size 2048 --supersample 2 --max-layers 0`` (0: every layer).
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

from blueprint import Renderer, load_model
from blueprint.pipeline.blueprint import stream_blueprint
from blueprint.pipeline.run import orbit
from blueprint.render.table import CaptureTable
from blueprint.scene.camera import fit_camera


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+")
    parser.add_argument("--size", type=int, nargs="+", default=[512, 2048])
    parser.add_argument("--supersample", type=int, nargs="+", default=[2])
    parser.add_argument("--max-layers", type=int, nargs="+", default=[0], help="0: every layer")
    parser.add_argument("--frames", type=int, default=60, help="frames a stream")
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    with Renderer() as r:
        product = r.capture_table
        # capture in compute exists where image passes run in compute (a GPU)
        ways = {"product": product}
        if r.use_compute:
            ways = {"graphics": _listing(product, None), "compute": _listing(product, 0), **ways}
        for path in args.models:
            model = load_model(path)
            for size in args.size:
                for ss in args.supersample:
                    for most in args.max_layers:
                        options = dict(size=(size, size), supersample=ss, max_layers=most or None)
                        for cameras in ("one camera", "turntable"):
                            for row in _measure(r, model, options, cameras, ways, args):
                                print(json.dumps({"model": Path(path).name, **row}), flush=True)
        r.capture_table = product


def _listing(table: CaptureTable, start: int | None) -> CaptureTable:
    """``table`` with its A-buffer's fragments listed in compute from ``start`` pixels."""
    rows = tuple(replace(row, compute_from=start) if row.way == "A-buffer" else row for row in table.rows)
    return replace(table, rows=rows)


def _measure(r, model, options: dict, cameras: str, ways: dict, args) -> list[dict]:
    size = options["size"]
    if cameras == "turntable":
        views = orbit(model, args.frames, size)
    else:
        views = [fit_camera(model, size, "iso")] * args.frames
    times: dict[str, list[float]] = {way: [] for way in ways}
    layers: dict[str, int] = {}
    for _ in range(args.rounds):
        for way, table in ways.items():
            r.capture_table = table
            for _ in stream_blueprint(r, model, views[:10], **options):
                pass  # warm: programs built, the lists' room known
            t0 = time.perf_counter()
            for frame in stream_blueprint(r, model, views, **options):
                layers[way] = frame.layers
            times[way].append((time.perf_counter() - t0) / len(views) * 1e3)
    return [
        {
            "renderer": r.info["renderer"],
            "size": size[0],
            "supersample": options["supersample"],
            "max_layers": options["max_layers"] or "all",
            "cameras": cameras,
            "capture": way,
            "layers": layers[way],
            "ms": [round(t, 3) for t in times[way]],
            "fps": round(1e3 / min(times[way]), 1),
        }
        for way in ways
    ]


if __name__ == "__main__":
    main()
