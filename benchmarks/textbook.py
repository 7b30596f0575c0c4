"""The paper's method as a textbook would write it: the baseline blueprint's speed is judged by.

Per layer: a geometry pass into depth + normal textures, a CPU read of the occlusion query to
decide whether to go on, one pass for normal edges and one for depth edges (raw window-depth
threshold), and one blending pass per layer onto the picture; no supersampling. Prints one JSON
object per model and configuration, like ``blueprint bench``.

    python benchmarks/textbook.py MODEL... [--size 512 512] [--max-layers 5] [--frames 20]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import moderngl
import numpy as np

from blueprint import Camera, load_model
from blueprint.scene.normals import corner_normals

VERT = """#version 330 core
uniform mat4 mvp; uniform mat4 mv;
in vec3 p; in vec3 n; out vec3 vn;
void main() { vn = mat3(mv) * n; gl_Position = mvp * vec4(p, 1.0); }"""
PEEL = """#version 330 core
uniform sampler2D prev; uniform bool peel; in vec3 vn;
layout(location = 0) out vec4 normal; layout(location = 1) out float depth;
void main() {
    if (peel && gl_FragCoord.z <= texelFetch(prev, ivec2(gl_FragCoord.xy), 0).r + 1e-6) discard;
    normal = vec4(normalize(vn) * (gl_FrontFacing ? 1.0 : -1.0), 1.0); depth = gl_FragCoord.z;
}"""
QUAD = """#version 330 core
out vec2 uv; void main() { vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
uv = p; gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }"""
NORMAL_EDGE = """#version 330 core
uniform sampler2D normal; out vec4 o;
void main() { ivec2 p = ivec2(gl_FragCoord.xy); vec3 c = texelFetch(normal, p, 0).xyz;
float e = 0.0;
e = max(e, 1.0 - dot(c, texelFetch(normal, p + ivec2(1, 0), 0).xyz));
e = max(e, 1.0 - dot(c, texelFetch(normal, p + ivec2(0, 1), 0).xyz));
o = vec4(step(0.3, e)); }"""
DEPTH_EDGE = """#version 330 core
uniform sampler2D depth; uniform sampler2D edges; out vec4 o;
void main() { ivec2 p = ivec2(gl_FragCoord.xy); float c = texelFetch(depth, p, 0).r;
float e = abs(c - texelFetch(depth, p + ivec2(1, 0), 0).r) + abs(c - texelFetch(depth, p + ivec2(0, 1), 0).r);
o = vec4(max(texelFetch(edges, p, 0).r, step(0.002, e))); }"""
BLEND = """#version 330 core
uniform sampler2D edges; uniform float alpha; out vec4 o;
void main() { o = vec4(1.0, 1.0, 1.0, texelFetch(edges, ivec2(gl_FragCoord.xy), 0).r * alpha); }"""


def frame(ctx, progs, vao, quad, targets, camera, size, max_layers) -> tuple[np.ndarray, int]:
    w, h = size
    depth_tex, normal_tex, edge_a, edge_b, gbufs, edge_fbos, out = targets
    mv = camera.view_matrix()
    mvp = camera.projection_matrix() @ mv
    progs["peel"]["mvp"].write(mvp.T.astype("f4").tobytes())
    progs["peel"]["mv"].write(mv.T.astype("f4").tobytes())
    out.use()
    out.clear(0.07, 0.27, 0.48, 1.0)
    layers = 0
    query = ctx.query(samples=True)
    for i in range(max_layers):
        ctx.enable(moderngl.DEPTH_TEST)
        gbufs[i % 2].use()
        gbufs[i % 2].clear(1.0, 1.0, 1.0, 1.0, depth=1.0)  # depth 1.0: nothing here
        depth_tex[(i + 1) % 2].use(0)
        progs["peel"]["prev"].value = 0
        progs["peel"]["peel"].value = i > 0
        with query:
            vao.render()
        if query.samples == 0:  # the textbook stall: one CPU wait per layer
            break
        layers += 1
        ctx.disable(moderngl.DEPTH_TEST)
        normal_tex[i % 2].use(1)
        progs["nedge"]["normal"].value = 1
        edge_fbos[0].use()
        quad["nedge"].render(vertices=3)
        depth_tex[i % 2].use(2)
        edge_a.use(3)
        progs["dedge"]["depth"].value = 2
        progs["dedge"]["edges"].value = 3
        edge_fbos[1].use()
        quad["dedge"].render(vertices=3)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
        edge_b.use(4)
        progs["blend"]["edges"].value = 4
        progs["blend"]["alpha"].value = 1.0 if i == 0 else 0.7 * 0.8 ** (i - 1)
        out.use()
        quad["blend"].render(vertices=3)
        ctx.disable(moderngl.BLEND)
    image = np.frombuffer(out.read(components=4), np.uint8).reshape(h, w, 4)[::-1]
    return image, layers


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+")
    parser.add_argument("--size", nargs=2, type=int, action="append")
    parser.add_argument("--max-layers", type=int, action="append")
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--warmup", type=int, default=3)
    parser.add_argument("--backend", default="egl")
    args = parser.parse_args()
    ctx = moderngl.create_standalone_context(backend=args.backend, require=330)
    progs = {
        "peel": ctx.program(vertex_shader=VERT, fragment_shader=PEEL),
        "nedge": ctx.program(vertex_shader=QUAD, fragment_shader=NORMAL_EDGE),
        "dedge": ctx.program(vertex_shader=QUAD, fragment_shader=DEPTH_EDGE),
        "blend": ctx.program(vertex_shader=QUAD, fragment_shader=BLEND),
    }
    quad = {k: ctx.vertex_array(progs[k], []) for k in ("nedge", "dedge", "blend")}
    for path in args.models:
        model = load_model(path)
        faces = model.faces[~model.degenerate_faces()]
        data = np.concatenate(
            [model.positions[faces], corner_normals(model.positions, faces, 30.0)], axis=2
        ).astype("f4")
        vbo = ctx.buffer(data.tobytes())
        vao = ctx.vertex_array(progs["peel"], [(vbo, "3f 3f", "p", "n")])
        for size in [tuple(s) for s in (args.size or [[512, 512], [1024, 1024]])]:
            depth_tex = [ctx.texture(size, 1, dtype="f4") for _ in range(2)]
            normal_tex = [ctx.texture(size, 4, dtype="f2") for _ in range(2)]
            rb = ctx.depth_renderbuffer(size)
            gbufs = [ctx.framebuffer([normal_tex[i], depth_tex[i]], rb) for i in range(2)]
            edge_a, edge_b = ctx.texture(size, 1, dtype="f1"), ctx.texture(size, 1, dtype="f1")
            edge_fbos = [ctx.framebuffer([edge_a]), ctx.framebuffer([edge_b])]
            out = ctx.framebuffer([ctx.texture(size, 4)])
            targets = (depth_tex, normal_tex, edge_a, edge_b, gbufs, edge_fbos, out)
            camera = Camera.fit(model.positions, "iso", aspect=size[0] / size[1], up=model.up)
            for max_layers in args.max_layers or [5, 256]:
                for _ in range(args.warmup):
                    frame(ctx, progs, vao, quad, targets, camera, size, max_layers)
                times = []
                for _ in range(args.frames):
                    t = time.perf_counter()
                    _, layers = frame(ctx, progs, vao, quad, targets, camera, size, max_layers)
                    times.append((time.perf_counter() - t) * 1e3)
                ms = statistics.median(times)
                print(
                    json.dumps(
                        {
                            "renderer": ctx.info["GL_RENDERER"],
                            "implementation": "textbook",
                            "model": Path(path).name,
                            "triangles": model.triangle_count,
                            "width": size[0],
                            "height": size[1],
                            "max_layers": max_layers if max_layers < 256 else "all",
                            "layers": layers,
                            "ms": round(ms, 3),
                            "fps": round(1000 / ms, 1),
                        }
                    ),
                    flush=True,
                )
            for obj in (*depth_tex, *normal_tex, rb, *gbufs, edge_a, edge_b, *edge_fbos, out):
                obj.release()
        vao.release()
        vbo.release()


if __name__ == "__main__":
    main()
