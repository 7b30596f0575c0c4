"""Seconds from a model file to a vector drawing, next to Blender Line Art's file-to-PNG times.

Every run starts from the file (load, peel, lines, occlusion, simplify, write), with the GL
context already made; the model is loaded anew each time, so nothing cached from a previous
run helps. Prints one JSON object per model: median seconds of ``--runs`` runs, the stages of
the median run, ``same_model_seconds`` (a further view of a model already loaded, whose
view-independent work is cached), file sizes of SVG, PDF and DXF, and the reference figure
measured for Blender 5.2 Line Art at 512 x 512 on a 2-core machine without a GPU
(../shared/reference/README.md).

    python benchmarks/vector.py [--models-dir ../shared/models] [--size 1024 1024] [--runs 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from pathlib import Path

from blueprint.api import default_renderer
from blueprint.api.files import render_vector_file
from blueprint.scene.loader import load_model

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
            runs = []
            for _ in range(max(args.runs, 1)):
                runs.append(
                    render_vector_file(
                        path,
                        out_dir / f"{stem}.svg",
                        size=size,
                        max_layers=args.max_layers,
                        renderer=renderer,
                    )
                )
            # the same Model object again: the view-independent work (upload, welding, the
            # intersections between parts) is cached per model, as in a viewer or a batch of views
            loaded = load_model(path)
            warm = [
                render_vector_file(
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
                        "same_model_seconds": warm["seconds"]["total"],
                        "stages": median["seconds"],
                        "lines_per_level": median["lines"],
                        "points": median["points"],
                        "bytes": sizes,
                        "blender_lineart_512_s": blender_s,
                        "speedup_vs_blender": round(blender_s / seconds, 2),
                    }
                ),
                flush=True,
            )


if __name__ == "__main__":
    main()
