"""Start-up: whole-process wall times of ``import blueprint``, ``blueprint --help`` and a small
binary STL drawn to a 512x512 PNG (command line and API), median of several runs; one JSON object.

    python benchmarks/startup.py [--runs 7] [--size 512 512] [--model FILE.stl]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _small_stl(path: Path) -> Path:
    """A binary STL of a 24-sided ring (numpy alone: the benchmark loads no trimesh either)."""
    n = 24
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rings = [np.stack([r * np.cos(a), r * np.sin(a), np.full(n, z)], 1) for r in (0.5, 1.0) for z in (0, 0.4)]
    v = np.concatenate(rings)
    tris = []
    for k in range(n):
        m = (k + 1) % n
        for lo, hi in ((n, 3 * n), (0, 2 * n)):  # outer wall, inner wall
            tris += [(lo + k, lo + m, hi + m), (lo + k, hi + m, hi + k)]
        for b, c in ((0, n), (2 * n, 3 * n)):  # bottom and top annuli
            tris += [(b + k, c + k, c + m), (b + k, c + m, b + m)]
    triangles = v[np.array(tris)].astype("<f4")
    record = np.dtype([("normal", "<f4", 3), ("triangle", "<f4", (3, 3)), ("attribute", "<u2")])
    data = np.zeros(len(triangles), record)
    data["triangle"] = triangles
    path.write_bytes(b"\0" * 80 + len(data).to_bytes(4, "little") + data.tobytes())
    return path


def _wall(args: list[str], runs: int) -> dict:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(args, check=True, capture_output=True, timeout=300)
        times.append(time.perf_counter() - start)
    return {"median_s": round(statistics.median(times), 3), "min_s": round(min(times), 3), "runs": runs}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--size", nargs=2, type=int, default=(512, 512))
    parser.add_argument("--model", type=Path, default=None, help="A binary STL (default: a generated ring).")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        stl = args.model or _small_stl(Path(tmp) / "ring.stl")
        out = Path(tmp) / "out.png"
        py = sys.executable
        w, h = map(str, args.size)
        api = f"import blueprint; blueprint.draw({str(stl)!r}, size=({w}, {h})).save({str(out)!r})"
        info = subprocess.run(
            [py, "-m", "blueprint", "info", "--json"], check=True, capture_output=True, text=True
        ).stdout
        record = {
            "renderer": json.loads(info)["renderer"],
            "cpus": os.cpu_count(),
            "load_average": round(os.getloadavg()[0], 2),
            "model": stl.name,
            "width": args.size[0],
            "height": args.size[1],
            "import_blueprint": _wall([py, "-c", "import blueprint"], args.runs),
            "help": _wall([py, "-m", "blueprint", "--help"], args.runs),
            "render_png_cli": _wall(
                [py, "-m", "blueprint", "render", str(stl), "-o", str(out), "--size", w, h], args.runs
            ),
            "draw_png_api": _wall([py, "-c", api], args.runs),
        }
    print(json.dumps(record))


if __name__ == "__main__":
    main()
