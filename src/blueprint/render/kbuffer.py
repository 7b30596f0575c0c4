"""The k-buffer: several layers from one geometry pass (kbuffer.frag), each pixel's nearest
surfaces behind the last layer sorted into up to ``KBUFFER_MAX`` integer targets. A pixel's
fragments read and write its surfaces one after another: through framebuffer fetch (a target a
layer) or under fragment shader interlock (the targets as images)."""

from __future__ import annotations

import contextlib

import numpy as np

from blueprint.gpu import units
from blueprint.render.abuffer import tile_max
from blueprint.render.gbuffer import BACK_BIAS, GBuffer, depth_tolerance, peel_uniforms
from blueprint.render.mesh import geometry_program, target_uniform
from blueprint.scene.camera import Camera

KBUFFER_FRAG = "blueprint.render:glsl/kbuffer.frag"
UNPACK_FRAG = "blueprint.render:glsl/unpack.frag"
# Layers one k-buffer pass finds at most: the targets a fragment shader may write.
KBUFFER_MAX = 8
# The k-buffer's targets hold 16 bytes a pixel a layer (8 for triangle IDs alone); above this
# many bytes the layers are peeled a pass each instead.
KBUFFER_MAX_BYTES = 1 << 29


def kbuffer_layers(layers: int | None) -> int:
    """The layers a k-buffer pass finds for a frame of ``layers`` (None: every layer): as many
    to a pass as evenly fit ``KBUFFER_MAX``."""
    wanted = layers or KBUFFER_MAX
    return -(-wanted // -(-wanted // KBUFFER_MAX))


class KBufferSource:
    """Depth peeling ``k`` layers a geometry pass (``kbuffer_layers``). At every k-th layer one
    geometry pass sorts the k nearest surfaces behind the previous layer into k targets; each
    layer is then unpacked into the G-buffer by a full-screen pass, so whatever reads layers
    sees what the peel draws, its occlusion query counting its covered pixels.

    Where one pass finds every layer of the frame for readers of its surfaces (the row's
    ``holds_frame``: framebuffer fetch alone) the layers stay in the surfaces (``reads``
    ``"surfaces"``, ``bind``), and the pass writes how many each pixel holds into one more
    target, with the surfaces it let go behind them (``count``, read back: the covered pixels of
    every layer, the tiles each covers and the layers a capped frame leaves): on a software
    rasteriser the unpacking and a full-screen pass counting the surfaces cost much of a
    frame's geometry, and readers of the surfaces fetch a pixel's depth, normal and IDs at once.

    A frame of depths and faces alone (``request.normals`` false: a vector drawing's) is one
    pass of ``rg32ui`` surfaces (window depth bits, face + 1), left for its readers
    (``surfaces``, or read back a layer at a time: ``faces``); a pixel's surfaces run up to the
    first with face 0.
    """

    way = "k-buffer"
    counts_kept = False
    defines: dict = {}

    def __init__(self, capturer, row, mesh, camera: Camera, gb: GBuffer, request) -> None:
        r = self.r = capturer.device
        self.mesh, self.gb, self.interlock = mesh, gb, row.interlock
        self.k = kbuffer_layers(request.layers)
        self.ids_only = not request.normals
        self.unpacks = not (self.ids_only or row.holds_frame(request))
        self.reads = None if self.unpacks else "surfaces"
        # (faces alone) each surface's face + 1 read back, 0 at and behind a pixel's first empty one
        self._faces: list[np.ndarray] = []
        # without unpacking: the layers each pixel holds and let go behind them (rg8,
        # count / 255), the pixels each layer covers, the most layers in each tile (``TILE``
        # pixels a side, row 0 at the bottom) and the most any pixel held and let go
        self.count = None
        self._layer_pixels: list[int] = []
        self._tile_layers: np.ndarray | None = None
        self._deepest = 0
        if self.ids_only:
            defines = {"K": self.k, "FACE_IDS": True, "IDS_ONLY": True, "PEEL": False}
            self.prog = geometry_program(capturer, KBUFFER_FRAG, mesh, defines)
            peel_uniforms(self.prog, camera, depth_tolerance(camera, mesh.bounds))
            target_uniform(r, self.prog, gb.size)
            self.prog["u_back_bias"].value = BACK_BIAS
            name, size = f"kbuffer.faces.{gb.size[0]}x{gb.size[1]}", gb.size
            self.surfaces = tuple(r.pool.texture(f"{name}.{i}", size, "rg32ui") for i in range(self.k))
            return
        surface = mesh.surface_defines
        defines = {
            "K": self.k,
            "FACE_IDS": request.face_ids,
            "INTERLOCK": self.interlock,
            "COUNT": not self.unpacks,
            **surface,
        }
        modern = self.interlock
        # the first pass's program, and the one of the passes behind it (kbuffer.frag's PEEL)
        self.prog = geometry_program(capturer, KBUFFER_FRAG, mesh, {**defines, "PEEL": False}, modern=modern)
        self.behind = None
        if self.unpacks:  # (one pass finds every layer otherwise)
            self.behind = geometry_program(
                capturer, KBUFFER_FRAG, mesh, {**defines, "PEEL": True}, modern=modern
            )
        for prog in (self.prog, self.behind) if self.behind is not None else (self.prog,):
            peel_uniforms(prog, camera, depth_tolerance(camera, mesh.bounds))
            target_uniform(r, prog, gb.size)
            prog["u_ortho"].value = camera.ortho
            if request.tie_break:
                prog["u_back_bias"].value = BACK_BIAS
        # the pass that unpacks a layer into the G-buffer, where layers are unpacked at all
        if self.unpacks:
            self.unpack, self.unpack_vao = r.fullscreen(UNPACK_FRAG, surface)
            self.unpack["u_surfaces"].value = units.KBUFFER
            self.unpack["u_back_bias"].value = BACK_BIAS
        self._held = self._surfaces(gb.size)
        self.surfaces = self._held[0]
        # readers fetch every layer from one array sampler where there is one (edges_surfaces.frag)
        self.defines = {**surface, "SURFACE_ARRAY": self._held[4] is not None}

    @classmethod
    def open(cls, capturer, row, mesh, camera: Camera, gb: GBuffer, request, selected=None) -> KBufferSource:
        return cls(capturer, row, mesh, camera, gb, request)

    def _surfaces(self, size: tuple[int, int]) -> tuple:
        """(targets, their framebuffer (with the count's target, without unpack), the one of
        the targets cleared before a pass (the first, and the count's), the count's target or
        None, the array whose slices the targets are or None) at ``size``, kept by the pool;
        named by size, as pipelines peel G-buffers of several sizes in turn. Surfaces read in
        place are the slices of one array where the context makes them (``TargetPool.sliced``)."""
        pool, name, k, unpacks = self.r.pool, f"kbuffer.{size[0]}x{size[1]}", self.k, self.unpacks

        def make() -> tuple:
            array = None
            if unpacks or not pool.slices_viewed:
                surfaces = tuple(pool.texture(f"{name}.{i}", size, "rgba32ui") for i in range(k))
            else:
                array = pool.sliced(f"{name}.slices", size, "rgba32ui", k)
                surfaces = array.slices
            count = None if unpacks else pool.texture(f"{name}.count", size, "rg8")
            return (
                surfaces,
                pool.framebuffer(surfaces if count is None else (*surfaces, count)),
                pool.framebuffer(surfaces[:1] if count is None else (surfaces[0], count)),
                count,
                array,
            )

        return pool.held(("kbuffer", tuple(size), k, unpacks, pool.slices_viewed), make)

    def draw(self, layer: int, query, guard=None) -> int:
        gb = self.gb
        gb.flat = None
        if self.ids_only:
            return self._find_faces() if layer == 0 else 0
        if not self.unpacks:
            # every layer is found at layer 0 and read from the surfaces: no depth to clear, and
            # the first pass's program reads no previous layer (kbuffer.frag without PEEL), so
            # the G-buffer's targets are never made
            return self._find_all() if layer == 0 else 0
        gb.clears[layer % 2].use()
        gb.clears[layer % 2].clear(depth=1.0)
        gb.depth[0].use(units.PEEL_DEPTH)
        gb.depth[1].use(units.PEEL_DEPTH + 1)
        with guard.crender if guard is not None else contextlib.nullcontext():
            return self._draw(layer, query)

    def _find(self, layer: int) -> None:
        """The pass that finds layers ``layer`` to ``layer + k - 1``."""
        ctx, gb = self.r.ctx, self.gb
        surfaces, target, cleared, _, _ = self._held
        # the first target alone is cleared (and the count): kbuffer.frag keeps the rest valid
        # up to a pixel's first empty one, and readers look no further (the count says where)
        cleared.clear()
        prog = self.prog
        if layer > 0:
            prog = self.behind
            prog["u_prev_depth"].value = units.PEEL_DEPTH + (layer - 1) % 2
        if self.interlock:
            # the surfaces as images; the pass rasterises into this layer's depth (not the
            # previous layer's, which it samples), writing nothing there: no depth test
            for unit, tex in enumerate(surfaces):
                tex.bind_to_image(unit, read=True, write=True)
            gb.clears[layer % 2].use()
            self.mesh.vao(prog).render()
            ctx.memory_barrier(ctx.TEXTURE_FETCH_BARRIER_BIT | ctx.FRAMEBUFFER_BARRIER_BIT)
        else:
            target.use()
            self.mesh.vao(prog).render()

    def _find_all(self) -> int:
        """Every layer into the surfaces in one pass, with the layers each pixel holds and let
        go, read back (``count``, the covered pixels, tiles and deepest). Returns the draw
        calls."""
        self._find(0)
        w, h = self.gb.size
        self.count = self._held[3]
        # a pixel's (held, let go) as one word, held + 256 * let go, read whole: only pixels
        # holding K, the most, let surfaces go, so the words order pixels as the layers they
        # hold do, and the largest is 256 times the most let go past K (one contiguous pass
        # each, where the two bytes apart cost several times as much)
        counts = np.frombuffer(self.count.read(), "<u2").reshape(h, w)
        self._layer_pixels = [int(np.count_nonzero(counts > k)) for k in range(self.k)]
        self._tile_layers = np.minimum(tile_max(counts), self.k)
        # layers are nested (a pixel holding k + 1 holds k)
        self._deepest = sum(1 for pixels in self._layer_pixels if pixels) + (int(counts.max()) >> 8)
        return 1

    def _find_faces(self) -> int:
        """Every layer's depths and faces into the surfaces in one pass; its draw calls."""
        ctx, pool = self.r.ctx, self.r.pool
        self._faces.clear()
        pool.framebuffer(self.surfaces[:1]).clear()
        pool.framebuffer(self.surfaces).use()
        ctx.enable_only(ctx.NOTHING)
        self.mesh.vao(self.prog).render()
        return 1

    def faces(self, layer: int) -> np.ndarray:
        """(H * W,) face + 1 of each pixel's ``layer``-th surface (OpenGL rows), 0 where it has
        none; read back up to that layer when first asked for (faces alone)."""
        while len(self._faces) <= layer:
            face = np.frombuffer(self.surfaces[len(self._faces)].read(), np.uint32)[1::2]
            held = face if not self._faces else np.where(self._faces[-1] != 0, face, 0)
            self._faces.append(held)
        return self._faces[layer]

    def _draw(self, layer: int, query) -> int:
        ctx, gb = self.r.ctx, self.gb
        surfaces = self._held[0]
        first = layer % self.k == 0
        if first:
            self._find(layer)
        gb.fbos[layer % 2].use()
        surfaces[layer % self.k].use(units.KBUFFER)
        self.unpack["u_first"].value = first
        self.unpack["u_prev_depth"].value = units.PEEL_DEPTH + (layer - 1) % 2
        ctx.enable(ctx.DEPTH_TEST)
        with query:
            self.unpack_vao.render(vertices=3)
        ctx.disable(ctx.DEPTH_TEST)
        return 2 if first else 1

    def samples(self, layer: int, query) -> int:
        if self.ids_only:
            return int(np.count_nonzero(self.faces(layer)))
        return query.samples if self.unpacks else self._layer_pixels[layer]

    def deepest(self) -> int | None:
        """Where one pass found every layer for its readers with a count: the most any pixel
        held and let go (coincident surfaces apart), once layer 0 is drawn; else None."""
        return None if self.unpacks or self.ids_only else self._deepest

    @property
    def tile_layers(self) -> np.ndarray | None:
        return None if self.unpacks else self._tile_layers

    def bind(self, prog, layer: int, step: int) -> None:
        """The surfaces of the layers from ``layer`` on and the count, for a reader of
        ``u_surfaces`` and ``u_count`` (edges_surfaces.frag): one fetch a pixel and layer gives
        its depth, normal and IDs. ``u_surfaces`` is the array of every layer where the
        surfaces are its slices (``defines``' SURFACE_ARRAY), else ``BATCH`` samplers from
        ``layer`` on (the last repeated past them)."""
        surfaces, array = self._held[0], self._held[4]
        self.count.use(units.INPUTS)
        if array is not None:
            array.use(units.INPUTS + 1)
            bound = units.INPUTS + 1
        else:
            batch = prog["u_surfaces"].array_length
            for k in range(batch):
                surfaces[min(layer + k, len(surfaces) - 1)].use(units.INPUTS + 1 + k)
            bound = tuple(range(units.INPUTS + 1, units.INPUTS + 1 + batch))
        self.r.uniforms.update(prog, {"u_count": units.INPUTS, "u_surfaces": bound, "u_back_bias": BACK_BIAS})

    def settle(self) -> None:
        """Nothing is read late."""

    def release(self) -> None:
        """The targets are the pool's."""
