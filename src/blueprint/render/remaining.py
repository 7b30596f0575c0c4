"""How many layers a capped peel left: one geometry pass, only on frames that hit the cap.

A peel stopped by ``max_layers`` whose last layer still covered pixels may have more behind
it. Peeling on to count them would cost the full peel the cap was there to save; instead one
pass draws the mesh with no depth test, adding one per fragment behind the last layer into a
float target, and the largest count, reduced on the GPU, is read back (a few texels). Frames
that stop on their own (an empty layer, ``min_fraction``, depth masking) never run it.
"""

from __future__ import annotations

import numpy as np

from blueprint.gpu import units
from blueprint.render.gbuffer import depth_tolerance, peel_uniforms
from blueprint.render.mesh import geometry_program, target_uniform
from blueprint.scene.camera import Camera

REMAINING_FRAG = "blueprint.render:glsl/remaining.frag"
MAX4_FRAG = "blueprint.render:glsl/max4.frag"


def layers_left(capturer, mesh, camera: Camera, last_depth) -> int:
    """The most surfaces any pixel has behind ``last_depth`` (the depth texture of the last
    layer peeled): the layers a peel without its cap would still draw. Coincident surfaces,
    which the peel takes as one, count apart here, so this is an upper bound. Waits for the
    GPU (one read-back); leaves depth test, blending and culling off."""
    r = capturer.device
    ctx = r.ctx
    size = tuple(last_depth.size)
    counts = r.pool.texture("remaining.count", size, "r32f")
    fbo = r.pool.framebuffer((counts,))
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0)
    prog = geometry_program(capturer, REMAINING_FRAG, mesh)
    peel_uniforms(prog, camera, depth_tolerance(camera, mesh.bounds))
    target_uniform(r, prog, size)
    last_depth.use(units.PEEL_DEPTH)
    prog["u_prev_depth"].value = units.PEEL_DEPTH
    ctx.enable_only(ctx.BLEND)
    ctx.blend_func = ctx.ONE, ctx.ONE
    ctx.blend_equation = ctx.FUNC_ADD
    mesh.vao(prog).render()
    ctx.enable_only(ctx.NOTHING)
    # the maximum in passes of 4x4 blocks down to a few texels: reading back a whole frame of
    # floats would cost more than the count itself
    prog, vao = r.fullscreen(MAX4_FRAG)
    prog["u_values"].value = units.INPUTS
    level = 0
    while max(counts.size) > 64:
        size = (-(-counts.size[0] // 4), -(-counts.size[1] // 4))
        reduced = r.pool.texture(f"remaining.max{level}", size, "r32f")
        counts.use(units.INPUTS)
        r.pool.framebuffer((reduced,)).use()
        vao.render(vertices=3)
        counts, level = reduced, level + 1
    # float32 counts are exact far beyond HARD_MAX_LAYERS
    return int(np.frombuffer(counts.read(), np.float32).max(initial=0.0))
