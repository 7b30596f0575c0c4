"""Vector memory: where a vector drawing's memory goes, phase by phase, with the counts that
drive it; one JSON line a case.

    python benchmarks/vector_memory.py MODEL [MODEL ...] [--size 1024 1024] [--max-layers 0]
                                       [--memory 20G] [--src DIR]

Each model is drawn to an SVG by ``blueprint render`` in a process of its own, in that process
(``BLUEPRINT_SUPERVISE=0``), the budget raised (``--memory``, ``BLUEPRINT_MEMORY_LIMIT``) so that
the guard does not refuse what is measured. The phases are marked around the drawing's own
functions (``vector.drawing``'s ``model_segments``, ``join_polylines``, ``sample_polylines``,
``Occlusion.levels``, ``split_by_level``): at each mark the kernel's peak resident memory
(VmHWM) is read and reset (``/proc/self/clear_refs``), so each phase's figure is its own peak;
Linux only. Each line: ``model``, ``size``, ``triangles`` (drawn), ``segments`` (placed),
``points`` (of the joined polylines), ``samples``, ``layers``, ``probed`` (pixels whose layers
were read back, where they were), ``phases`` (MiB: the peak of ``before`` (reading, the
capture set up), ``segments``, ``join``, ``sample``, ``levels``, ``pieces`` and ``rest``),
``seconds`` and ``error`` where the command failed. On a GPU host the figures are the host's
alone; on a software rasteriser its GPU buffers are in the process too. ``--src`` names the
source tree to run (default: this one's).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# run in the measured process: the phases marked around the drawing's functions
_PROBE = r"""
import json, sys
import blueprint.vector.drawing as d

def status():
    with open("/proc/self/status") as fh:
        peak = next(int(line.split()[1]) >> 10 for line in fh if line.startswith("VmHWM"))
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")
    return peak

phases, counts = {}, {}
current = ["before"]

def mark(name):
    peak = status()
    phases[current[0]] = max(phases.get(current[0], 0), peak)
    current[0] = name

def wrapped(owner, name, phase, count):
    original = getattr(owner, name)
    def call(*args, **kwargs):
        mark(phase)
        result = original(*args, **kwargs)
        count(result, args)
        return result
    setattr(owner, name, call)

def counted(key, value):
    counts[key] = value

def segments_counted(result, args):
    counted("triangles", int(args[0].triangle_count))
    counted("segments", len(result))

wrapped(d, "model_segments", "segments", segments_counted)
wrapped(d, "join_polylines", "join", lambda r, a: counted("points", len(r.points)))
wrapped(d, "sample_polylines", "sample", lambda r, a: counted("samples", len(r.line)))

def levels_counted(result, args):
    counted("layers", int(result[1]))
    peeled = args[0].peeled
    if peeled is not None and peeled.pixels is not None:
        counted("probed", int(len(peeled.pixels)))

wrapped(d.Occlusion, "levels", "levels", levels_counted)
wrapped(d, "split_by_level", "pieces", lambda r, a: None)
wrapped(d, "_chained", "rest", lambda r, a: None)

import blueprint.cli as cli
try:
    cli.main(sys.argv[1:])
except SystemExit as stop:
    code = stop.code or 0
else:
    code = 0
mark("end")
print("VECTOR_MEMORY " + json.dumps({"phases": phases, "counts": counts}), file=sys.stderr)
sys.exit(code)
"""


def measure(model: Path, size, max_layers: int, memory: str, src: Path) -> dict:
    """One model's line (see the module's docstring)."""
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "out.svg"
        command = [sys.executable, "-c", _PROBE, "render", str(model), "-o", str(out)]
        command += ["--size", str(size[0]), str(size[1]), "--max-layers", str(max_layers)]
        env = {
            **os.environ,
            "PYTHONPATH": os.pathsep.join(p for p in (str(src), os.environ.get("PYTHONPATH")) if p),
            "BLUEPRINT_SUPERVISE": "0",
            "BLUEPRINT_MEMORY_LIMIT": memory,
        }
        start = time.perf_counter()
        proc = subprocess.run(command, capture_output=True, text=True, env=env)
        seconds = time.perf_counter() - start
    line = {"model": model.name, "size": list(size), "seconds": round(seconds, 2)}
    found = [text for text in proc.stderr.splitlines() if text.startswith("VECTOR_MEMORY ")]
    if proc.returncode != 0 or not found:
        told = [text for text in proc.stderr.splitlines() if text.strip() and text not in found]
        line["error"] = (told or ["no output"])[-1]
        return line
    record = json.loads(found[-1].split(" ", 1)[1])
    line.update(record["counts"])
    names = ("before", "segments", "join", "sample", "levels", "pieces", "rest")
    line["phases"] = {name: record["phases"].get(name) for name in names}
    line["peak_mib"] = max(value for value in record["phases"].values())
    return line


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="+", type=Path)
    parser.add_argument("--size", nargs=2, type=int, default=(1024, 1024), metavar=("W", "H"))
    parser.add_argument("--max-layers", type=int, default=0)
    parser.add_argument("--memory", default="20G", help="the budget each drawing runs under")
    parser.add_argument("--src", type=Path, default=ROOT / "src", help="the source tree to run")
    args = parser.parse_args(argv)
    for model in args.models:
        print(
            json.dumps(measure(model, tuple(args.size), args.max_layers, args.memory, args.src)), flush=True
        )


if __name__ == "__main__":
    main()
