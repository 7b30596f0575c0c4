"""Preparing a model for the GPU, stage by stage: seconds and memory a triangle, one JSON line
a case, each case in a process of its own.

    python benchmarks/prepare.py [--scans 7,8,9] [--shared] [--workdir DIR]

Cases are generated dense scans (an icosphere of ``20 * 4**n`` triangles, its vertices moved
along their radius by noise of 5 % of an edge, written as binary STL: a triangle soup, three
vertices a triangle, as scanners write them) and, with ``--shared``, the shared test models.
Each process loads its model, then runs every stage of the preparation on its own, in turn:

``load`` (``load_model``: reading and the loader's checks), ``degenerate`` (the degenerate
faces, as the loader finds them), ``up`` (the up-axis guess from the shape), ``environment``
(skyboxes and ground planes), ``weld`` (``weld_ids``), ``creases`` (``crease_vertices``),
``normals`` (``corner_normals``, welding and creases included), ``gpu_arrays`` (all that
``GpuMesh`` makes before its buffers, normals included, as a first drawing of the model does),
``gpu_arrays_again`` (the same for a second model of the same content: another view, a batch),
``gpu_arrays_ids`` (without normals, for ID passes) and ``adjacency`` (the welded edges of a
vector drawing).

``seconds`` and ``cpu_seconds`` are wall and process CPU times a stage; ``peak_mb`` the stage's
peak resident memory above what the process held before it (``/proc/self/clear_refs``), and
``bytes_per_triangle`` the same over the triangles, measured in a second process whose
allocator returns every large array it frees (so that a stage's peak is its own; that costs
time, so the times come from the first). ``process_peak_mb`` is the process's peak
(the highest of the stages' and the start's), ``loaded_mb`` its resident memory with the model
loaded. It runs
against whichever tree ``PYTHONPATH`` names, so that two trees can be compared in turns:
stages a tree does not have are left out.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from functools import partial
from pathlib import Path

import numpy as np

SHARED = Path("/work/shared/models")
SHARED_MODELS = [
    "common-3d-test-models/stanford-bunny.obj",
    "common-3d-test-models/fandisk.obj",
    "common-3d-test-models/rocker-arm.obj",
    "common-3d-test-models/ogre.obj",
    "libigl-tutorial-data/armadillo.obj",
    "Euclid/dragon.ply",
    "glTF-Sample-Models/2CylinderEngine.glb",
    "trimesh/counter.unitsmm.STL",
    "trimesh/converted/cycloidal.glb",
    "trimesh/converted/FM1_satellite.glb",
]
# Every large array mapped and unmapped on its own, so that the memory a stage frees leaves the
# process and the next stage's peak is its own (glibc keeps freed memory below its mapping
# threshold, which it raises as arrays are freed).
_MALLOC = {"MALLOC_MMAP_THRESHOLD_": str(1 << 17), "MALLOC_TRIM_THRESHOLD_": str(1 << 17)}
_ICOSAHEDRON_FACES = np.array(
    [
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
        [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
        [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ]
)  # fmt: skip


def icosphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    """(V, 3) float64 unit-sphere vertices and (F, 3) int64 faces of a subdivided icosahedron,
    ``20 * 4**subdivisions`` faces."""
    t = (1.0 + 5.0**0.5) / 2.0
    v = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    )  # fmt: skip
    v /= np.linalg.norm(v, axis=1)[:, None]
    f = _ICOSAHEDRON_FACES
    for _ in range(subdivisions):
        edges = np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        keys, inverse = np.unique(edges[:, 0] * len(v) + edges[:, 1], return_inverse=True)
        middle = (v[keys // len(v)] + v[keys % len(v)]) / 2.0
        middle /= np.linalg.norm(middle, axis=1)[:, None]
        ab, bc, ca = (inverse.reshape(-1, 3) + len(v)).T
        a, b, c = f.T
        f = np.concatenate([np.c_[a, ab, ca], np.c_[b, bc, ab], np.c_[c, ca, bc], np.c_[ab, bc, ca]])
        v = np.concatenate([v, middle])
    return v, f


def write_scan(path: Path, subdivisions: int, seed: int = 0) -> int:
    """Write the noisy icosphere scan as binary STL; returns its triangle count."""
    v, f = icosphere(subdivisions)
    edge = float(np.linalg.norm(v[f[:, 0]] - v[f[:, 1]], axis=1).mean())
    v *= 1.0 + np.random.default_rng(seed).normal(0.0, 0.05 * edge, (len(v), 1))
    record = np.zeros(len(f), [("normal", "<f4", 3), ("triangle", "<f4", (3, 3)), ("attribute", "<u2")])
    record["triangle"] = v[f]
    with open(path, "wb") as fh:
        fh.write(b"blueprint benchmark scan".ljust(80, b" "))
        fh.write(np.uint32(len(f)).tobytes())
        fh.write(record.tobytes())
    return len(f)


def _rss_mb() -> float:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def _reset_peak() -> None:
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")


def _peak_mb() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    raise RuntimeError("no VmHWM in /proc/self/status")


class _Buffers:
    """A stand-in for a moderngl context that keeps nothing of the buffers it is given."""

    def buffer(self, data):
        memoryview(data)
        return None


def child(path: str, name: str) -> dict:
    from dataclasses import replace

    from blueprint.columns import face_cross
    from blueprint.render import mesh
    from blueprint.scene import normals
    from blueprint.scene.environment import environment_parts
    from blueprint.scene.loader import load_model
    from blueprint.scene.up import guess_up

    seconds, cpu, peak, highest = {}, {}, {}, [_peak_mb()]

    def stage(label, run):
        _reset_peak()
        before = _rss_mb()
        wall, process = time.perf_counter(), time.process_time()
        result = run()
        seconds[label] = round(time.perf_counter() - wall, 4)
        cpu[label] = round(time.process_time() - process, 4)
        top = _peak_mb()
        highest.append(top)
        peak[label] = round(max(0.0, top - before), 1)
        return result

    model = stage("load", lambda: load_model(path))
    loaded = _rss_mb()
    triangles = len(model.faces)

    def fresh():
        return replace(model, _cache={})

    def degenerate():
        m = fresh()
        with m.holding_corners():
            return m.degenerate_faces()

    stage("degenerate", degenerate)
    stage("up", lambda: guess_up(model.positions, model.faces))
    stage("environment", lambda: environment_parts(fresh()))
    welded = stage("weld", lambda: normals.weld_ids(model.positions, model.faces))
    cross = face_cross(model.positions[model.faces].astype(np.float64))
    length = np.linalg.norm(cross, axis=1)
    unit = cross / np.where(length > 0, length, 1.0)[:, None]
    del cross, length
    stage("creases", partial(normals.crease_vertices, welded, unit, 30.0, model.positions, model.faces))
    del welded, unit
    stage("normals", lambda: normals.corner_normals(model.positions, model.faces, 30.0))
    prepared = sys.modules.get("blueprint.scene.prepare")
    held = getattr(prepared, "_topologies", None)
    if held is not None:
        held.clear()
    stage("gpu_arrays", lambda: mesh.GpuMesh(_Buffers(), fresh(), 30.0))
    stage("gpu_arrays_again", lambda: mesh.GpuMesh(_Buffers(), fresh(), 30.0))
    if held is not None:
        held.clear()
    stage("gpu_arrays_ids", lambda: mesh.GpuMesh(_Buffers(), fresh(), None))
    if held is not None:
        held.clear()
    try:
        from blueprint.vector.lines import adjacency
    except ImportError:
        adjacency = None
    if adjacency is not None:
        stage("adjacency", lambda: adjacency(fresh()))
    return {
        "case": name,
        "triangles": triangles,
        "vertices": len(model.positions),
        "parts": len(model.part_names),
        "seconds": seconds,
        "cpu_seconds": cpu,
        "peak_mb": peak,
        "bytes_per_triangle": {k: round(v * 2**20 / triangles) for k, v in peak.items()},
        "loaded_mb": round(loaded, 1),
        "process_peak_mb": round(max(highest), 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", default="7,8", help="subdivisions of the scans (9: 5.2 M triangles)")
    parser.add_argument("--shared", action="store_true", help="also the shared test models")
    parser.add_argument("--workdir", default="/tmp/blueprint-bench-prepare", help="where scans are written")
    parser.add_argument("--child", nargs=2, metavar=("PATH", "NAME"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(child(*args.child)), flush=True)
        return
    cases = []
    work = Path(args.workdir)
    work.mkdir(parents=True, exist_ok=True)
    for n in [int(s) for s in args.scans.split(",") if s]:
        path = work / f"scan{n}.stl"
        if not path.exists():
            write_scan(path, n)
        cases.append((str(path), f"scan-{20 * 4**n / 1e6:.1f}M"))
    if args.shared:
        cases += [(str(SHARED / m), Path(m).name) for m in SHARED_MODELS if (SHARED / m).exists()]
    for path, name in cases:
        timed, measured = (_run_child(path, name, env) for env in ({}, _MALLOC))
        if "failed" in timed or "failed" in measured:
            print(json.dumps(timed if "failed" in timed else measured), flush=True)
            continue
        # times from a process with the usual allocator, memory from one that returns what it frees
        for key in ("peak_mb", "bytes_per_triangle", "loaded_mb", "process_peak_mb"):
            timed[key] = measured[key]
        print(json.dumps(timed), flush=True)


def _run_child(path: str, name: str, env: dict) -> dict:
    run = subprocess.run(
        [sys.executable, __file__, "--child", path, name],
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, **env},
    )
    lines = [line for line in run.stdout.splitlines() if line.startswith("{")]
    if run.returncode or not lines:
        return {"case": name, "failed": run.stderr.strip().splitlines()[-1:]}
    return json.loads(lines[-1])


if __name__ == "__main__":
    main()
