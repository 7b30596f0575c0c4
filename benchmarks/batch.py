"""Batch drawing throughput: one collection (every shared model, or the example model copied,
x views x PNG + SVG) drawn by ``blueprint.api.batch`` on 1 worker and on N workers, one per EGL
device where the host has several GPUs (two sharing device 0 where it has one, as with
llvmpipe). Prints one JSON object per configuration and one with the scaling ratio.

    python benchmarks/batch.py [--models DIR] [--views iso,top,front,right] [--size 512 512]
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from pathlib import Path

from blueprint.api.batch import batch, choose_devices
from blueprint.examples import example_path

SHARED = Path(__file__).resolve().parents[1] / ".." / "shared" / "models"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", type=Path, default=SHARED if SHARED.is_dir() else None)
    parser.add_argument(
        "--copies",
        type=int,
        default=0,
        help="Draw this many copies of the example model instead of --models.",
    )
    parser.add_argument("--views", default="iso,top,front,right")
    parser.add_argument("--formats", default="png,svg")
    parser.add_argument("--size", nargs=2, type=int, default=(512, 512))
    args = parser.parse_args()
    views, formats = args.views.split(","), args.formats.split(",")
    devices = choose_devices("all")
    many = len(devices) if len(devices) > 1 else 2
    with tempfile.TemporaryDirectory() as tmp:
        if args.copies or args.models is None:
            folder = Path(tmp) / "models"
            folder.mkdir()
            for k in range(args.copies or 8):
                shutil.copy(example_path(), folder / f"gearbox{k}.glb")
            inputs = [folder]
        else:
            inputs = [args.models]
        rates = {}
        for workers in (1, many):
            # one worker a device, or two workers sharing the one device
            chosen = devices[:workers] if len(devices) > 1 else devices[:1]
            manifest = batch(
                inputs,
                Path(tmp) / f"out{workers}",
                views=views,
                formats=formats,
                workers=workers,
                gpus=chosen,
                size=tuple(args.size),
            )
            drawings = manifest["drawn"] * len(views) * len(formats)
            ok = [r for r in manifest["inputs"] if not r.get("error")]
            renderer = ok[0]["renderer"] if ok else None
            rates[workers] = drawings / manifest["seconds"]
            print(
                json.dumps(
                    {
                        "renderer": renderer,
                        "workers": workers,
                        "devices": chosen,
                        "inputs": len(manifest["inputs"]),
                        "failed": manifest["failed"],
                        "drawings": drawings,
                        "seconds": manifest["seconds"],
                        "drawings_per_s": round(rates[workers], 3),
                    }
                )
            )
    ratio = rates[many] / rates[1]
    gpus = min(many, len(devices))
    print(json.dumps({"scaling": round(ratio, 3), "workers": many, "devices": gpus, "target": 0.8 * gpus}))


if __name__ == "__main__":
    main()
