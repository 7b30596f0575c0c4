"""Seconds from a model file to a vector drawing, next to Blender Line Art's file-to-PNG times.

Every run starts from the file (load, peel, lines, occlusion, simplify, write), with the GL
context already made; the model is loaded anew each time and the caches of view-independent
line work are emptied first, so nothing from a previous run helps. Prints one JSON object per
model: median wall seconds of ``--runs`` runs and their process CPU seconds (every thread,
llvmpipe's included: the figure to trust on a loaded machine), the stages of the median run,
``same_model_seconds`` and ``same_model_cpu_seconds`` (a further view of the same mesh, whose
adjacency, intersection lines and face planes are cached: a viewer, a batch, a turntable), file sizes of
SVG, PDF and DXF, and the reference figure measured for Blender 5.2 Line Art at 512 x 512 on a
2-core machine without a GPU (../shared/reference/README.md).

    python benchmarks/vector.py [--models-dir ../shared/models] [--size 1024 1024] [--runs 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

from blueprint.api import default_renderer
from blueprint.api.files import render_vector_file
from blueprint.scene.loader import load_model
from blueprint.vector.lines import ADJACENCY, INTERSECTIONS
from blueprint.vector.occlusion.levels import PLANES


def timed(*args, **kwargs) -> tuple[dict, float]:
    """``render_vector_file`` and the process CPU seconds it took."""
    clock = time.process_time()
    summary = render_vector_file(*args, **kwargs)
    return summary, time.process_time() - clock


ROOT = Path(__file__).resolve().parents[1]
# model path under the models folder -> Blender Line Art seconds, file to PNG at 512 x 512
MODELS = {
    "trimesh/featuretype.STL": 0.90,
    "common-3d-test-models/stanford-bunny.obj": 1.25,
    "glTF-Sample-Models/2CylinderEngine.glb": 3.92,
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models-dir", type=Path, default=ROOT.parent / "shared" / "models")
    parser.add_argument("--size", nargs=2, type=int, default=[1024, 1024])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--max-layers", type=int, default=8)
    parser.add_argument("--keep", type=Path, default=None, help="Folder to keep the drawings in.")
    args = parser.parse_args()
    renderer = default_renderer()
    size = tuple(args.size)
    with tempfile.TemporaryDirectory() as scratch:
        out_dir = args.keep or Path(scratch)
        out_dir.mkdir(parents=True, exist_ok=True)
        for name, blender_s in MODELS.items():
            path = args.models_dir / name
            if not path.exists():  # a flat folder of models
                path = args.models_dir / Path(name).name
            if not path.exists():
                print(json.dumps({"model": name, "skipped": f"not found under {args.models_dir}"}))
                continue
            stem = path.stem
            runs, cpu = [], []
            for _ in range(max(args.runs, 1)):
                for cache in (ADJACENCY, INTERSECTIONS, PLANES):
                    cache.clear()
                summary, spent = timed(
                    path, out_dir / f"{stem}.svg", size=size, max_layers=args.max_layers, renderer=renderer
                )
                runs.append(summary)
                cpu.append(spent)
            # the same mesh again: its view-independent work (welding, the intersections between
            # parts) is cached, as in a viewer or a batch of views
            loaded = load_model(path)
            warm, warm_cpu = [
                timed(
                    loaded, out_dir / f"{stem}.svg", size=size, max_layers=args.max_layers, renderer=renderer
                )
                for _ in range(2)
            ][-1]
            totals = [r["seconds"]["total"] for r in runs]
            median = sorted(runs, key=lambda r: r["seconds"]["total"])[len(runs) // 2]
            sizes = {"svg": median["bytes"]}
            for fmt in ("pdf", "dxf"):
                other = render_vector_file(
                    path, out_dir / f"{stem}.{fmt}", size=size, max_layers=args.max_layers, renderer=renderer
                )
                sizes[fmt] = other["bytes"]
            seconds = statistics.median(totals)
            print(
                json.dumps(
                    {
                        "renderer": renderer.info["renderer"],
                        "model": path.name,
                        "width": size[0],
                        "height": size[1],
                        "max_layers": args.max_layers,
                        "layers": median["layers"],
                        "seconds": round(seconds, 3),
                        "runs": [round(t, 3) for t in totals],
                        "cpu_seconds": round(statistics.median(cpu), 3),
                        "same_model_seconds": warm["seconds"]["total"],
                        "same_model_cpu_seconds": round(warm_cpu, 3),
                        "stages": median["seconds"],
                        "lines_per_level": median["lines"],
                        "points": median["points"],
                        "bytes": sizes,
                        "blender_lineart_512_s": blender_s,
                        "speedup_vs_blender": round(blender_s / seconds, 2),
                        "cpu_speedup_vs_blender": round(blender_s / statistics.median(cpu), 2),
                    }
                ),
                flush=True,
            )


if __name__ == "__main__":
    main()
