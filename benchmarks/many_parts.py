"""Many parts: GLBs of N instances of one box in a 3D grid, each overlapping its neighbours along
x a little (so that intersection lines are found between them), rendered with ``blueprint
render`` under ``/usr/bin/time``; prints the peak resident memory and the seconds (wall and
CPU) of each, and one JSON object.

    python benchmarks/many_parts.py [--counts 1000,10000,30000,100000] [--size 512]
                                    [--output svg] [--memory 6G] [--keep DIR]

Run it with ``PYTHONPATH`` naming the tree to measure; ``--memory`` limits each run's address
space (``ulimit -v``); ``--keep`` leaves the models and the drawings in DIR.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from hostile import box_arrays, glb

# Instance spacing in box sizes: neighbours along x overlap, along y and z they stand apart;
# every other one along x is shifted by SHIFT, so that their faces cut through each other.
SPACING = (0.9, 1.25, 1.25)
SHIFT = (0.0, 0.1, 0.1)


def grid_nodes(count: int) -> list[dict]:
    """glTF nodes placing ``count`` instances of mesh 0 in a grid about as deep as it is wide."""
    side = max(1, round(count ** (1 / 3)))
    i = np.arange(count)
    cells = np.stack([i % side, (i // side) % side, i // (side * side)], axis=1)
    places = cells * np.asarray(SPACING) + (cells[:, :1] % 2) * np.asarray(SHIFT)
    return [{"mesh": 0, "translation": place} for place in places.tolist()]


def many_boxes(count: int) -> bytes:
    """A GLB of ``count`` instances of a unit box (12 triangles) in ``grid_nodes``."""
    v, f = box_arrays((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    return glb(grid_nodes(count), list(range(count)), v, faces=f)


def _limit(memory: int | None):
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))

    return None if memory is None else apply


def _bytes(text: str) -> int:
    return int(float(text[:-1]) * 1024 ** " KMG".index(text[-1].upper())) if text[-1].isalpha() else int(text)


def measure(model: Path, out: Path, size: int, memory: int | None = None) -> dict:
    """Exit code, seconds and peak resident MiB of ``blueprint render model -o out``, under an
    address-space limit of ``memory`` bytes where given."""
    blueprint = Path(sys.executable).with_name("blueprint")
    command = ["/usr/bin/time", "-v", str(blueprint), "render", str(model), "-o", str(out)]
    done = subprocess.run(
        [*command, "--size", str(size), str(size)], capture_output=True, text=True, preexec_fn=_limit(memory)
    )
    field = lambda name: re.search(rf"{name}: (.*)", done.stderr).group(1)  # noqa: E731
    wall = [float(x) for x in field(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\)").split(":")]
    errors = [line for line in done.stderr.splitlines() if line.startswith("blueprint:") or "Error" in line]
    return {
        "code": done.returncode,
        "seconds": round(sum(x * 60**k for k, x in enumerate(reversed(wall))), 2),
        "cpu_seconds": round(
            float(field(r"User time \(seconds\)")) + float(field(r"System time \(seconds\)")), 2
        ),
        "peak_mib": round(int(field(r"Maximum resident set size \(kbytes\)")) / 1024),
        "error": errors[-1] if errors else "",
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", default="1000,10000,30000,100000")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--output", default="svg")
    parser.add_argument("--memory", type=_bytes)
    parser.add_argument("--keep", type=Path)
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp()) if args.keep is None else args.keep
    folder.mkdir(parents=True, exist_ok=True)
    results = {}
    try:
        for count in (int(c) for c in args.counts.split(",")):
            model = folder / f"boxes{count}.glb"
            model.write_bytes(many_boxes(count))
            result = measure(model, folder / f"boxes{count}.{args.output}", args.size, args.memory)
            results[count] = result
            print(
                f"{count:>7} boxes: exit {result['code']}, {result['seconds']} s "
                f"({result['cpu_seconds']} s CPU), {result['peak_mib']} MiB {result['error']}",
                flush=True,
            )
    finally:
        if args.keep is None:
            shutil.rmtree(folder)
    print(json.dumps({"pythonpath": os.environ.get("PYTHONPATH", ""), "size": args.size, "runs": results}))


if __name__ == "__main__":
    main()
