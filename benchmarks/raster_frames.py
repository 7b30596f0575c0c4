"""Whole frames of one model with the A-buffer's fragments listed by the compute rasteriser and
by the graphics pipeline, in the order given, each compute dispatch of the rasteriser timed
(the GPU finished before and after it): where a frame of a big model spends its capture, and
whether the two ways draw the same picture. One JSON object per frame, then one comparing the
first picture of each way.

    python benchmarks/raster_frames.py MODEL [--size 2048] [--ways graphics,compute,compute]
                                       [--lists-bytes 36G] [--chunk FACES] [--keep DIR]

``--lists-bytes`` raises the A-buffer's cap (``ABufferRow.max_bytes``) so that a frame the
device's own cap would send to the graphics pipeline (the rasteriser's buffers beside the lists
not fitting it) is listed in compute all the same; ``--chunk`` sets the rasteriser's faces a
chunk (``ComputeRaster.chunk``). Each frame's line: its seconds (``profile``: synchronised
stages), layers, the pixels apart from the first graphics frame's picture (channels more than
8 apart), and for each rasteriser listing its bins' room and its dispatches' milliseconds, four
a chunk (set-up, scan, binning, rasterising). ``--keep`` writes the first picture of each way,
at half size, as PNG.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import moderngl
import numpy as np

from blueprint import Renderer, load_model, settings
from blueprint.export.files import save_png
from blueprint.render.raster import ComputeRaster


class Timed:
    """Times every compute dispatch issued while the rasteriser lists a frame's fragments."""

    def __init__(self, ctx) -> None:
        self.ctx, self.dispatches, self.listings = ctx, None, []
        run, fragments = moderngl.ComputeShader.run, ComputeRaster.fragments
        timed = self

        def timed_run(prog, *args, **kwargs):
            if timed.dispatches is None:
                return run(prog, *args, **kwargs)
            timed.ctx.finish()
            start = time.perf_counter()
            run(prog, *args, **kwargs)
            timed.ctx.finish()
            timed.dispatches.append(round((time.perf_counter() - start) * 1e3, 2))
            return None

        def timed_fragments(raster, *args, **kwargs):
            timed.dispatches = []
            try:
                room = fragments(raster, *args, **kwargs)
            finally:
                dispatches, timed.dispatches = timed.dispatches, None
            timed.listings.append({"room": room, "dispatches_ms": dispatches})
            return room

        moderngl.ComputeShader.run = timed_run
        ComputeRaster.fragments = timed_fragments


def size_bytes(text: str) -> int:
    """``--lists-bytes``: digits, or digits and K, M or G (``settings.parse_size``)."""
    value = settings.parse_size(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"not a size: {text!r} (digits, or digits and K, M or G)")
    return value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model")
    parser.add_argument("--size", type=int, default=2048)
    parser.add_argument("--ways", default="graphics,compute,compute")
    parser.add_argument("--lists-bytes", type=size_bytes, default=None, help="the A-buffer's cap, e.g. 36G")
    parser.add_argument("--chunk", type=int, default=None, help="the rasteriser's faces a chunk")
    parser.add_argument("--keep", type=Path, default=None)
    args = parser.parse_args()
    start = time.perf_counter()
    model = load_model(args.model)
    print(
        json.dumps(
            {
                "model": Path(args.model).name,
                "triangles": model.triangle_count,
                "load_s": round(time.perf_counter() - start, 2),
            }
        ),
        flush=True,
    )
    with Renderer() as r:
        default = r.capture_table
        listed = default.row("A-buffer")
        if listed is None:
            raise SystemExit("this driver has no A-buffer (OpenGL 4.3)")
        if args.lists_bytes:
            listed = replace(listed, max_bytes=max(listed.max_bytes, args.lists_bytes))
        if args.chunk:
            r.compute_raster.chunk = args.chunk
        compute_from = listed.compute_from if listed.compute_from is not None else 0
        print(
            json.dumps(
                {
                    "renderer": r.info["renderer"],
                    "storage_binding_bytes": r.device.storage_bytes,
                    "chunk": r.compute_raster.chunk,
                    "lists_bytes": listed.max_bytes,
                }
            ),
            flush=True,
        )
        timed = Timed(r.ctx)
        first: dict[str, np.ndarray] = {}
        for way in args.ways.split(","):
            row = replace(listed, compute_from=compute_from if way == "compute" else None)
            r.capture_table = replace(
                default, rows=tuple(row if x is default.row("A-buffer") else x for x in default.rows)
            )
            timed.listings.clear()
            r.ctx.finish()
            start = time.perf_counter()
            frame = r.render(model, size=(args.size, args.size), max_layers=None, profile=True)
            r.ctx.finish()
            seconds = time.perf_counter() - start
            picture = frame.image.astype(np.int16)
            first.setdefault(way, picture)
            reference = first.get("graphics")
            apart = None if reference is None else int((np.abs(picture - reference).max(-1) > 8).sum())
            print(
                json.dumps(
                    {
                        "way": way,
                        "frame_s": round(seconds, 3),
                        "layers": frame.layers,
                        "pixels_apart_from_graphics": apart,
                        "stages_ms": {k: round(v, 2) for k, v in frame.stages.items()},
                        "listings": timed.listings,
                    }
                ),
                flush=True,
            )
        if args.keep is not None:
            args.keep.mkdir(parents=True, exist_ok=True)
            stem = Path(args.model).stem
            for way, picture in first.items():
                save_png(
                    args.keep / f"{stem}-{way}.png", np.ascontiguousarray(picture.astype(np.uint8)[::2, ::2])
                )


if __name__ == "__main__":
    main()
