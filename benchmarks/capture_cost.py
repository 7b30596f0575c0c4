"""What bounds the A-buffer's geometry pass: its GPU time with variants of its fragment shader
(``benchmarks/glsl/abuffer_variants.frag``) that leave out one cost at a time — exact depth,
the node's bytes, one atomic on the node counter a fragment (against one a subgroup), every
write — for each model and G-buffer size. One JSON object per line.

    python benchmarks/capture_cost.py MODEL... [--size 2048 4096] [--frames 9]

Sizes are G-buffer sizes (a 2048² drawing at the default supersample 2 is 4096²). Times are
of the list clear and the geometry pass alone (no resolve), the GPU kept busy beforehand so
the time query times the GPU (``compute_capture.Bench.gpu_ms``).
"""

from __future__ import annotations

import argparse
import functools
import json
from pathlib import Path

from compute_capture import Bench, fragments, peeled_capture

from blueprint import Renderer, load_model
from blueprint.gpu.shaders import build_program
from blueprint.render.gbuffer import gbuffer
from blueprint.render.mesh import GEOMETRY_VERT, target_uniform
from blueprint.scene.camera import fit_camera

SHADER = Path(__file__).parent / "glsl" / "abuffer_variants.frag"
VARIANTS = {
    1: "no exact depth",
    2: "8-byte node",
    3: "8-byte node, counter a subgroup",
    4: "no exact depth, counter a subgroup",
    5: "counter alone",
    6: "nothing written",
    7: "product, counter a subgroup",
    8: "8-byte node, exact depth, heads in a storage buffer",
    9: "8-byte slots (16 a pixel), exact depth, no links",
    10: "4-byte node (face)",
    11: "4-byte slots (16 a pixel), no links",
}
FIXED = 16  # abuffer_variants.frag


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+")
    parser.add_argument("--size", type=int, nargs="+", default=[2048, 4096])
    parser.add_argument("--frames", type=int, default=9)
    args = parser.parse_args()
    with Renderer() as r:
        bench = Bench(r, None, args.frames)
        bench.use(False)
        programs = {}
        for k in VARIANTS:
            try:
                programs[k] = build_program(
                    r.ctx,
                    GEOMETRY_VERT,
                    SHADER,
                    {"VARIANT": k, "EXACT_DEPTH": r.capture_table.exact_depth},
                    "#version 450 core",
                )
            except Exception as exc:  # a driver without ARB_shader_ballot: that variant is left out
                print(json.dumps({"variant": k, "error": str(exc)[:300]}), flush=True)
        for path in args.models:
            model = load_model(path)
            for size in args.size:
                camera = fit_camera(model, (size, size))
                gb = gbuffer(r.pool, (size, size))
                ab = peeled_capture(r, model, camera, gb)
                name = f"abuffer.{size}x{size}"
                ab._capture(gb, name)  # the room this size needs
                ab._capture(gb, name)
                row = {
                    "renderer": r.info["renderer"],
                    "model": Path(path).name,
                    "size": size,
                    "fragments": fragments(r, size),
                }
                bench.loops = 20_000_000 if size > 1024 else 4_000_000
                run = Capture(r, ab, gb, camera, size)
                row["product_ms"] = bench.gpu_ms(run)
                for k, prog in programs.items():
                    row[f"v{k}_ms"] = bench.gpu_ms(functools.partial(run, prog))
                    if k in (3, 4, 7):
                        row[f"v{k}_fragments"] = fragments(r, size)
                row["variants"] = VARIANTS
                print(json.dumps(row), flush=True)


class Capture:
    """The lists cleared and every fragment listed by the product's geometry pass, or by a
    variant's program: a call is one capture (no sort)."""

    def __init__(self, r, ab, gb, camera, size: int) -> None:
        self.r, self.ab, self.gb, self.camera, self.size = r, ab, gb, camera, size
        self.name = f"abuffer.{size}x{size}"
        self.room = r.abuffer_room[(size, size)]
        most = max(self.room, FIXED * size * size)
        self.small = r.pool.buffer(f"{self.name}.small", 8 * most)
        self.faces = r.pool.buffer(f"{self.name}.faces", 4 * most)
        self.heads = r.pool.buffer(f"{self.name}.heads", 4 * size * size)
        self.head = r.pool.texture(f"{self.name}.head", (size, size), "r32ui")

    def __call__(self, prog=None) -> None:
        r, ab, size = self.r, self.ab, self.size
        ab._buffers(self.name, self.room)
        self.small.bind_to_storage_buffer(7)
        self.heads.clear()
        self.heads.bind_to_storage_buffer(10)
        self.faces.bind_to_storage_buffer(11)
        self.head.bind_to_image(0, read=True, write=True)
        ab.clear["u_capacity"].value = self.room
        ab.clear.run(-(-size // 8), -(-size // 8))
        r.ctx.memory_barrier()
        if prog is None:
            ab.fragments(self.gb, self.head)
            return
        self.gb.clears[0].use()
        for u in ("u_view", "u_projection"):
            prog[u].write(ab.geometry[u].read())
        for u, value in (("u_ortho", self.camera.ortho), ("u_width", size), ("u_pixels", size * size)):
            if u in prog:
                prog[u].value = value
        if "u_target" in prog:
            target_uniform(r, prog, (size, size))
        ab.mesh.vao(prog).render()


if __name__ == "__main__":
    main()
