"""How a frame's cost grows with layers and size: ms against layers (1, 5, 10, all) and size
(512², 1024², 2048²), per model and layer capture (peeled a geometry pass a layer, or every
layer from the A-buffer's one pass), so that a table shows whether cost follows fragments or
layers × screen. One JSON object per line (median of ``--frames`` frames after warm-up, image
read back, camera fitted once), then a markdown table per model.

    python benchmarks/layers.py MODEL... [--size 512 ...] [--layers 1 5 10 0] [--capture peel abuffer]
"""

from __future__ import annotations

import argparse
import json
import statistics
from dataclasses import replace
from pathlib import Path

from blueprint import Renderer, load_model
from blueprint.render.table import ABufferRow, CaptureTable, capture_table, device_max_bytes
from blueprint.scene.camera import fit_camera


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+")
    parser.add_argument("--size", type=int, nargs="+", default=[512, 1024, 2048])
    parser.add_argument("--layers", type=int, nargs="+", default=[1, 5, 10, 0], help="0: all")
    parser.add_argument("--capture", nargs="+", default=["peel", "abuffer"], choices=["peel", "abuffer"])
    parser.add_argument("--supersample", type=int, default=2)
    parser.add_argument("--frames", type=int, default=9)
    parser.add_argument("--warmup", type=int, default=3)
    args = parser.parse_args()
    rows = []
    with Renderer() as r:
        default = capture_table(r)
        listed = ABufferRow(max_bytes=device_max_bytes(r), min_layers=1, slim=r.use_compute)
        listed = replace(default.row("A-buffer") or listed, min_layers=1)
        tables = {
            # the A-buffer's rows are its own, not a k-buffer's that holds every layer
            "abuffer": (listed, *(row for row in default.rows if row.way == "peel" or _unpacking(row))),
            "peel": tuple(row for row in default.rows if row.way != "A-buffer"),
        }
        for path in args.models:
            model = load_model(path)
            for size in args.size:
                camera = fit_camera(model, (size, size))
                for capture in args.capture:
                    r.capture_table = CaptureTable(tables[capture], default.exact_depth)
                    for layers in args.layers:
                        options = dict(
                            size=(size, size), supersample=args.supersample, max_layers=layers or None
                        )
                        for _ in range(args.warmup):
                            r.render(model, camera, **options)
                        times = [r.render(model, camera, **options).ms for _ in range(args.frames)]
                        frame = r.render(model, camera, profile=True, **options)
                        row = {
                            "renderer": r.info["renderer"],
                            "model": Path(path).name,
                            "triangles": model.triangle_count,
                            "size": size,
                            "supersample": args.supersample,
                            "max_layers": layers or "all",
                            "capture": capture,
                            "layers": frame.layers_shown,
                            "ms": round(statistics.median(times), 2),
                            "stages": {k: round(v, 2) for k, v in frame.stages.items()},
                        }
                        rows.append(row)
                        print(json.dumps(row), flush=True)
            r.forget(model)
    for name in dict.fromkeys(row["model"] for row in rows):
        print(f"\n{name} (ms a frame, {rows[0]['renderer']}, supersample {args.supersample})\n")
        columns = [layers or "all" for layers in args.layers]
        print("| size | capture | " + " | ".join(f"{c} layer{'' if c == 1 else 's'}" for c in columns) + " |")
        print("|---|---|" + "---|" * len(columns))
        for size in args.size:
            for capture in args.capture:
                cells = {
                    row["max_layers"]: row["ms"]
                    for row in rows
                    if row["model"] == name and row["size"] == size and row["capture"] == capture
                }
                print(f"| {size}² | {capture} | " + " | ".join(str(cells.get(c, "")) for c in columns) + " |")


def _unpacking(row) -> bool:
    """A k-buffer row that takes any frame its thresholds allow."""
    return row.way == "k-buffer" and not row.whole_frames


if __name__ == "__main__":
    main()
