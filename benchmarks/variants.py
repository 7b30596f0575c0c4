"""Time the renderer's alternative code paths on this machine, so the defaults are measured.

Image-space passes as compute or fragment shaders; the back-face tie-break as two culled draws
or one draw writing depth; layers peeled one geometry pass a layer or, where the driver has
framebuffer fetch or fragment shader interlock, several a pass (k-buffer, whatever the
model's triangles per pixel). Prints one JSON object per model, size and variant.

    python benchmarks/variants.py MODEL... [--size 512 512] [--supersample 1] [--frames 30]
"""

from __future__ import annotations

import argparse
import json
import statistics
from dataclasses import replace
from pathlib import Path

from blueprint import Renderer, load_model
from blueprint.render.table import CaptureTable, PeelRow, capture_table
from blueprint.scene.camera import fit_camera


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+")
    parser.add_argument("--size", nargs=2, type=int, action="append")
    parser.add_argument("--supersample", type=int, action="append")
    parser.add_argument("--max-layers", type=int, default=5)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--warmup", type=int, default=5)
    args = parser.parse_args()
    with Renderer() as r:
        default = capture_table(r)
        kbuffer = default.row("k-buffer")
        supported = kbuffer is not None
        computes = (True, False) if r.ctx.version_code >= 430 else (False,)
        variants = [(c, b, False) for c in computes for b in (True, False)]
        variants += [(c, True, True) for c in computes if supported]
        for path in args.models:
            model = load_model(path)
            for size in [tuple(s) for s in (args.size or [[512, 512]])]:
                camera = fit_camera(model, size)
                for ss in args.supersample or [1, 2]:
                    for use_compute, in_shader, kbuffered in variants:
                        r.use_compute = use_compute
                        # the variant's tie-break at every size, the k-buffer whatever the
                        # density, no A-buffer (benchmarks/layers.py times that)
                        peel = PeelRow(culled_from=None if in_shader else (0, 0))
                        rows = (replace(kbuffer, min_density=0.0, whole_frames=False), peel)
                        r.capture_table = CaptureTable(rows if kbuffered else (peel,), default.exact_depth)
                        options = dict(size=size, supersample=ss, max_layers=args.max_layers)
                        for _ in range(args.warmup):
                            r.render(model, camera, **options)
                        times = [r.render(model, camera, **options).ms for _ in range(args.frames)]
                        profiled = r.render(model, camera, profile=True, **options)
                        ms = statistics.median(times)
                        print(
                            json.dumps(
                                {
                                    "renderer": r.info["renderer"],
                                    "model": Path(path).name,
                                    "triangles": model.triangle_count,
                                    "width": size[0],
                                    "height": size[1],
                                    "supersample": ss,
                                    "max_layers": args.max_layers,
                                    "image_passes": "compute" if use_compute else "fragment",
                                    "tie_break": "one draw, shader depth"
                                    if in_shader
                                    else "two culled draws",
                                    "peel": (
                                        ("k-buffer, interlock" if kbuffer.interlock else "k-buffer, fetch")
                                        if kbuffered
                                        else "a pass a layer"
                                    ),
                                    "ms": round(ms, 3),
                                    "fps": round(1000 / ms, 1),
                                    "stages": {k: round(v, 3) for k, v in profiled.stages.items()},
                                }
                            ),
                            flush=True,
                        )
                r.forget(model)


if __name__ == "__main__":
    main()
