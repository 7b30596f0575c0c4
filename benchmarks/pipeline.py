"""Pipeline benchmark: the cases of paper 004 (the G²-buffer) and the blueprint preset against
Renderer.render. Prints one JSON object per line.

    python benchmarks/pipeline.py [MODEL] [--frames N] [--warmup N] [--blueprint-size W H ...]

Each figure is the median wall time of whole frames after warm-up: attributes rendered, every
pass run, the output read back to the CPU (which waits for the GPU, so frames are
synchronised). ``fps`` is 1000 / median ms, next to the paper's figure on a Radeon 9700 PRO
(2003, a 1024x1024 viewport unless noted; its models are not ours, so only the order of
magnitude compares).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

from blueprint import examples
from blueprint.api import default_renderer
from blueprint.pipeline import load_pipeline, render_blueprint
from blueprint.scene.camera import fit_camera
from blueprint.scene.loader import load_model

# (case, preset, size, the paper's fps)
PAPER_CASES = [
    ("roberts", "edges-roberts", (1024, 1024), 185.0),
    ("sobel", "edges-sobel", (1024, 1024), 80.0),
    ("dilated_edges", "dilated-edges", (1024, 1024), 64.0),
    ("supersampled_blur", "supersampled-blur", (512, 512), 145.0),
    ("screening", "screening", (1024, 768), 78.0),
]


def _median(run, frames: int, warmup: int) -> tuple[float, list[float]]:
    for _ in range(warmup):
        run()
    times = []
    for _ in range(frames):
        t0 = time.perf_counter()
        run()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times), times


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model", nargs="?", default=None, help="model file (default: the example gearbox)")
    parser.add_argument("--frames", type=int, default=10)
    parser.add_argument("--warmup", type=int, default=2)
    parser.add_argument("--blueprint-size", nargs=2, type=int, action="append", metavar=("W", "H"))
    parser.add_argument("--skip-paper", action="store_true")
    args = parser.parse_args(argv)
    renderer = default_renderer()
    model = load_model(args.model) if args.model else examples.gearbox()
    name = Path(args.model).name if args.model else "gearbox (example)"
    ex = renderer.executor
    base = {"renderer": renderer.info["renderer"], "model": name, "triangles": model.triangle_count}
    if not args.skip_paper:
        for case, preset, size, paper_fps in PAPER_CASES:
            spec = load_pipeline(preset)
            camera = fit_camera(model, size)
            last = {}

            def run(spec=spec, camera=camera, size=size, last=last):
                last["result"] = ex.run(spec, model, camera, size=size)

            ms, times = _median(run, args.frames, args.warmup)
            record = {
                **base,
                "case": case,
                "pipeline": preset,
                "width": size[0],
                "height": size[1],
                "passes": len(ex.plan(spec).passes),
                "draws": last["result"].draws,
                "ms": round(ms, 3),
                "ms_min": round(min(times), 3),
                "fps": round(1000.0 / ms, 1),
                "paper_fps_radeon9700": paper_fps,
            }
            print(json.dumps(record), flush=True)
    for size in [tuple(s) for s in args.blueprint_size or [(512, 512), (1024, 1024)]]:
        camera = fit_camera(model, size)
        frames = {}

        def old(size=size, camera=camera, frames=frames):
            frames["render"] = renderer.render(model, camera, size=size)

        def new(size=size, camera=camera, frames=frames):
            frames["pipeline"] = render_blueprint(renderer, model, camera, size=size)

        # alternate so drift on a busy machine hits both alike
        old_times, new_times = [], []
        for _ in range(args.warmup):
            old()
            new()
        for _ in range(args.frames):
            for fn, times in ((old, old_times), (new, new_times)):
                t0 = time.perf_counter()
                fn()
                times.append((time.perf_counter() - t0) * 1e3)
        a, b = frames["render"].image.astype(float), frames["pipeline"].image.astype(float)
        record = {
            **base,
            "case": "blueprint",
            "width": size[0],
            "height": size[1],
            "layers": frames["render"].layers,
            "render_ms": round(statistics.median(old_times), 3),
            "pipeline_ms": round(statistics.median(new_times), 3),
            "ratio": round(statistics.median(new_times) / statistics.median(old_times), 3),
            "render_draws": frames["render"].draws,
            "pipeline_draws": frames["pipeline"].draws,
            "max_mean_abs_diff": round(float(abs(a - b).mean(axis=(0, 1)).max()), 4),
        }
        print(json.dumps(record), flush=True)


if __name__ == "__main__":
    sys.exit(main())
