"""The A-buffer's geometry pass in compute against the graphics pipeline's: does capture in
compute (triangles binned to tiles, each tile rasterised by a workgroup) pay where the graphics
pipeline is narrow (an H200 draws triangles on a couple of its TPCs, computes on all 132 SMs)?

Each model and size: the layers both ways (A-buffer, resolved as the renderer resolves them),
compared pixel by pixel — surfaces per pixel, triangle, depth, normal — and the GPU time of the
geometry pass alone (a time query, the GPU kept busy beforehand so the query times the GPU, not
Python issuing it) and of a whole ``Renderer.render`` frame each way. One JSON object per line.

    python benchmarks/compute_capture.py MODEL... [--size 1024 2048 4096] [--frames 9]

Sizes are G-buffer sizes (a 2048² drawing at the default supersample 2 is 4096²). The compute
pass leaves out clipping: views with a vertex behind the eye are refused.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

from blueprint import Renderer, load_model
from blueprint.gpu.shaders import build_compute
from blueprint.render.abuffer import ABuffer, list_defines
from blueprint.render.capture import BACK_OFFSET, abuffer_uniforms, gbuffer
from blueprint.scene.camera import fit_camera

SHADER = Path(__file__).parent / "glsl" / "raster.comp"
TILE = 16
ROWS = 8  # threads a triangle in the set-up and binning (raster.comp)


class ComputeRaster:
    """The four dispatches of ``raster.comp`` and their buffers, for one renderer."""

    def __init__(self, r) -> None:
        self.r = r
        defines = {**list_defines(r), "SLIM": r.abuffer_slim}
        self.stages = [build_compute(r.ctx, SHADER, {"STAGE": k, **defines}) for k in range(4)]
        # triangle-tile pairs the bins hold: the most a frame listed so far (a frame that lists
        # more loses triangles: ``binned`` tells)
        self.bin_room = 0

    def fragments(self, ab: ABuffer, gb) -> None:
        r, ctx = self.r, self.r.ctx
        w, h = gb.size
        triangles = ab.mesh.triangles
        columns, rows = -(-w // TILE), -(-h // TILE)
        tiles = columns * rows
        pool = r.pool
        setup = pool.buffer("raster.setup", 80 * triangles)
        count = pool.buffer("raster.count", 4 * tiles)
        start = pool.buffer("raster.start", 4 * (tiles + 1))
        room = max(self.bin_room, 16 * triangles, 1 << 22)
        bins = pool.buffer("raster.bins", 4 * room)
        pool.buffer("raster.edges", 72 * triangles).bind_to_storage_buffer(15)
        count.clear()
        ab.mesh.vbo.bind_to_storage_buffer(5)
        ab.mesh.ibo.bind_to_storage_buffer(6)
        for binding, buf in ((11, setup), (12, count), (13, start), (14, bins)):
            buf.bind_to_storage_buffer(binding)
        pool.texture(f"abuffer.{w}x{h}.head", (w, h), "r32ui").bind_to_image(0, read=True, write=True)
        view, projection = ab.geometry["u_view"].read(), ab.geometry["u_projection"].read()
        # (slim fragments' geometry pass has no normals to turn: the resolve holds the camera's)
        ortho = (ab.resolve if ab.slim else ab.geometry)["u_ortho"].value
        for prog in self.stages:
            for name, value in (
                ("u_size", (w, h)),
                ("u_triangles", triangles),
                ("u_tile_columns", columns),
                ("u_tiles", tiles),
                ("u_bin_room", room),
                ("u_ortho", ortho),
            ):
                if name in prog:
                    prog[name].value = value
            for name, value in (("u_view", view), ("u_projection", projection)):
                if name in prog:
                    prog[name].write(value)
        groups = -(-triangles * ROWS // 64)
        self.stages[0].run(groups)
        ctx.memory_barrier()
        self.stages[1].run(1)
        ctx.memory_barrier()
        self.stages[2].run(groups)
        ctx.memory_barrier()
        self.stages[3].run(columns, rows)

    def binned(self, size: tuple[int, int]) -> int:
        """Triangle-tile pairs of the last frame at ``size`` (a read: not for timed frames)."""
        tiles = -(-size[0] // TILE) * -(-size[1] // TILE)
        start = self.r.pool.buffer("raster.start", 4 * (tiles + 1))
        pairs = int(np.frombuffer(start.read(size=4, offset=4 * tiles), np.uint32)[0])
        self.bin_room = max(self.bin_room, pairs)
        return pairs


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
        r.abuffer_min_layers, r.kbuffer = 2, False
        bench = Bench(r, args.layers or None, args.frames)
        for path in args.models:
            model = load_model(path)
            for size in args.size:
                row = {"renderer": r.info["renderer"], "model": Path(path).name, "size": size}
                row.update(bench.measure(model, size))
                print(json.dumps(row), flush=True)


class Bench:
    """Both ways of filling the A-buffer's lists, switched in ``ABuffer.fragments``."""

    def __init__(self, r, layers: int | None, frames: int) -> None:
        self.r, self.layers, self.frames = r, layers, frames
        self.raster = ComputeRaster(r)
        self.graphics = ABuffer.fragments
        self.stall_prog = r.ctx.compute_shader(STALL)
        self.stall_buf = r.ctx.buffer(reserve=256)
        self.loops = 0

    def use(self, compute: bool) -> None:
        raster = self.raster
        ABuffer.fragments = (lambda ab, gb: raster.fragments(ab, gb)) if compute else self.graphics

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
            "tile_pairs": self.raster.binned((size, size)),
            "fragments": fragments(r, size),
        }
        # the capture alone (lists emptied, every fragment listed, the lists sorted), each way
        ab = peeled_capture(r, model, camera)
        gb = gbuffer(r.pool, (size, size))
        self.loops = 20_000_000 if size > 1024 else 4_000_000
        options = dict(size=(size // 2, size // 2), max_layers=self.layers)
        pictures = []
        for compute in (False, True):
            self.use(compute)
            form = "compute" if compute else "graphics"
            row[f"capture_{form}_ms"] = self.gpu_ms(lambda: ab._capture(gb, f"abuffer.{size}x{size}"))
            pictures.append(r.render(model, camera, **options).image.astype(np.int16))
            row[f"frame_{form}_ms"] = self.gpu_ms(lambda: r.render(model, camera, **options))
        self.use(False)
        row["pixels_apart"] = int((np.abs(pictures[0] - pictures[1]).max(-1) > 8).sum())
        return row


def fragments(r, size: int) -> int:
    """Fragments the last A-buffer capture at ``size`` drew (its totals' first count)."""
    totals = r.pool.buffer(f"abuffer.{size}x{size}.totals", 16)
    return int(np.frombuffer(totals.read(size=4), np.uint32)[0])


def peeled_capture(r, model, camera) -> ABuffer:
    """An A-buffer with ``camera``'s uniforms over ``model``, as a frame makes it."""
    return ABuffer(
        r, r.mesh(model, 30.0), abuffer_uniforms(camera), BACK_OFFSET / (1 << 24), r.abuffer_max_bytes
    )


if __name__ == "__main__":
    main()
