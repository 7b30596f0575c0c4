"""Scale: generated models of growing size, each drawn by ``blueprint render`` in a process of its
own, to a PNG and to an SVG; one JSON line a case.

    python benchmarks/scale.py [--families scan,assembly,parts] [--sizes FAMILY=S1,S2 ...]
                               [--quick] [--size 1024 1024] [--max-layers 0]
                               [--outputs png,svg] [--src DIR] [--workdir DIR] [--timeout 900]
                               [--threads 1,16]

Families, each with a size parameter:

* ``scan``: a dense scan, an icosphere with radial noise of 5 % of an edge; the size is the
  triangle count (rounded to the icosphere's, 20·4^k); written as binary STL and as binary PLY.
* ``assembly``: N × N copies of a CAD model in one GLB, each copy its own nodes instancing the
  model's meshes (2CylinderEngine from the shared models where it is found, else the gearbox of
  ``blueprint.examples``); the size is N.
* ``parts``: many small distinct parts in one GLB (prisms of 12 to 100 triangles on a grid,
  like the elements of a building or a plant), one mesh and one node each; the size is the
  part count.

Each line: ``family``, ``size``, ``file`` (and its ``format`` and ``file_bytes``),
``triangles_drawn``, ``triangles_unique``, ``parts``, ``instances``, ``output``, ``threads`` (with
``--threads``: the preparation's, ``BLUEPRINT_THREADS``), ``seconds`` (the whole process, wall),
``cpu_seconds`` (its user and system time, every thread's), ``stages`` (seconds: the command's
own timings, ``BLUEPRINT_STAGES=1``, see ``blueprint.api.stages``), ``peak_rss_bytes`` (the
process's peak resident memory, VmHWM, and ``bytes_per_triangle`` drawn), ``gpu_memory``
(bytes, where the driver tells), and ``error`` (its last line) where the command failed or ran
past ``--timeout``. ``--src`` names the source tree to run (default: this one's),
so that two trees can be timed in turns. The models are kept in ``--workdir`` and made once.
Every process runs as an installed package does, with bytecode (written into a temporary
``PYTHONPYCACHEPREFIX`` by a warm-up drawing of the shipped example, ``PYTHONDONTWRITEBYTECODE``
removed: without bytecode each process compiles the package's modules, 0.2 s on llvmpipe's
machine) and with Mesa's shader cache as that drawing left it.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from lineart import process_environment  # noqa: E402  (a script beside this one)

# sizes for this machine (llvmpipe), and the smallest with --quick; benchmarks/device.sh gives
# the device's own
SIZES = {"scan": [327_680, 1_310_720], "assembly": [2, 5], "parts": [10_000, 30_000]}
QUICK = {"scan": [327_680], "assembly": [2], "parts": [10_000]}
ENGINES = ("glTF-Sample-Models/2CylinderEngine.glb", "2CylinderEngine.glb")


# -- models ------------------------------------------------------------------------------------
def icosphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    """A unit icosphere: (V, 3) float64 vertices and (20·4^k, 3) int64 faces."""
    t = (1 + 5**0.5) / 2
    v = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t]]
        + [[0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
        float,
    )
    f = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2]]
        + [[10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5]]
        + [[2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        np.int64,
    )
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(subdivisions):
        n = len(v)
        edges = f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        keys = edges.min(axis=1) * n + edges.max(axis=1)
        unique, inverse = np.unique(keys, return_inverse=True)
        mid = v[unique // n] + v[unique % n]
        v = np.vstack([v, mid / np.linalg.norm(mid, axis=1, keepdims=True)])
        m = (n + inverse).reshape(-1, 3)  # midpoints of edges 01, 12, 20
        f = np.concatenate(
            [
                np.column_stack([f[:, 0], m[:, 0], m[:, 2]]),
                np.column_stack([f[:, 1], m[:, 1], m[:, 0]]),
                np.column_stack([f[:, 2], m[:, 2], m[:, 1]]),
                m,
            ]
        )
    return v, f


def scan(triangles: int, folder: Path) -> tuple[list[Path], dict]:
    """The noisy icosphere of about ``triangles`` triangles as binary STL and binary PLY."""
    k = max(0, round(math.log(max(triangles, 20) / 20, 4)))
    stl, ply = folder / f"scan-{20 * 4**k}.stl", folder / f"scan-{20 * 4**k}.ply"
    if not (stl.exists() and ply.exists()):
        v, f = icosphere(k)
        edge = 1.0515 / 2**k  # an icosahedron's edge on the unit sphere, halved k times
        v *= (1 + 0.05 * edge * np.random.default_rng(k).standard_normal(len(v)))[:, None]
        record = np.dtype([("normal", "<f4", 3), ("triangle", "<f4", (3, 3)), ("attribute", "<u2")])
        with open(stl, "wb") as fh:
            fh.write(b"\0" * 80 + struct.pack("<I", len(f)))
            for block in range(0, len(f), 1 << 20):
                rows = np.zeros(len(f[block : block + (1 << 20)]), record)
                rows["triangle"] = v[f[block : block + (1 << 20)]]
                rows.tofile(fh)
        header = (
            f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\n"
            f"property float y\nproperty float z\nelement face {len(f)}\n"
            "property list uchar int vertex_indices\nend_header\n"
        )
        face = np.dtype([("count", "u1"), ("corners", "<i4", 3)])
        rows = np.empty(len(f), face)
        rows["count"], rows["corners"] = 3, f
        with open(ply, "wb") as fh:
            fh.write(header.encode())
            v.astype("<f4").tofile(fh)
            rows.tofile(fh)
    count = 20 * 4**k
    return [stl, ply], {"triangles_drawn": count, "triangles_unique": count, "parts": 1, "instances": 1}


def _glb(doc: dict, binary: bytes) -> bytes:
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    body = (
        struct.pack("<II", len(text), 0x4E4F534A)
        + text
        + struct.pack("<II", len(binary), 0x004E4942)
        + binary
    )
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def _chunks(data: bytes) -> tuple[dict, bytes]:
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + length])
    return doc, data[28 + length :]


def engine_source() -> Path:
    """2CylinderEngine where the shared models (or the device's copy of them) hold it, else the
    gearbox example."""
    for folder in (ROOT.parent / "shared" / "models", ROOT / ".models", Path("/work/shared/models")):
        for name in ENGINES:
            if (folder / name).is_file():
                return folder / name
    from blueprint import examples

    return examples.example_path()


def assembly(side: int, folder: Path) -> tuple[list[Path], dict]:
    """``side`` × ``side`` copies of the engine, each copy its own nodes over the same meshes."""
    from blueprint.scene.loader import load_model

    source = engine_source()
    path = folder / f"assembly-{source.stem}-{side}x{side}.glb"
    model = load_model(source, include="*")
    doc, binary = _chunks(source.read_bytes())
    if not path.exists():
        nodes = doc.get("nodes", [])
        for node in nodes:
            for key in ("camera", "skin"):
                node.pop(key, None)
        scene = doc["scenes"][doc.get("scene", 0)]["nodes"]
        extent = np.ptp(model.bounds, axis=0) * 1.1
        across = [0, 2] if model.up == "y" else [0, 1]
        copies, roots = [], []
        for k in range(side * side):
            offset = len(nodes) * k + side * side
            for node in nodes:
                copy = dict(node)
                if "children" in node:
                    copy["children"] = [c + offset for c in node["children"]]
                copies.append(copy)
            place = [0.0, 0.0, 0.0]
            place[across[0]], place[across[1]] = (
                float(extent[across[0]] * (k % side)),
                float(extent[across[1]] * (k // side)),
            )
            roots.append({"name": f"copy{k}", "translation": place, "children": [r + offset for r in scene]})
        out = {
            key: doc[key] for key in ("asset", "buffers", "bufferViews", "accessors", "meshes") if key in doc
        }
        for mesh in out["meshes"]:
            for primitive in mesh["primitives"]:
                primitive.pop("material", None)
        out["nodes"] = roots + copies
        out["scenes"], out["scene"] = [{"nodes": list(range(side * side))}], 0
        path.write_bytes(_glb(out, binary))
    unique = sum(
        doc["accessors"][p.get("indices", p["attributes"]["POSITION"])]["count"] // 3
        for mesh in doc["meshes"]
        for p in mesh["primitives"]
    )
    copies = side * side
    return [path], {
        "triangles_drawn": copies * model.triangle_count,
        "triangles_unique": unique,
        "parts": copies * len(model.part_names),
        "instances": copies * len(model.part_names),
        "source": source.name,
    }


def parts(count: int, folder: Path) -> tuple[list[Path], dict]:
    """``count`` distinct prisms of 12 to 100 triangles on a grid, one mesh and one node each."""
    from blueprint import examples

    path = folder / f"parts-{count}.glb"
    rng = np.random.default_rng(count)
    segments = rng.integers(3, 26, count)  # a prism of k segments has 4k triangles
    drawn = int(4 * segments.sum())
    if not path.exists():
        positions, indices, meshes, accessors, nodes = [], [], [], [], []
        at_v = at_i = 0
        side = max(1, round(count ** (1 / 3)))
        for k in range(3, 26):
            chosen = np.flatnonzero(segments == k)
            if not len(chosen):
                continue
            v, f = examples.prism(1.0, 1.0, int(k))
            scale = rng.uniform(0.2, 0.45, (len(chosen), 1, 3))
            made = (v[None] * scale).astype("<f4")
            positions.append(made.reshape(-1, 3))
            indices.append(np.broadcast_to(f.astype("<u2"), (len(chosen), *f.shape)).reshape(-1))
            for j, part in enumerate(chosen):
                accessors.append(
                    {"bufferView": 0, "byteOffset": at_v + j * v.size * 4, "componentType": 5126}
                    | {"count": len(v), "type": "VEC3"}
                )
                accessors.append(
                    {"bufferView": 1, "byteOffset": at_i + j * f.size * 2, "componentType": 5123}
                    | {"count": f.size, "type": "SCALAR"}
                )
                meshes.append((int(part), len(accessors) - 2))
            at_v += len(chosen) * v.size * 4
            at_i += len(chosen) * f.size * 2
        order = sorted(meshes)
        mesh_list = [
            {"name": f"part{p}", "primitives": [{"attributes": {"POSITION": a}, "indices": a + 1}]}
            for p, a in order
        ]
        cells = np.arange(count)
        for p in range(count):
            x, y, z = cells[p] % side, (cells[p] // side) % side, cells[p] // (side * side)
            nodes.append({"name": f"part{p}", "mesh": p, "translation": [float(x), float(y), float(z)]})
        vertex_bytes = np.concatenate(positions).tobytes()
        index_bytes = np.concatenate(indices).tobytes()
        pad = -len(vertex_bytes) % 4
        binary = vertex_bytes + b"\0" * pad + index_bytes
        doc = {
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": len(binary)}],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": len(vertex_bytes)},
                {"buffer": 0, "byteOffset": len(vertex_bytes) + pad, "byteLength": len(index_bytes)},
            ],
            "accessors": accessors,
            "meshes": mesh_list,
            "nodes": nodes,
            "scenes": [{"nodes": list(range(count))}],
            "scene": 0,
        }
        path.write_bytes(_glb(doc, binary))
    return [path], {"triangles_drawn": drawn, "triangles_unique": drawn, "parts": count, "instances": count}


FAMILIES = {"scan": scan, "assembly": assembly, "parts": parts}


# -- runs ----------------------------------------------------------------------------------------
# Printed by the drawing's process as it exits: its peak resident memory (VmHWM, its own; the
# ru_maxrss a parent sees carries over the parent's across fork and exec).
_PEAK = """import atexit, json, sys
def _peak():
    with open("/proc/self/status") as fh:
        kib = next(int(line.split()[1]) for line in fh if line.startswith("VmHWM"))
    print(json.dumps({"peak_rss": kib * 1024}), file=sys.stderr, flush=True)
atexit.register(_peak)
"""


def warm_up(src: Path, pycache: Path, workdir: Path) -> None:
    """Draw the shipped example of the tree ``src`` to a PNG and an SVG once, as the cases run,
    so that they start as an installed package's second run does: its bytecode written into
    ``pycache`` and Mesa's shader cache filled."""
    env = process_environment(pycache, src)
    example = src / "blueprint" / "data" / "gearbox.glb"
    command = [sys.executable, "-m", "blueprint", "render", str(example), "--size", "64", "64", "-o"]
    for kind in ("png", "svg"):
        argv = [*command, str(workdir / f"warm-up.{kind}")]
        subprocess.run(argv, check=True, capture_output=True, timeout=600, env=env)


def run(
    src: Path,
    pycache: Path,
    model: Path,
    output: Path,
    size: tuple[int, int],
    layers: int,
    timeout: float,
    threads: int | None = None,
) -> dict:
    """One ``blueprint render`` in a process of its own, as an installed package runs (its
    bytecode in ``pycache``, ``warm_up``; its preparation on ``threads`` threads,
    ``BLUEPRINT_THREADS``; None: the tree's default): its wall seconds, its CPU seconds
    (threads included), its peak resident memory, its stage timings, or its error."""
    # the tree first, the environment's own paths after it (a device's carried wheels)
    env = process_environment(pycache, src, BLUEPRINT_STAGES="1")
    if threads is not None:
        env["BLUEPRINT_THREADS"] = str(threads)
    code = _PEAK + "from blueprint.cli import main; main()"
    argv = [sys.executable, "-c", code, "render", str(model), "-o", str(output)]
    argv += ["--size", str(size[0]), str(size[1]), "--max-layers", str(layers)]
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        child = subprocess.Popen(argv, stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=env)
        killer = threading.Timer(timeout, child.kill)
        killer.start()
        _, status, usage = os.wait4(child.pid, 0)
        killer.cancel()
        child.returncode = os.waitstatus_to_exitcode(status)
        seconds = time.perf_counter() - start
        err.seek(0)
        lines = err.read().decode("utf-8", "replace").splitlines()
    peaks = [json.loads(line)["peak_rss"] for line in lines if line.startswith('{"peak_rss"')]
    found = {
        "seconds": round(seconds, 3),
        "cpu_seconds": round(usage.ru_utime + usage.ru_stime, 3),
        "peak_rss_bytes": peaks[-1] if peaks else None,
    }
    reports = [json.loads(line) for line in lines if line.startswith('{"stages"')]
    if reports:
        found["stages"] = {k: round(v, 3) for k, v in reports[-1]["stages"].items()}
        found["gpu_memory"] = reports[-1]["gpu_memory"]
    if child.returncode != 0:
        timed_out = seconds >= timeout
        found["error"] = (
            f"over {timeout:g} s" if timed_out else (lines[-1] if lines else f"exit {child.returncode}")
        )
    return found


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--families", default="scan,assembly,parts")
    parser.add_argument("--sizes", action="append", default=[], metavar="FAMILY=S1,S2")
    parser.add_argument("--quick", action="store_true", help="the smallest size of each family")
    parser.add_argument("--size", nargs=2, type=int, default=(1024, 1024), metavar=("W", "H"))
    parser.add_argument("--max-layers", type=int, default=0)
    parser.add_argument("--outputs", default="png,svg")
    parser.add_argument("--src", type=Path, default=ROOT / "src", help="the source tree to run")
    parser.add_argument("--workdir", type=Path, default=Path(tempfile.gettempdir()) / "blueprint-scale")
    parser.add_argument("--timeout", type=float, default=900.0)
    parser.add_argument(
        "--threads", default="", help="thread counts to prepare on, each a case (BLUEPRINT_THREADS): 1,16"
    )
    args = parser.parse_args(argv)
    thread_counts = [int(t) for t in args.threads.split(",") if t] or [None]
    sizes = dict(QUICK if args.quick else SIZES)
    for given in args.sizes:
        family, _, values = given.partition("=")
        sizes[family] = [int(float(v)) for v in values.split(",") if v]
    args.workdir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as pycache:
        warm_up(args.src.resolve(), Path(pycache), args.workdir)
        cases(args, sizes, thread_counts, Path(pycache))


def cases(args: argparse.Namespace, sizes: dict, thread_counts: list, pycache: Path) -> None:
    """Each family's models made (once) and drawn to each output, one JSON line a case."""
    for family in args.families.split(","):
        for size in sizes[family]:
            files, counts = FAMILIES[family](size, args.workdir)
            for path in files:
                for kind in args.outputs.split(","):
                    for threads in thread_counts:
                        output = args.workdir / f"{path.stem}.{path.suffix[1:]}.{kind}"
                        found = run(
                            args.src.resolve(),
                            pycache,
                            path,
                            output,
                            tuple(args.size),
                            args.max_layers,
                            args.timeout,
                            threads,
                        )
                        case = {"family": family, "size": size, "file": path.name, "format": path.suffix[1:]}
                        case |= {"file_bytes": path.stat().st_size, **counts, "output": kind}
                        case |= ({"threads": threads} if threads else {}) | found
                        if found["peak_rss_bytes"]:
                            case["bytes_per_triangle"] = round(
                                found["peak_rss_bytes"] / counts["triangles_drawn"]
                            )
                        print(json.dumps(case), flush=True)


if __name__ == "__main__":
    main()
