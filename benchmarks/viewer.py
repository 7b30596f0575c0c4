"""The viewer's frame rates: while the view moves (the turntable) and at rest (full drawings),
one JSON line a case, each case a viewer process of its own in a window.

    python benchmarks/viewer.py [--frames 60] [--still-frames 10] [--scan 8] [--size 800 600]
                                [--cases rocker-full,rocker,scan] [--workdir DIR]

Cases: ``rocker-full``, the rocker arm (20 K triangles) with ``--interactive-scale 1``: moving
frames at the window's size, supersample 1 and the 5 layers asked for, whatever they cost
(the frame rate issue 38 sets a target for); ``rocker``, the same with the quality ladder
(``--moving-fps``, 10 by default); ``scan``, a generated dense scan (an icosphere of
``20 * 4**n`` triangles, noisy, as ``benchmarks/prepare.py`` writes it; 8: 1.3 M) with the
ladder. Each line: ``moving`` (the turntable's ``fps`` over every timed frame, the frames
each step drew, the ``step`` it settled at and the ``step_fps`` since) and ``still`` (full
drawings, supersample 2, of the view the turntable stopped at), with the model's triangles,
the renderer and ``seconds``, the whole process.

Without ``DISPLAY`` it starts an Xvfb of its own (the Debian package ``xvfb``). It runs against
whichever tree ``PYTHONPATH`` names, so that two trees can be compared in turns; a tree whose
viewer has no ladder reports its moving frames alone (``still`` and the steps missing).
Frame rates on a machine shared with other work vary with its load: compare in turns.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROCKER = Path("/work/shared/models/common-3d-test-models/rocker-arm.obj")

# One case's process: the viewer measuring itself, its result printed as JSON.
_CHILD = """
import inspect, json, sys
from blueprint.api.options import DrawOptions
from blueprint.viewer.app import run_viewer
path, width, height, scale, frames, still = sys.argv[1:7]
given = dict(interactive_scale=float(scale), frames=int(frames), still_frames=int(still))
known = inspect.signature(run_viewer).parameters
options = DrawOptions(size=(int(width), int(height)), max_layers=5)
result = run_viewer(path, options, **{k: v for k, v in given.items() if k in known})
print(json.dumps(result))
"""


def _display() -> tuple[str, subprocess.Popen | None]:
    """The display to use: ``DISPLAY``, else a fresh Xvfb's (and its process)."""
    if os.environ.get("DISPLAY"):
        return os.environ["DISPLAY"], None
    if shutil.which("Xvfb") is None:
        sys.exit("no DISPLAY and no Xvfb (Debian package xvfb) to start one")
    read, write = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write), "-screen", "0", "1920x1200x24", "-nolisten", "tcp"],
        pass_fds=(write,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    with os.fdopen(read) as fh:
        number = fh.readline().strip()
    if not number:
        server.kill()
        sys.exit("Xvfb did not start")
    return f":{number}", server


def _case(name: str, path: Path, args, display: str, scale: float) -> dict:
    """One viewer process measuring ``path``; its JSON and the case's settings."""
    still = args.still_frames if name != "scan" else min(args.still_frames, 3)
    start = time.perf_counter()
    run = subprocess.run(
        [
            sys.executable,
            "-c",
            _CHILD,
            str(path),
            *map(str, args.size),
            str(scale),
            str(args.frames),
            str(still),
        ],
        env={**os.environ, "DISPLAY": display},
        capture_output=True,
        text=True,
        check=False,
    )
    seconds = time.perf_counter() - start
    lines = [line for line in run.stdout.splitlines() if line.startswith("{")]
    if run.returncode or not lines:
        return {"case": name, "failed": run.stderr.strip().splitlines()[-1:]}
    result = json.loads(lines[-1])
    moving_keys = ("frames", "fps", "ms", "draw_ms_median", "steps", "step", "step_frames", "step_fps")
    return {
        "case": name,
        "model": path.name,
        "triangles": result.get("triangles"),
        "size": list(args.size),
        "interactive_scale": scale,
        "moving": {k: result[k] for k in moving_keys if k in result},
        "still": result.get("still"),
        "renderer": result.get("renderer"),
        "seconds": round(seconds, 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=60, help="turntable frames timed (after a warm-up)")
    parser.add_argument(
        "--still-frames", type=int, default=10, help="full drawings timed (the scan: 3 at most)"
    )
    parser.add_argument("--scan", type=int, default=8, help="subdivisions of the scan (8: 1.3 M triangles)")
    parser.add_argument("--size", type=int, nargs=2, default=(800, 600))
    parser.add_argument("--cases", default="rocker-full,rocker,scan")
    parser.add_argument("--workdir", default="/tmp/blueprint-bench-viewer", help="where the scan is written")
    args = parser.parse_args()
    cases = [c for c in args.cases.split(",") if c]
    unknown = set(cases) - {"rocker-full", "rocker", "scan"}
    if unknown:
        sys.exit(f"unknown cases: {', '.join(sorted(unknown))}")
    scan = Path(args.workdir) / f"scan{args.scan}.stl"
    if "scan" in cases and not scan.exists():
        sys.path.insert(0, str(Path(__file__).parent))
        from prepare import write_scan

        scan.parent.mkdir(parents=True, exist_ok=True)
        write_scan(scan, args.scan)
    display, server = _display()
    try:
        for name in cases:
            path = scan if name == "scan" else ROCKER
            scale = 1.0 if name == "rocker-full" else 0.0
            print(json.dumps(_case(name, path, args, display, scale)), flush=True)
    finally:
        if server is not None:
            server.terminate()
            server.wait(10)


if __name__ == "__main__":
    main()
