"""What ``blueprint silhouettes`` costs a frame, by method: the line method (``gpu-edges``, the
default: 2 layers, visible and hidden lines; and 1 layer, visible only), the triangle-ID method
it replaced as the default (``gpu-vertex``, 1 layer) and the CPU method's per-frame part.

One JSON object per model and size: ``renderer``, ``model``, ``triangles``, ``width``,
``height``, ``edge_records`` and the median ms of a frame (image read back, after warm-up):

* ``gpu_edges_ms`` (2 layers), ``gpu_edges_visible_ms`` (1 layer), ``gpu_vertex_ms`` (1 layer);
* ``gpu_edges_noread_ms``: the default frame left on the GPU (``ctx.finish()`` instead);
* ``gpu_edges_deform_ms``: the default frame of a deforming mesh, every corner uploaded;
* ``gpu_edges_pre_ms``: building and uploading the edge records, once per topology;
* ``cpu_frame_ms``: ``classify_edges`` + ``draw_segments`` (``--cpu-frames 0`` skips it).

    python benchmarks/silhouettes.py [--models-dir DIR] [--size 1400 900] [--frames 20]
        [--model NAME ...]

Models are found by file name as in ``table1.py`` (``teapot.bpt`` makes the 200K teapot).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from blueprint import Camera, Renderer
from blueprint.gpu_silhouettes import GpuSilhouettes
from blueprint.silhouette import BORDER, SILHOUETTE, build_adjacency, classify_edges, draw_segments, weld

sys.path.insert(0, str(Path(__file__).resolve().parent))
from table1 import ROOT, find, make_model, median_ms  # noqa: E402

MODELS = [
    ("Bunny 70K", "stanford-bunny.obj", None),
    ("Dragon 100K", "dragon.ply", None),
    ("Teapot 200K", "teapot.bpt", 56),
    ("featuretype", "featuretype.STL", None),
]


def measure(r: Renderer, sil: GpuSilhouettes, model, size, args) -> dict:
    w, h = size
    camera = Camera.fit(model.positions, "iso", aspect=w / h, up=model.up)
    record: dict = {}
    t0 = time.perf_counter()
    records = sil.edge_records(model)
    record["gpu_edges_pre_ms"] = round((time.perf_counter() - t0) * 1e3, 1)
    record["edge_records"] = len(records)
    for key, method, layers in (
        ("gpu_edges_ms", "edges", 2),
        ("gpu_edges_visible_ms", "edges", 1),
        ("gpu_vertex_ms", "vertex", 1),
    ):
        ms = median_ms(
            lambda m=method, n=layers: sil.render(model, camera, size, layers=n, method=m),
            args.frames,
            args.warmup,
        )
        record[key] = round(ms, 3)

    def unread() -> None:
        sil.render(model, camera, size, layers=2, method="edges", read=False)
        with sil.current():
            r.ctx.finish()

    record["gpu_edges_noread_ms"] = round(median_ms(unread, args.frames, args.warmup), 3)

    corners = np.ascontiguousarray(model.positions[model.faces], dtype=np.float32)
    # the topology of the surface, not of the file's soup (an STL repeats every vertex)
    welded, faces = weld(model.positions, model.faces)
    soup = sil.soup(corners, model.face_part, (faces, len(welded)))
    try:

        def deform_frame() -> None:
            soup.update(corners)
            sil.render(soup, camera, size, layers=2, method="edges")

        record["gpu_edges_deform_ms"] = round(median_ms(deform_frame, args.frames, args.warmup), 3)
    finally:
        soup.release()
    sil.forget(model)
    r.forget(model)

    if args.cpu_frames > 0:
        adjacency = build_adjacency(model.positions, model.faces)
        view, projection = camera.view_matrix(), camera.projection_matrix()
        times = []
        for _ in range(args.cpu_frames):
            t0 = time.perf_counter()
            edge_set = classify_edges(adjacency, view, projection, w, h)
            draw_segments(edge_set.segments2d[np.isin(edge_set.kind, (SILHOUETTE, BORDER))], w, h)
            times.append((time.perf_counter() - t0) * 1e3)
        record["cpu_frame_ms"] = round(statistics.median(times), 1)
    return record


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--models-dir", type=Path, action="append")
    parser.add_argument("--size", type=int, nargs=2, default=(1400, 900))
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--warmup", type=int, default=3)
    parser.add_argument("--cpu-frames", type=int, default=2)
    parser.add_argument("--model", action="append", help="only the rows of these names (repeatable)")
    args = parser.parse_args()
    dirs = args.models_dir or [p for p in (ROOT.parent / "shared" / "models", ROOT / ".models") if p.is_dir()]
    size = tuple(args.size)
    # loaded on first use by the adjacency, whose first build would otherwise time the import
    import scipy.sparse.csgraph  # noqa: F401

    with Renderer() as r, GpuSilhouettes(r) as sil:
        for name, file, how in MODELS:
            if args.model and name not in args.model:
                continue
            base = {"renderer": r.info["renderer"], "model": name, "width": size[0], "height": size[1]}
            path = find(dirs, file)
            if path is None:
                print(json.dumps({**base, "skipped": f"{file} not found"}), flush=True)
                continue
            model = make_model(path, how)
            record = measure(r, sil, model, size, args)
            print(json.dumps({**base, "triangles": model.triangle_count, **record}), flush=True)


if __name__ == "__main__":
    main()
