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

``--lineart`` measures Line Art on this machine instead, side by side (``lineart.py``: one
Blender process a run, file to PNG at ``--size``), a run of it, one of ours and one whole
``blueprint render`` process to SVG taking turns in each round. Then ``lineart`` holds its
figures (Blender's version named), ``process_seconds`` and ``process_cpu_seconds`` ours of
the whole process, and the speedups: ``speedup_vs_lineart`` and ``cpu_speedup_vs_lineart``
(our drawing in a running process against Line Art's file to PNG, as the recorded figures
are compared), ``process_...`` (process against process) and ``warm_...`` (against Line Art's
warm frame, the model already in Blender).

Whole processes run as an installed package does: with bytecode (compiled once, into a
temporary ``PYTHONPYCACHEPREFIX``, by a warm-up run; ``PYTHONDONTWRITEBYTECODE`` is removed
from their environment, since without bytecode every start compiles the package's modules
anew) and with Mesa's shader cache as the user has it, filled by that warm-up run.
``process_cold_cache_cpu_seconds`` is one more process with the shader cache empty, as on
the first run after installing (llvmpipe then compiles every shader with LLVM). ``--before
SRC`` adds a whole process of another source tree of the package (``SRC``, the folder holding
``blueprint``: an older commit's ``src``) to each round's turns, ``before_process_...``.

    python benchmarks/vector.py [--models-dir ../shared/models] [--size 1024 1024] [--runs 3]
                                [--lineart [--blender PATH] [--xvfb]] [--before SRC]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

from blueprint.api import default_renderer
from blueprint.api.files import render_vector_file
from blueprint.scene.loader import load_model
from blueprint.vector.lines import ADJACENCY, INTERSECTIONS
from blueprint.vector.occlusion.levels import PLANES

sys.path.insert(0, str(Path(__file__).resolve().parent))
from lineart import LineArt, find_model, process_environment, run_process  # noqa: E402  (a script beside this one)


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


def our_process(path: Path, output: Path, size, max_layers: int, env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU seconds (every thread) of the whole ``blueprint render`` process, file to SVG:
    Python's start, the imports and the GL context included, as Blender's start is in its
    figure."""
    command = [sys.executable, "-m", "blueprint", "render", str(path), "-o", str(output)]
    command += ["--size", *map(str, size), "--max-layers", str(max_layers)]
    done, wall, cpu = run_process(command, env)
    if done.returncode != 0:
        raise RuntimeError(f"blueprint render failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models-dir", type=Path, default=ROOT.parent / "shared" / "models")
    parser.add_argument("--size", nargs=2, type=int, default=[1024, 1024])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--max-layers", type=int, default=8)
    parser.add_argument("--keep", type=Path, default=None, help="Folder to keep the drawings in.")
    parser.add_argument(
        "--lineart",
        action="store_true",
        help="Measure Blender Line Art here too (benchmarks/lineart.py), a run of each in turn.",
    )
    parser.add_argument("--blender", default=os.environ.get("BLENDER", "blender"))
    parser.add_argument("--xvfb", action="store_true", help="Run Blender under xvfb-run.")
    parser.add_argument(
        "--before", type=Path, default=None, help="Another source tree of the package, taking turns too."
    )
    args = parser.parse_args()
    renderer = default_renderer()
    size = tuple(args.size)
    lineart = LineArt(args.blender, args.xvfb, size) if args.lineart else None
    with tempfile.TemporaryDirectory() as scratch:
        out_dir = args.keep or Path(scratch)
        out_dir.mkdir(parents=True, exist_ok=True)
        envs = {"process": process_environment(Path(scratch) / "pycache")}
        if args.before is not None:
            envs["before"] = process_environment(Path(scratch) / "pycache", args.before.resolve())
        for name, blender_s in MODELS.items():
            path = find_model(args.models_dir, name)
            if path is None:
                print(json.dumps({"model": name, "skipped": f"not found under {args.models_dir}"}))
                continue
            stem = path.stem
            runs, cpu, theirs = [], [], []
            processes: dict[str, list] = {turn: [] for turn in envs}
            for turn, env in envs.items():  # warm-up: bytecode written, shader cache filled
                our_process(path, out_dir / f"{stem}_{turn}.svg", size, args.max_layers, env)
            for run in range(max(args.runs, 1)):
                # side by side: Blender and we take turns, each first every other round, so
                # that the other loads of the machine fall on both alike
                turns = ["ours", *envs, "lineart"] if lineart else ["ours", *envs]
                for turn in turns if run % 2 == 0 else turns[::-1]:
                    if turn == "lineart":
                        theirs.append(lineart.run(path, out_dir / f"{stem}_lineart.png"))
                    elif turn in envs:
                        output = out_dir / f"{stem}_{turn}.svg"
                        processes[turn].append(our_process(path, output, size, args.max_layers, envs[turn]))
                    else:
                        for cache in (ADJACENCY, INTERSECTIONS, PLANES):
                            cache.clear()
                        summary, spent = timed(
                            path,
                            out_dir / f"{stem}.svg",
                            size=size,
                            max_layers=args.max_layers,
                            renderer=renderer,
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
            cpu_seconds = statistics.median(cpu)
            cold = {**envs["process"], "MESA_SHADER_CACHE_DIR": str(Path(scratch) / f"mesa-cold-{stem}")}
            cold_cpu = our_process(path, out_dir / f"{stem}_cold.svg", size, args.max_layers, cold)[1]
            process_s = statistics.median(w for w, _ in processes["process"])
            process_cpu = statistics.median(c for _, c in processes["process"])
            figures = {
                "renderer": renderer.info["renderer"],
                "model": path.name,
                "width": size[0],
                "height": size[1],
                "max_layers": args.max_layers,
                "layers": median["layers"],
                "seconds": round(seconds, 3),
                "runs": [round(t, 3) for t in totals],
                "cpu_seconds": round(cpu_seconds, 3),
                "same_model_seconds": warm["seconds"]["total"],
                "same_model_cpu_seconds": round(warm_cpu, 3),
                "stages": median["seconds"],
                "lines_per_level": median["lines"],
                "points": median["points"],
                "bytes": sizes,
                "process_seconds": round(process_s, 3),
                "process_cpu_seconds": round(process_cpu, 3),
                "process_cold_cache_cpu_seconds": round(cold_cpu, 3),
            }
            if "before" in processes:
                before = processes["before"]
                figures["before_process_seconds"] = round(statistics.median(w for w, _ in before), 3)
                figures["before_process_cpu_seconds"] = round(statistics.median(c for _, c in before), 3)
            if lineart is None:
                figures["blender_lineart_512_s"] = blender_s
                figures["speedup_vs_blender"] = round(blender_s / seconds, 2)
                figures["cpu_speedup_vs_blender"] = round(blender_s / cpu_seconds, 2)
            else:
                peer = LineArt.summary(theirs)
                figures["lineart"] = {"renderer": f"{lineart.version} Line Art", **peer}
                # a drawing in a running process against Line Art's file to PNG, as the
                # recorded figures were compared; and process against process
                figures["speedup_vs_lineart"] = round(peer["seconds"] / seconds, 2)
                figures["cpu_speedup_vs_lineart"] = round(peer["cpu_seconds"] / cpu_seconds, 2)
                figures["process_speedup_vs_lineart"] = round(peer["seconds"] / process_s, 2)
                figures["process_cpu_speedup_vs_lineart"] = round(peer["cpu_seconds"] / process_cpu, 2)
                figures["warm_speedup_vs_lineart"] = round(peer["warm_seconds"] / seconds, 2)
                figures["warm_cpu_speedup_vs_lineart"] = round(peer["warm_cpu_seconds"] / cpu_seconds, 2)
            print(json.dumps(figures), flush=True)


if __name__ == "__main__":
    main()
