"""Layer sources: the ways a frame's layers are captured into its G-buffer, one class a way
behind one protocol (``LayerSource``), each named by a row of the capture table
(``blueprint.render.table``) that says when it is used. Here the protocol and the peel, a
geometry pass a layer; the k-buffer in ``render.kbuffer``, the A-buffer in ``render.abuffer``.
"""

from __future__ import annotations

import contextlib
from typing import Protocol

import numpy as np

from blueprint.gpu import units
from blueprint.render.gbuffer import BACK_BIAS, BACK_OFFSET, GBuffer, depth_tolerance, peel_uniforms
from blueprint.render.mesh import geometry_program, target_uniform
from blueprint.scene.camera import Camera

PEEL_FRAG = "blueprint.render:glsl/peel.frag"


class LayerSource(Protocol):
    """How one frame's layers come into its G-buffer (``render.capture.Capture`` holds the one
    the capture table chose).

    ``open`` (a class method) makes the source for a frame, or None where it cannot hold the
    frame (the chooser's next row is asked then). ``draw(layer, query, guard)`` clears and
    draws layer ``layer`` (its samples counted by ``query``; skipped on the GPU where ``guard``,
    the layer before's query, counted none) and returns the draw calls issued, or None where it
    finds at layer 0 that it cannot hold the frame after all (the peel draws it then).
    ``samples(layer, query)`` is a drawn layer's covered samples; ``deepest()`` the most layers
    any pixel has where the source knows it once layer 0 is drawn (else None: a capped frame's
    layers left take a counting pass); ``tile_layers`` the layers of each ``TILE``-pixel tile
    where it knows them, else None; ``settle()`` reads what was read late (may raise
    ``abuffer.Overflow``); ``release()`` lets go of what it holds for the frame.

    ``reads``: where readers find the layers in place, unpacked into no G-buffer: None (each
    layer is drawn into the G-buffer), ``"surfaces"`` (a k-buffer's) or ``"lists"`` (an
    A-buffer's); there ``bind(prog, layer, step)`` binds the layers from ``layer`` on for a
    reader's program (whose first layers of two passes lie ``step`` apart), with what the pass
    before it wrote made visible, which takes ``defines`` (a k-buffer's ``surfaces`` are its
    targets, for readers that bind them their own way: the vector drawings'). ``counts_kept``:
    the counts stay readable after the next frame is issued (a stream reads them a frame late).
    ``way`` names it for reports (``blueprint bench``).
    """

    way: str
    reads: str | None
    defines: dict
    counts_kept: bool

    @classmethod
    def open(
        cls, capturer, row, mesh, camera: Camera, gb: GBuffer, request, selected
    ) -> LayerSource | None: ...

    def draw(self, layer: int, query, guard=None) -> int | None: ...

    def samples(self, layer: int, query) -> int: ...

    def deepest(self) -> int | None: ...

    @property
    def tile_layers(self) -> np.ndarray | None: ...

    def settle(self) -> None: ...

    def release(self) -> None: ...


class PeelSource:
    """A geometry pass a layer (peel.frag): each layer is the nearest surface behind the one
    before it, drawn into the G-buffer; its occlusion query counts its samples (covered pixels
    and the fragments drawn over again). The back-face tie-break is one draw writing a pushed
    depth, or two culled draws with a polygon offset where the row's ``culled`` says so; with
    ``selected`` (P,) bool only those parts are drawn. Takes any frame."""

    way = "peel"
    reads = None
    defines: dict = {}
    counts_kept = False
    tile_layers = None

    def __init__(self, capturer, row, mesh, camera: Camera, gb: GBuffer, request, selected=None) -> None:
        r = self.r = capturer.device
        self.mesh, self.gb = mesh, gb
        normals = gb.normals
        self.tie_break = request.tie_break
        self.shader_bias = self.tie_break and not row.culled(request, capturer.table.exact_depth)
        defines = {
            "BACK_BIAS_IN_SHADER": self.shader_bias,
            "SELECTED_ONLY": selected is not None,
            "FACE_IDS": request.face_ids,
            "NORMALS": normals,
        }
        prog = self.prog = geometry_program(capturer, PEEL_FRAG, mesh, defines)
        peel_uniforms(prog, camera, depth_tolerance(camera, mesh.bounds))
        target_uniform(r, prog, gb.size)
        if normals:  # only the normal's orientation needs it
            prog["u_ortho"].value = camera.ortho
        if self.shader_bias:
            prog["u_back_bias"].value = BACK_BIAS
        self._flags = None
        if selected is not None:
            data = np.asarray(selected, bool).astype(np.int32).tobytes()
            self._flags = r.ctx.texture((len(selected), 1), 1, data, dtype="i4")
            self._flags.filter = (r.ctx.NEAREST, r.ctx.NEAREST)
            prog["u_selected"].value = units.SELECTED

    @classmethod
    def open(cls, capturer, row, mesh, camera: Camera, gb: GBuffer, request, selected=None) -> PeelSource:
        return cls(capturer, row, mesh, camera, gb, request, selected)

    def draw(self, layer: int, query, guard=None) -> int:
        gb, ctx = self.gb, self.r.ctx
        gb.flat = None
        gb.clears[layer % 2].use()
        gb.clears[layer % 2].clear(depth=1.0)
        gb.depth[0].use(units.PEEL_DEPTH)
        gb.depth[1].use(units.PEEL_DEPTH + 1)
        if self._flags is not None:
            self._flags.use(units.SELECTED)
        with guard.crender if guard is not None else contextlib.nullcontext():
            gb.fbos[layer % 2].use()
            self.prog["u_peel"].value = layer > 0
            self.prog["u_prev_depth"].value = units.PEEL_DEPTH + (layer - 1) % 2
            vao = self.mesh.vao(self.prog)
            if self.shader_bias or not self.tie_break:
                ctx.enable(ctx.DEPTH_TEST)
                with query:
                    vao.render()
                ctx.disable(ctx.DEPTH_TEST)
                return 1
            ctx.enable(ctx.DEPTH_TEST | ctx.CULL_FACE)
            with query:
                ctx.cull_face = "back"
                vao.render()
                ctx.cull_face = "front"
                ctx.polygon_offset = 0.0, BACK_OFFSET
                vao.render()
            ctx.polygon_offset = 0.0, 0.0
            ctx.disable(ctx.DEPTH_TEST | ctx.CULL_FACE)
            return 2

    def samples(self, layer: int, query) -> int:
        return query.samples

    def deepest(self) -> None:
        """Unknown without a counting pass (``render.remaining``)."""
        return None

    def settle(self) -> None:
        """Nothing is read late."""

    def release(self) -> None:
        if self._flags is not None:
            self._flags.release()
            self._flags = None
