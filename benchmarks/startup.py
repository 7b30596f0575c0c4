"""Start-up: whole-process wall times of ``import blueprint``, ``blueprint --help`` and a small
binary STL drawn to a 512x512 PNG (command line and API), median of several runs, and where a
drawing's process spends its time; one JSON object.

    python benchmarks/startup.py [--runs 7] [--size 512 512] [--model FILE.stl]

The processes run as an installed package does: with bytecode (compiled once, into a temporary
``PYTHONPYCACHEPREFIX``, by a warm-up run of each command; ``PYTHONDONTWRITEBYTECODE`` is
removed from their environment) and with Mesa's shader cache as the user has it (the warm-up
fills it). ``no_bytecode`` is the API drawing in this environment with
``PYTHONDONTWRITEBYTECODE=1``: a source tree without bytecode then compiles every module of the
package at every start. ``phases`` splits one drawing's process (medians, ms): imports, model
load, context (``Renderer()``: EGL context and capability probes), the first frame
(``programs``: the GL programs it built and the time building them), a second, warm frame, and
the PNG save, in wall time and in the main thread's CPU time (which other processes' load
changes less; llvmpipe rasterises in threads of its own, which it leaves out).
``cold_shader_cache`` is the same with Mesa's shader cache empty, as on the first run after
installing (llvmpipe compiles its shaders by LLVM then).
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
from lineart import process_environment  # noqa: E402  (a script beside this one)

# One drawing's process, timed from inside: prints a JSON object of milliseconds per phase.
_PHASES = """
import json, sys, time
start = time.perf_counter(), time.thread_time()
marks, cpu = {}, {}
def mark(name, since):
    marks[name] = (time.perf_counter() - since[0]) * 1e3
    cpu[name] = (time.thread_time() - since[1]) * 1e3
    return time.perf_counter(), time.thread_time()
t = start
import numpy
t = mark("import_numpy", t)
import blueprint
from blueprint.api import draw, renderer
from blueprint.export import writers
t = mark("import_blueprint", t)
import blueprint.gpu.device as device
built = []
def timed(build):
    def run(*args, **kwargs):
        s = time.perf_counter()
        program = build(*args, **kwargs)
        built.append((time.perf_counter() - s) * 1e3)
        return program
    return run
device.build_program = timed(device.build_program)
device.build_compute = timed(device.build_compute)
model = blueprint.load_model(sys.argv[1])
t = mark("load_model", t)
blueprint.api._renderer = blueprint.Renderer()
t = mark("context", t)
size = (int(sys.argv[3]), int(sys.argv[4]))
drawing = blueprint.draw(model, size=size)
t = mark("first_frame", t)
marks["programs"] = len(built)
marks["programs_ms"] = sum(built)
blueprint.draw(model, size=size)
t = mark("warm_frame", t)
drawing.save(sys.argv[2])
t = mark("save_png", t)
marks["total"] = (t[0] - start[0]) * 1e3
cpu["total"] = (t[1] - start[1]) * 1e3
print(json.dumps({"wall_ms": marks, "cpu_ms": cpu}))
"""


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


def _wall(args: list[str], runs: int, env: dict[str, str]) -> dict:
    subprocess.run(args, check=True, capture_output=True, timeout=300, env=env)  # warm-up
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(args, check=True, capture_output=True, timeout=300, env=env)
        times.append(time.perf_counter() - start)
    return {"median_s": round(statistics.median(times), 3), "min_s": round(min(times), 3), "runs": runs}


def _phases(args: list[str], runs: int, env: dict[str, str], warm_up: bool = True) -> dict:
    if warm_up:
        subprocess.run(args, check=True, capture_output=True, timeout=300, env=env)
    records = []
    for _ in range(runs):
        done = subprocess.run(args, check=True, capture_output=True, text=True, timeout=300, env=env)
        records.append(json.loads(done.stdout))
    return {
        part: {k: round(statistics.median(r[part][k] for r in records), 1) for k in records[0][part]}
        for part in records[0]
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--size", nargs=2, type=int, default=(512, 512))
    parser.add_argument("--model", type=Path, default=None, help="A binary STL (default: a generated ring).")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        stl = args.model or _small_stl(folder / "ring.stl")
        out = folder / "out.png"
        py = sys.executable
        w, h = map(str, args.size)
        env = process_environment(folder / "pycache")
        api = f"import blueprint; blueprint.draw({str(stl)!r}, size=({w}, {h})).save({str(out)!r})"
        phases = [py, "-c", _PHASES, str(stl), str(out), w, h]
        info = subprocess.run(
            [py, "-m", "blueprint", "info", "--json"], check=True, capture_output=True, text=True, env=env
        ).stdout
        # the interpreter's and site-packages' bytecode as installed, none written for the package
        source_only = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
        cold = process_environment(folder / "pycache", MESA_SHADER_CACHE_DIR=str(folder / "mesa-cold"))
        record = {
            "renderer": json.loads(info)["renderer"],
            "cpus": os.cpu_count(),
            "load_average": round(os.getloadavg()[0], 2),
            "model": stl.name,
            "width": args.size[0],
            "height": args.size[1],
            "bytecode": "cached: compiled into a temporary PYTHONPYCACHEPREFIX by a warm-up run",
            "mesa_shader_cache": "off" if os.environ.get("MESA_SHADER_CACHE_DISABLE") else "on",
            "import_blueprint": _wall([py, "-c", "import blueprint"], args.runs, env),
            "help": _wall([py, "-m", "blueprint", "--help"], args.runs, env),
            "render_png_cli": _wall(
                [py, "-m", "blueprint", "render", str(stl), "-o", str(out), "--size", w, h], args.runs, env
            ),
            "draw_png_api": _wall([py, "-c", api], args.runs, env),
            "no_bytecode": {"draw_png_api": _wall([py, "-c", api], args.runs, source_only)},
            "phases": _phases(phases, args.runs, env),
            # one run: a second one would find the cache this one filled
            "cold_shader_cache": _phases(phases, 1, cold, warm_up=False),
        }
    print(json.dumps(record))


if __name__ == "__main__":
    main()
