"""The A-buffer's geometry pass in compute against the graphics pipeline's: does capture in
compute (triangles binned to tiles, each tile rasterised by a workgroup) pay where the graphics
pipeline is narrow (an H200 draws triangles on a couple of its TPCs, computes on all 132 SMs)?

Each model and size: the layers both ways (A-buffer, resolved as the renderer resolves them),
compared pixel by pixel — surfaces per pixel, triangle, depth, normal — and the GPU time of the
geometry pass alone (a time query, the GPU kept busy beforehand so the query times the GPU, not
Python issuing it) and of a whole ``Renderer.render`` frame each way. One JSON object per line.

    python benchmarks/compute_capture.py MODEL... [--size 1024 2048 4096] [--frames 9]

Sizes are G-buffer sizes (a 2048² drawing at the default supersample 2 is 4096²). The compute
rasteriser is the renderer's (``render.raster``, ``ABufferRow.compute_from``); it does not
clip: views with a vertex behind the eye are refused.
"""

from __future__ import annotations

import argparse
import functools
import json
import statistics
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from blueprint import Renderer, load_model
from blueprint.render.abuffer import ABufferSource
from blueprint.render.gbuffer import gbuffer
from blueprint.render.raster import TILE
from blueprint.render.table import CaptureTable, Request, capture_table
from blueprint.scene.camera import fit_camera


def binned(r, size: tuple[int, int]) -> int:
    """Triangle-tile pairs the compute rasteriser listed in the last frame at ``size`` (a read:
    not for timed frames)."""
    tiles = -(-size[0] // TILE) * -(-size[1] // TILE)
    start = r.pool.buffer("raster.start", 4 * (tiles + 1))
    return int(np.frombuffer(start.read(size=4, offset=4 * tiles), np.uint32)[0])


STALL = """#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 11) buffer Out { float v[]; };
uniform int u_loops;
void main() {
    float x = float(gl_GlobalInvocationID.x);
    for (int i = 0; i < u_loops; ++i) x = sin(x) * 1.0001 + 0.3;
    v[gl_GlobalInvocationID.x] = x;
}
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+")
    parser.add_argument("--size", type=int, nargs="+", default=[1024, 2048, 4096])
    parser.add_argument("--layers", type=int, default=8, help="layers compared (0: all)")
    parser.add_argument("--frames", type=int, default=9)
    args = parser.parse_args()
    with Renderer() as r:
        bench = Bench(r, args.layers or None, args.frames)
        for path in args.models:
            model = load_model(path)
            for size in args.size:
                row = {"renderer": r.info["renderer"], "model": Path(path).name, "size": size}
                row.update(bench.measure(model, size))
                print(json.dumps(row), flush=True)


class Bench:
    """Both ways of filling the A-buffer's lists, whatever the size (``ABufferRow.compute_from``),
    the renderer's capture table the A-buffer's from two layers, then the peel."""

    def __init__(self, r, layers: int | None, frames: int) -> None:
        self.r, self.layers, self.frames = r, layers, frames
        default = capture_table(r)
        self.listed = replace(default.row("A-buffer"), min_layers=2)
        self.table = CaptureTable((self.listed, default.row("peel")), default.exact_depth)
        self.stall_prog = r.ctx.compute_shader(STALL)
        self.stall_buf = r.ctx.buffer(reserve=256)
        self.loops = 0

    def use(self, compute: bool) -> None:
        rows = (replace(self.listed, compute_from=0 if compute else None), *self.table.rows[1:])
        self.r.capture_table = replace(self.table, rows=rows)

    def stall(self) -> None:
        self.stall_buf.bind_to_storage_buffer(11)
        self.stall_prog["u_loops"].value = self.loops
        self.stall_prog.run(1)

    def gpu_ms(self, call) -> float:
        """Median GPU time of ``call`` (a time query; wall time with a finish where the
        driver's queries time nothing, as llvmpipe's), the GPU kept busy before it."""
        times = []
        for _ in range(self.frames):
            self.stall()
            query = self.r.ctx.query(time=True)
            t0 = time.perf_counter()
            with query:
                call()
            self.r.ctx.finish()
            wall = (time.perf_counter() - t0) * 1e3
            times.append(query.elapsed / 1e6 if query.elapsed > 1000 else wall)
        return round(statistics.median(times), 3)

    def measure(self, model, size: int) -> dict:
        r = self.r
        camera = fit_camera(model, (size, size))
        clip = (
            np.c_[model.positions, np.ones(len(model.positions))]
            @ (camera.projection_matrix() @ camera.view_matrix()).T
        )
        if (clip[:, 3] <= 0).any():
            return {"refused": "a vertex lies behind the eye"}
        peeled = []
        for compute in (False, True):
            self.use(compute)
            peeled.append(r.peel(model, camera, size=(size, size), max_layers=self.layers))
        a, b = peeled
        k = min(len(a.depth), len(b.depth))
        both = (a.depth[:k] < 1) & (b.depth[:k] < 1)
        row = {
            "triangles": model.triangle_count,
            "layers": [len(a.depth), len(b.depth)],
            "pixels_same_count": round(float(((a.depth < 1).sum(0) == (b.depth < 1).sum(0)).mean()), 6),
            "surfaces_same_triangle": round(float((a.triangle[:k] == b.triangle[:k])[both].mean()), 6),
            "depth_max_diff": float(np.abs(a.depth[:k] - b.depth[:k])[both].max(initial=0.0)),
            "normal_max_diff": float(np.abs(a.normal[:k] - b.normal[:k])[both].max(initial=0.0)),
            "tile_pairs": binned(r, (size, size)),
            "fragments": fragments(r, size),
        }
        # the capture alone (lists emptied, every fragment listed, the lists sorted), each way
        gb = gbuffer(r.pool, (size, size))
        self.loops = 20_000_000 if size > 1024 else 4_000_000
        options = dict(size=(size // 2, size // 2), max_layers=self.layers)
        pictures = []
        for compute in (False, True):
            self.use(compute)
            ab = peeled_capture(r, model, camera, gb)
            form = "compute" if compute else "graphics"
            row[f"capture_{form}_ms"] = self.gpu_ms(
                functools.partial(ab._capture, gb, f"abuffer.{size}x{size}")
            )
            pictures.append(r.render(model, camera, **options).image.astype(np.int16))
            row[f"frame_{form}_ms"] = self.gpu_ms(lambda: r.render(model, camera, **options))
        self.use(False)
        row["pixels_apart"] = int((np.abs(pictures[0] - pictures[1]).max(-1) > 8).sum())
        return row


def fragments(r, size: int) -> int:
    """Fragments the last A-buffer capture at ``size`` drew (its totals' first count)."""
    totals = r.pool.buffer(f"abuffer.{size}x{size}.totals", 16)
    return int(np.frombuffer(totals.read(size=4), np.uint32)[0])


def peeled_capture(r, model, camera, gb) -> ABufferSource:
    """An A-buffer of ``model`` from ``camera`` into ``gb``, as a frame of every layer makes it
    with the renderer's capture table."""
    mesh = r.mesh(model, 30.0)
    request = Request(gb.size, mesh.triangles, mesh.part_count, None)
    return ABufferSource(r.capturer, r.capture_table.row("A-buffer"), mesh, camera, gb, request)


if __name__ == "__main__":
    main()
