"""The paper's Table 1 (paper 002), measured here: triangle-ID silhouettes on the GPU against the
object-space method on the CPU, at 1400x900.

Per model, one JSON object per line, then a markdown table next to the paper's figures (GTX 295,
one core of a 3 GHz dual-core CPU):

* ``gpu_vertex_deform_fps``: the paper's GPU setup: every frame uploads all corner positions (a
  deforming mesh) and draws the ID layer and the silhouette pass, image read back;
* ``gpu_vertex_fps``, ``gpu_idlist_fps``: the same for a static mesh, nothing uploaded, by vertex
  storage and by ID lists (``idlist_pre_ms``: welding and building the lists, once);
  ``gpu_vertex_noread_ms``: the static vertex-storage frame without reading the image back
  (``ctx.finish()`` instead), as the blueprint's own passes would consume it;
* ``gpu_edges_fps``: the default of ``blueprint silhouettes`` (not the paper's method): the CPU
  method's edges classified and drawn on the GPU, visible and hidden (2 layers), read back;
  ``gpu_edges_noread_ms`` the same left on the GPU (``benchmarks/silhouettes.py`` has more);
* ``cpu_pre_ms``: the object-space preprocessing (weld, connect, orient; ``build_adjacency``);
* ``cpu_fps``: its per-frame part alone (``classify_edges`` + ``draw_segments``);
* ``cpu_deform_fps``: both every frame, the paper's "CPU-FPS" (its worst case: a mesh that
  deforms and changes topology);
* ``edge_share``: silhouette pixels per covered pixel of layer 0 (grows where triangles fall
  below a pixel: neighbouring pixels then hold triangles two apart).

    python benchmarks/table1.py [--models-dir DIR] [--size 1400 900] [--frames 20] [--cpu-frames 2]

``--models-dir`` (repeatable) is searched recursively by file name, so both ``../shared/models``
(the default when present) and a flat copy such as ``.models/`` work; ``teapot.bpt`` must be
among them for the 25K and 61K teapots.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from blueprint import Camera, Model, Renderer, load_model
from blueprint.gpu_silhouettes import GpuSilhouettes
from blueprint.silhouette import BORDER, SILHOUETTE, build_adjacency, classify_edges, draw_segments
from blueprint.silhouette.teapot import teapot_model

ROOT = Path(__file__).resolve().parents[1]
# (row name, file, how to make it, the paper's (GPU fps, CPU fps, CPU preprocess ms) or None)
ROWS = [
    ("Bunny 70K", "stanford-bunny.obj", None, ("Bunny-70K", 22, 1.9, 474.7)),
    ("Teapot 6K", "teapot.obj", None, ("Teapot-6K", 21, 8.6, 108.5)),
    ("Teapot 25K", "teapot.bpt", 20, ("Teapot-25K", 21, 4.8, 189.2)),
    ("Teapot 61K", "teapot.bpt", 31, ("Teapot-61K", 21, 2.6, 345.0)),
    ("Dragon 100K", "dragon.ply", None, ("Dragon-200K", 23, 0.7, 1454.0)),
    ("Armadillo 86K", "armadillo.obj", None, None),
    ("Ogre 124K", "ogre.obj", None, None),
    ("Teapot 200K", "teapot.bpt", 56, None),
    ("Cycloidal 376K", "cycloidal.glb", None, None),
    ("Bunny 1.1M", "stanford-bunny.obj", "subdivide2", ("Dragon-870K", 6, None, None)),
]


def find(models_dirs: list[Path], name: str) -> Path | None:
    for folder in models_dirs:
        if (folder / name).is_file():
            return folder / name
        found = sorted(folder.rglob(name))
        if found:
            return found[0]
    return None


def make_model(path: Path, how) -> Model:
    if path.suffix == ".bpt":
        return teapot_model(path, int(how))
    model = load_model(path)
    if how == "subdivide2":
        import trimesh

        mesh = trimesh.Trimesh(model.positions, model.faces, process=False)
        mesh = mesh.subdivide().subdivide()
        model = Model.from_arrays(mesh.vertices, mesh.faces, up=model.up, source=f"{path.name} x16")
    return model


def median_ms(step, frames: int, warmup: int) -> float:
    for _ in range(warmup):
        step()
    times = []
    for _ in range(frames):
        t0 = time.perf_counter()
        step()
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def fps(ms: float | None) -> float | None:
    return None if ms is None else round(1000.0 / ms, 2)


def measure(r: Renderer, sil: GpuSilhouettes, model: Model, size, args) -> dict:
    w, h = size
    camera = Camera.fit(model.positions, "iso", aspect=w / h, up=model.up)
    record: dict = {}

    # GPU, static mesh: the first call uploads (and for ID lists, builds the lists); not timed
    sil.render(model, camera, size, method="vertex")
    t0 = time.perf_counter()
    sil.id_lists(model)
    record["idlist_pre_ms"] = round((time.perf_counter() - t0) * 1e3, 1)
    for method in ("vertex", "idlist"):
        ms = median_ms(lambda m=method: sil.render(model, camera, size, method=m), args.frames, args.warmup)
        record[f"gpu_{method}_ms"] = round(ms, 3)
        record[f"gpu_{method}_fps"] = fps(ms)

    def edges_frame() -> None:
        sil.render(model, camera, size, layers=2, method="edges")

    ms = median_ms(edges_frame, args.frames, args.warmup)
    record["gpu_edges_ms"], record["gpu_edges_fps"] = round(ms, 3), fps(ms)

    def edges_unread() -> None:
        sil.render(model, camera, size, layers=2, method="edges", read=False)
        with sil.current():
            r.ctx.finish()

    record["gpu_edges_noread_ms"] = round(median_ms(edges_unread, args.frames, args.warmup), 3)

    def unread() -> None:
        sil.render(model, camera, size, method="vertex", read=False)
        with sil.current():
            r.ctx.finish()

    # the same frame left on the GPU (as an edge source of the blueprint would use it)
    record["gpu_vertex_noread_ms"] = round(median_ms(unread, args.frames, args.warmup), 3)

    # GPU, deforming mesh: all corner positions uploaded every frame, as the paper did
    corners = np.ascontiguousarray(model.positions[model.faces], dtype=np.float32)
    soup = sil.soup(corners, model.face_part)
    try:

        def deform_frame() -> None:
            soup.update(corners)
            sil.render(soup, camera, size, method="vertex")

        ms = median_ms(deform_frame, args.frames, args.warmup)
        record["gpu_vertex_deform_ms"] = round(ms, 3)
        record["gpu_vertex_deform_fps"] = fps(ms)
        record["upload_mb"] = round(corners.nbytes / 2**20, 1)
    finally:
        soup.release()

    edges = sil.render(model, camera, size, method="vertex")[0] > 0
    covered = r.peel(model, camera, size=size, max_layers=1).triangle[0] >= 0
    record["edge_share"] = round(float(edges.sum() / max(covered.sum(), 1)), 4)
    sil.forget(model)
    r.forget(model)

    if args.cpu_frames > 0:
        view, projection = camera.view_matrix(), camera.projection_matrix()
        pre, per_frame = [], []
        for _ in range(args.cpu_frames):
            t0 = time.perf_counter()
            adjacency = build_adjacency(model.positions, model.faces)
            t1 = time.perf_counter()
            edge_set = classify_edges(adjacency, view, projection, w, h)
            chosen = np.isin(edge_set.kind, (SILHOUETTE, BORDER))
            draw_segments(edge_set.segments2d[chosen], w, h)
            t2 = time.perf_counter()
            pre.append((t1 - t0) * 1e3)
            per_frame.append((t2 - t1) * 1e3)
        pre_ms, frame_ms = statistics.median(pre), statistics.median(per_frame)
        record.update(
            cpu_pre_ms=round(pre_ms, 1),
            cpu_frame_ms=round(frame_ms, 1),
            cpu_fps=fps(frame_ms),
            cpu_deform_fps=fps(pre_ms + frame_ms),
            cpu_segments=int(chosen.sum()),
        )
    return record


def cell(value, digits: int = 1) -> str:
    if value is None:
        return "–"
    return f"{value:,.{digits}f}"


def markdown(records: list[dict], renderer: str) -> str:
    lines = [
        f"Table 1 at {records[0]['width']}x{records[0]['height']} on {renderer} "
        f"(silhouette pass: {records[0]['pass']}); paper: GTX 295 and one core of a 3 GHz CPU",
        "",
        "| model | triangles | GPU vertex fps, upload every frame | GPU vertex fps, static "
        "| GPU ID-list fps | ID-list prep ms | GPU vertex ms, not read back "
        "| CPU fps (classify + draw) | CPU fps incl. prep "
        "| CPU prep ms | edge share | GPU edges fps (default) | paper: model | GPU fps | CPU fps "
        "| CPU prep ms |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|",
    ]
    for rec in records:
        if "skipped" in rec:
            lines.append(f"| {rec['model']} | – | skipped: {rec['skipped']} |" + " |" * 13)
            continue
        paper = rec.get("paper") or ["–", None, None, None]
        lines.append(
            "| "
            + " | ".join(
                [
                    rec["model"],
                    f"{rec['triangles']:,}",
                    cell(rec["gpu_vertex_deform_fps"]),
                    cell(rec["gpu_vertex_fps"]),
                    cell(rec["gpu_idlist_fps"]),
                    cell(rec["idlist_pre_ms"]),
                    cell(rec["gpu_vertex_noread_ms"], 2),
                    cell(rec.get("cpu_fps"), 2),
                    cell(rec.get("cpu_deform_fps"), 2),
                    cell(rec.get("cpu_pre_ms")),
                    cell(rec["edge_share"], 3),
                    cell(rec["gpu_edges_fps"]),
                    str(paper[0]),
                    cell(paper[1], 0),
                    cell(paper[2]),
                    cell(paper[3]),
                ]
            )
            + " |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default_dir = ROOT.parent / "shared" / "models"
    parser.add_argument(
        "--models-dir",
        type=Path,
        action="append",
        help="folder searched (recursively) for the model files; repeat for several "
        "(default: ../shared/models, else .models)",
    )
    parser.add_argument("--size", nargs=2, type=int, default=(1400, 900), metavar=("W", "H"))
    parser.add_argument("--frames", type=int, default=20, help="timed GPU frames per figure")
    parser.add_argument("--warmup", type=int, default=3)
    parser.add_argument("--cpu-frames", type=int, default=2, help="timed CPU runs (0: skip the CPU)")
    parser.add_argument("--only", nargs="*", default=None, help="row names to run, e.g. 'Bunny 70K'")
    parser.add_argument("--pass", dest="passes", choices=("auto", "compute", "fragment"), default="auto")
    args = parser.parse_args()
    args.models_dir = args.models_dir or [default_dir if default_dir.is_dir() else ROOT / ".models"]
    size = tuple(args.size)
    records = []
    with Renderer() as r:
        compute = None if args.passes == "auto" else args.passes == "compute"
        if compute and r.ctx.version_code < 430:
            sys.exit("table1: compute passes need OpenGL 4.3")
        with GpuSilhouettes(r, compute=compute) as sil:
            kind = "compute" if sil.compute else "fragment"
            for name, filename, how, paper in ROWS:
                if args.only and name not in args.only:
                    continue
                base = {"model": name, "renderer": r.info["renderer"], "width": size[0], "height": size[1]}
                base["pass"] = kind
                path = find(args.models_dir, filename)
                if path is None:
                    folders = ", ".join(map(str, args.models_dir))
                    record = {**base, "skipped": f"{filename} not in {folders}"}
                else:
                    model = make_model(path, how)
                    base.update(triangles=model.triangle_count, file=path.name, paper=paper)
                    record = {**base, **measure(r, sil, model, size, args)}
                records.append(record)
                print(json.dumps(record), flush=True)
    if records:
        print()
        print(markdown(records, records[0]["renderer"]))


if __name__ == "__main__":
    main()
