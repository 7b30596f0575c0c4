"""Layer capture: the G-buffer's targets, the geometry passes that peel depth layers into
them (a pass a layer, or several layers a pass in a k-buffer), the front surface of chosen
parts, and the one peel loop every caller runs, with its stop rules (``blueprint.render.stop``).
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from blueprint.errors import InputError
from blueprint.gpu import units
from blueprint.render.abuffer import ABuffer, tile_max
from blueprint.render.mesh import geometry_program, target_uniform
from blueprint.render.stop import HARD_MAX_LAYERS, StopRule
from blueprint.render.table import ABufferRow, KBufferRow, Request, choose, kbuffer_layers
from blueprint.scene.camera import Camera

# Layers peeled between two looks at the occlusion queries when no maximum is set: one CPU
# wait per chunk instead of one per layer.
CHUNK = 8
# Peeling tolerance in eye depth, as a fraction of the camera's depth range: surfaces closer
# than this count as one (coplanar faces, duplicates, touching parts).
PEEL_EPSILON = 1e-5
PEEL_FRAG = "blueprint.render:glsl/peel.frag"
KBUFFER_FRAG = "blueprint.render:glsl/kbuffer.frag"
UNPACK_FRAG = "blueprint.render:glsl/unpack.frag"
REVEAL_FRAG = "blueprint.render:glsl/reveal.frag"
# Touching solids have coincident faces of opposite winding (the top of one, the bottom of the
# other). Drawing back faces in a second draw pushed back by this polygon offset (in steps of
# the depth buffer) makes the front face win every pixel of the tie, instead of whichever
# rounds nearer (speckle); it is far below the peeling tolerance, so both still peel as one.
BACK_OFFSET = 16.0


@dataclass
class GBuffer:
    """The targets layers are peeled into: two depth textures that alternate (layer ``i`` in
    ``depth[i % 2]``, the previous layer in the other; in ``flat`` where the A-buffer
    captured the layers: read them through ``layer_depth``), the normal target (None for ID-only
    buffers) and the ID target: (face + 1, part + 1) as rg32i, or face + 1 alone as r32i."""

    depth: tuple
    normal: object | None
    ids: object
    fbos: tuple
    clears: tuple
    # float targets that hold the layers' depths instead, where the A-buffer captured them
    flat: tuple | None = None

    @functools.cached_property
    def size(self) -> tuple[int, int]:
        return tuple(self.depth[0].size)

    def layer_depth(self, layer: int):
        return (self.flat or self.depth)[layer % 2]


def gbuffer(pool, size: tuple[int, int], name: str = "gb", normals: bool = True) -> GBuffer:
    """The G-buffer ``name`` at ``size`` from ``pool``; without ``normals``, face IDs alone (a
    quarter of the bytes a fragment: what triangle-ID passes need)."""
    depth = (pool.depth(f"{name}.depth0", size), pool.depth(f"{name}.depth1", size))
    normal = pool.texture(f"{name}.normal", size, "rgba16f") if normals else None
    ids = pool.texture(f"{name}.ids", size, "rg32i" if normals else "r32i")
    colors = (normal, ids) if normals else (ids,)
    fbos = tuple(pool.framebuffer(colors, d) for d in depth)
    clears = tuple(pool.framebuffer((), d) for d in depth)
    return GBuffer(depth, normal, ids, fbos, clears)


def peel_uniforms(prog, camera: Camera) -> None:
    """What every geometry pass of the peel takes from the camera."""
    prog["u_view"].write(camera.view_matrix().T.astype("f4").tobytes())
    prog["u_projection"].write(camera.projection_matrix().T.astype("f4").tobytes())
    prog["u_depth_range"].value = depth_range(camera)
    prog["u_peel_eps"].value = peel_eps(camera)


@functools.lru_cache(maxsize=16)
def abuffer_uniforms(camera: Camera) -> dict:
    """What an A-buffer's geometry pass and resolve take from the camera (``ABuffer``); kept
    by the camera's value, as streams may draw from one camera again and again (read only)."""
    return {
        "u_view": camera.view_matrix().T.astype("f4").tobytes(),
        "u_projection": camera.projection_matrix().T.astype("f4").tobytes(),
        "u_ortho": camera.ortho,
        "u_depth_range": depth_range(camera),
        "u_peel_eps": peel_eps(camera),
    }


def depth_range(camera: Camera) -> tuple[float, float, float]:
    """``u_depth_range`` of depth.glsl: near, far, and 1 for an orthographic camera."""
    return (camera.near, camera.far, 1.0 if camera.ortho else 0.0)


def peel_eps(camera: Camera) -> float:
    """The peeling tolerance in eye depth for ``camera``."""
    return PEEL_EPSILON * (camera.far - camera.near)


class Capture:
    """The geometry passes of one frame into one G-buffer.

    ``face_ids`` false leaves the face channel 0 (a software rasteriser pays for tracking
    primitive IDs, and the blueprint needs only parts). ``tie_break`` pushes back faces behind
    coincident front faces (see ``BACK_OFFSET``); ID-only passes break no ties unless asked.
    ``batch`` > 1 (the layers the frame draws at most; None: all of them) lets one geometry
    pass find that many layers where the driver allows (``_KBuffer``), or every layer
    (``ABuffer``, from ``abuffer_min_layers``, after a k-buffer that finds them all at once
    where ``abuffer_after_kbuffer``). ``selected`` (P,) bool draws only those parts.
    ``tiles``: an A-buffer also finds which tiles each layer covers (``tile_layers``).
    ``defer``: an A-buffer's counts are read only when asked for (``abuffer.Overflow``);
    ``unpack`` false: an A-buffer unpacks no layer into ``gb`` (its caller reads the lists);
    ``slot``: which of the A-buffer's count buffers (``ABuffer``).
    ``surfaces``: a k-buffer that finds every layer of the frame in one pass leaves them in its
    surfaces, unpacked (``kbuffer.unpacks`` false): its caller reads them from there
    (``_KBuffer.surfaces``, ``_KBuffer.count``).
    """

    def __init__(
        self,
        r,
        mesh,
        camera: Camera,
        gb: GBuffer,
        *,
        face_ids: bool = True,
        batch: int | None = 1,
        tie_break: bool | None = None,
        selected: np.ndarray | None = None,
        tiles: bool = False,
        defer: bool = False,
        unpack: bool = True,
        slot: int = 0,
        surfaces: bool = False,
    ) -> None:
        self.r, self.mesh, self.gb = r, mesh, gb
        normals = gb.normal is not None
        self.tie_break = normals if tie_break is None else tie_break
        request = Request(
            tuple(gb.size), mesh.triangles, mesh.part_count, batch, normals, selected is not None, surfaces
        )
        self.abuffer = kbuffer = None
        for row in choose(r.capture_table, request):
            if isinstance(row, ABufferRow):
                abuffer = ABuffer(
                    r,
                    row,
                    mesh,
                    abuffer_uniforms(camera),
                    BACK_OFFSET / (1 << 24),
                    tiles,
                    defer,
                    unpack,
                    slot,
                )
                if abuffer.fits(gb.size):
                    self.abuffer = abuffer
                    break
            elif isinstance(row, KBufferRow):
                kbuffer = row
                break
            else:
                break
        self.prog = self.kbuffer = self._flags = None
        # the peel's own program only where it peels: an A-buffer frame sets up none (unless
        # its lists prove too big for memory, ``draw``)
        self._peel_with = (camera, face_ids, selected, kbuffer, request)
        if self.abuffer is None:
            self._set_up_peel()

    def _set_up_peel(self) -> None:
        r, (w, h) = self.r, self.gb.size
        camera, face_ids, selected, kbuffer, request = self._peel_with
        table = r.capture_table
        normals = self.gb.normal is not None
        culled = kbuffer is None and table.rows[-1].culled(request, table.exact_depth)
        self.shader_bias = self.tie_break and not culled
        behind = None
        if kbuffer is not None:
            surfaces = kbuffer.holds_frame(request)
            batch = kbuffer_layers(request.layers)
            modern = interlock = kbuffer.interlock
            defines = {"K": batch, "FACE_IDS": face_ids, "INTERLOCK": interlock, "COUNT": surfaces}
            prog = geometry_program(r, KBUFFER_FRAG, {**defines, "PEEL": False}, modern=modern)
            if not surfaces:  # (one pass finds every layer there)
                behind = geometry_program(r, KBUFFER_FRAG, {**defines, "PEEL": True}, modern=modern)
        else:
            defines = {
                "BACK_BIAS_IN_SHADER": self.shader_bias,
                "SELECTED_ONLY": selected is not None,
                "FACE_IDS": face_ids,
                "NORMALS": normals,
            }
            prog = geometry_program(r, PEEL_FRAG, defines)
        for each in (prog, behind) if behind is not None else (prog,):
            peel_uniforms(each, camera)
            target_uniform(r, each, (w, h))
            if normals:  # only the normal's orientation needs it
                each["u_ortho"].value = camera.ortho
            if self.shader_bias:
                each["u_back_bias"].value = BACK_OFFSET / (1 << 24)
        self.prog = prog
        if kbuffer is not None:
            self.kbuffer = _KBuffer(r, prog, behind, batch, kbuffer.interlock, unpack=not surfaces)
        if selected is not None:
            data = np.asarray(selected, bool).astype(np.int32).tobytes()
            self._flags = r.ctx.texture((len(selected), 1), 1, data, dtype="i4")
            self._flags.filter = (r.ctx.NEAREST, r.ctx.NEAREST)
            prog["u_selected"].value = units.SELECTED

    @property
    def way(self) -> str:
        """How this capture found its layers, for reports (``blueprint bench``): ``peel`` (a
        geometry pass a layer), ``k-buffer`` (up to 8 layers a pass), ``A-buffer`` (every
        layer from one pass) or ``A-buffer, compute rasteriser`` (its fragments listed in
        compute: render.raster)."""
        if self.abuffer is not None:
            return "A-buffer, compute rasteriser" if self.abuffer.rasterised_in_compute else "A-buffer"
        return "k-buffer" if self.kbuffer is not None else "peel"

    def samples(self, layer: int, query) -> int:
        """Layer ``layer``'s covered pixels: what its occlusion ``query`` counted, or what the
        A-buffer counted where it drew the layer."""
        if self.abuffer is not None:
            pixels = self.abuffer.layer_pixels
            return pixels[layer] if layer < len(pixels) else 0
        if self.kbuffer is not None and not self.kbuffer.unpacks:
            return self.kbuffer.layer_pixels[layer]
        return query.samples

    def counts(self, layers: int, queries) -> list[int]:
        """``samples`` of layers 0 to ``layers`` - 1, each counted by its query of ``queries``."""
        if self.abuffer is not None:
            pixels = self.abuffer.layer_pixels[:layers]
            return pixels + [0] * (layers - len(pixels))
        if self.kbuffer is not None and not self.kbuffer.unpacks:
            return self.kbuffer.layer_pixels[:layers]
        return [queries[k].samples for k in range(layers)]

    @property
    def tile_layers(self) -> np.ndarray | None:
        """The layers of each tile (``abuffer.TILE`` pixels a side, row 0 at the bottom) where
        the A-buffer captured them with ``tiles``, or a k-buffer left them in its surfaces, once
        layer 0 is drawn; else None."""
        if self.abuffer is not None:
            return self.abuffer.tile_layers
        if self.kbuffer is not None and not self.kbuffer.unpacks:
            return self.kbuffer.tile_layers
        return None

    def deepest(self) -> int | None:
        """The most layers any pixel has where the A-buffer captured them, or where a k-buffer
        found every layer of the frame in one pass (its surfaces held and let go, coincident
        ones apart), once layer 0 is drawn; None otherwise: the layers a capped peel left,
        without a counting pass."""
        if self.abuffer is not None:
            return self.abuffer.deepest()
        if self.kbuffer is not None and not self.kbuffer.unpacks:
            return self.kbuffer.deepest
        return None

    def settle(self) -> None:
        """Read a deferred A-buffer's counts (``abuffer.Overflow`` where it had too little
        room): every capture of a frame is known to be whole before the frame is used."""
        if self.abuffer is not None:
            self.abuffer.settle()

    def release(self) -> None:
        if self._flags is not None:
            self._flags.release()
            self._flags = None

    def draw(self, layer: int, query, guard=None) -> int:
        """Clear and draw layer ``layer`` into ``gb.depth[layer % 2]``, its samples counted by
        ``query``; with a ``guard`` query (the layer before's), an empty layer skips its draws
        on the GPU without the CPU waiting (conditional rendering). Returns the draw calls
        issued."""
        gb, ctx = self.gb, self.r.ctx
        if self.abuffer is not None:
            if layer and not self.abuffer.unpacks:
                return 0  # every layer was captured at layer 0, and none is unpacked
            drawn = self.abuffer.draw(gb, layer)
            if drawn is not None:
                gb.flat = self.abuffer.flat(gb.size)
                return drawn
            # more fragments than the lists may hold: peeled a pass a layer
            self.abuffer = None
            self._set_up_peel()
        gb.flat = None
        if self.kbuffer is not None and not self.kbuffer.unpacks:
            # every layer is found at layer 0 and read from the surfaces: no depth to clear;
            # kbuffer.frag's previous layer is read though unused (llvmpipe runs the branch a
            # uniform skips): a depth texture, never one the pass draws into
            gb.depth[1].use(units.PEEL_DEPTH + 1)
            return self.kbuffer.find_all(self.mesh, gb) if layer == 0 else 0
        gb.clears[layer % 2].use()
        gb.clears[layer % 2].clear(depth=1.0)
        gb.depth[0].use(units.PEEL_DEPTH)
        gb.depth[1].use(units.PEEL_DEPTH + 1)
        if self._flags is not None:
            self._flags.use(units.SELECTED)
        with guard.crender if guard is not None else contextlib.nullcontext():
            if self.kbuffer is not None:
                return self.kbuffer.draw(self.mesh, gb, layer, query)
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


class _KBuffer:
    """Depth peeling ``k`` layers a geometry pass. At every k-th layer one geometry pass
    (kbuffer.frag) sorts the k nearest surfaces behind the previous layer into k integer
    targets; each layer is then unpacked into the G-buffer by a full-screen pass, so whatever
    reads layers sees what the one-pass-a-layer peel draws. The layer's occlusion query counts
    its covered pixels.

    Without ``unpack`` (one pass finds every layer of the frame, through framebuffer fetch:
    ``find_all``) the layers stay in the surfaces, and the pass writes how many each pixel holds
    into one more target instead, with the surfaces it let go behind them (``count``, read back:
    the covered pixels of every layer, the tiles each covers and the layers a capped frame
    leaves): on a software rasteriser the unpacking and a full-screen pass counting the
    surfaces cost much of a frame's geometry, and readers of the surfaces fetch a pixel's depth,
    normal and IDs at once."""

    def __init__(self, r, prog, behind, k: int, interlock: bool, unpack: bool = True) -> None:
        # the first pass's program, and the one of the passes behind it (kbuffer.frag's PEEL)
        self.r, self.prog, self.behind, self.k, self.unpacks = r, prog, behind, k, unpack
        self.interlock = interlock
        self.back_bias = BACK_OFFSET / (1 << 24)  # kbuffer.glsl's kb_depth
        # the pass that unpacks a layer into the G-buffer, where layers are unpacked at all
        if unpack:
            self.unpack, self.unpack_vao = r.fullscreen(UNPACK_FRAG)
            self.unpack["u_surfaces"].value = units.KBUFFER
            self.unpack["u_back_bias"].value = self.back_bias
        self._targets: dict[tuple[int, int], tuple] = {}
        # without unpack: the layers each pixel holds and let go behind them (rg8, count / 255),
        # the pixels each layer covers, the most layers in each tile (``TILE`` pixels a side,
        # row 0 at the bottom) and the most any pixel held and let go
        self.count = None
        self.layer_pixels: list[int] = []
        self.tile_layers: np.ndarray | None = None
        self.deepest = 0

    def _surfaces(self, size: tuple[int, int]) -> tuple:
        """(targets, their framebuffer (with the count's target, without unpack), the one of
        the targets cleared before a pass (the first, and the count's), the count's target or
        None) at ``size``: pipelines peel G-buffers of several sizes in turn, so the targets
        are named by size too."""
        held = self._targets.get(size)
        if held is None:
            pool, name = self.r.pool, f"kbuffer.{size[0]}x{size[1]}"
            surfaces = tuple(pool.texture(f"{name}.{i}", size, "rgba32ui") for i in range(self.k))
            count = None if self.unpacks else pool.texture(f"{name}.count", size, "rg8")
            held = self._targets[size] = (
                surfaces,
                pool.framebuffer(surfaces if count is None else (*surfaces, count)),
                pool.framebuffer(surfaces[:1] if count is None else (surfaces[0], count)),
                count,
            )
        return held

    @property
    def surfaces(self) -> tuple:
        """The targets of the last pass, surface ``k`` of each pixel in the ``k``-th."""
        return self._surfaces(self.count.size)[0]

    def _find(self, mesh, gb: GBuffer, layer: int) -> None:
        """The pass that finds layers ``layer`` to ``layer + k - 1``."""
        ctx = self.r.ctx
        surfaces, target, cleared, _ = self._surfaces(gb.size)
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
            mesh.vao(prog).render()
            ctx.memory_barrier(ctx.TEXTURE_FETCH_BARRIER_BIT | ctx.FRAMEBUFFER_BARRIER_BIT)
        else:
            target.use()
            mesh.vao(prog).render()

    def find_all(self, mesh, gb: GBuffer) -> int:
        """Every layer into the surfaces in one pass, with the layers each pixel holds and let
        go, read back (``count``, ``layer_pixels``, ``tile_layers``, ``deepest``). Returns the
        draw calls."""
        self._find(mesh, gb, 0)
        w, h = gb.size
        self.count = self._surfaces(gb.size)[3]
        counts = np.frombuffer(self.count.read(), np.uint8).reshape(h, w, 2)
        held = np.ascontiguousarray(counts[..., 0])
        self.layer_pixels = [int(np.count_nonzero(held > k)) for k in range(self.k)]
        self.tile_layers = tile_max(held)
        # only pixels holding K let surfaces go; layers are nested (a pixel holding k + 1 holds k)
        self.deepest = sum(1 for pixels in self.layer_pixels if pixels) + int(counts[..., 1].max())
        return 1

    def draw(self, mesh, gb: GBuffer, layer: int, query) -> int:
        ctx = self.r.ctx
        surfaces = self._surfaces(gb.size)[0]
        first = layer % self.k == 0
        if first:
            self._find(mesh, gb, layer)
        gb.fbos[layer % 2].use()
        surfaces[layer % self.k].use(units.KBUFFER)
        self.unpack["u_first"].value = first
        self.unpack["u_prev_depth"].value = units.PEEL_DEPTH + (layer - 1) % 2
        ctx.enable(ctx.DEPTH_TEST)
        with query:
            self.unpack_vao.render(vertices=3)
        ctx.disable(ctx.DEPTH_TEST)
        return 2 if first else 1


def capture_parts(r, mesh, camera: Camera, size: tuple[int, int], parts: np.ndarray, name: str, what: str):
    """The front surface of the flagged parts alone, in the G-buffer ``name`` (layer 0, in
    ``depth[0]``), with face IDs: depth masking, highlighted and shaded parts."""
    parts = np.asarray(parts, bool)
    if parts.shape != (mesh.part_count,):
        raise InputError(f"{what} needs one flag per part ({mesh.part_count}), got {parts.shape}")
    gb = gbuffer(r.pool, size, name)
    capture = Capture(r, mesh, camera, gb, selected=parts)
    r.ctx.enable_only(r.ctx.NOTHING)
    r.ctx.depth_func = "<"
    capture.draw(0, r.queries("capture")[0])
    capture.release()
    return gb


def peel(
    draw: Callable[[int, object, object], None],
    queries: Sequence,
    rules: Sequence[StopRule],
    on_counted: Callable[[int], None] | None = None,
    look: bool = True,
    samples: Callable[[int, object], int] | None = None,
    eager: bool = False,
) -> tuple[list[int], int]:
    """The one peel loop. ``draw(layer, query, guard)`` issues layer ``layer``'s geometry pass
    (counting its samples in ``query``, skipped on the GPU when ``guard``, the layer before's
    query, counted none) and whatever runs per layer. Returns the samples of every layer
    peeled and how many of them count under ``rules``.

    The CPU looks at the counts after every layer where a rule needs it or where the caller
    reads each counted layer back (``on_counted``, called once the layer is known to count);
    else once per ``CHUNK`` layers, or once at the end when a rule caps the layers. Without
    ``look`` (a capped peel whose caller reads nothing back) it never waits: every layer up to
    the cap is issued, and the counts are left unread (returned empty). ``eager`` looks after
    every layer all the same: on a software rasteriser the CPU waiting costs nothing, while a
    capped frame of a shallow model would otherwise draw its empty layers to the cap.
    ``samples(layer, query)`` reads a layer's count where not every layer is counted by its
    query (``Capture.samples``).
    """
    samples = samples or (lambda layer, query: query.samples)
    limits = [r.limit() for r in rules if r.limit() is not None]
    limit = min(limits) if limits else HARD_MAX_LAYERS
    every_layer = on_counted is not None or any(r.every_layer for r in rules)
    step = 1 if every_layer or eager else (limit if limits else CHUNK)
    if not look:
        if every_layer or not limits:
            raise ValueError("a peel that does not look needs a cap and no rule that looks every layer")
        for layer in range(limit):
            draw(layer, queries[layer], queries[layer - 1] if layer else None)
        return [], limit
    peeled = counted = 0
    counts: list[int] = []
    while peeled < limit:
        end = min(limit, peeled + step)
        for layer in range(peeled, end):
            draw(layer, queries[layer], queries[layer - 1] if layer else None)
        counts += [samples(k, queries[k]) for k in range(peeled, end)]
        peeled = end
        counted = min((r.count(counts) for r in rules), default=len(counts))
        if on_counted is not None and counted == peeled:
            on_counted(peeled - 1)
        # every rule looks (depth masking counts what the last layer uncovered), then any stops
        finished = [r.done(counts) for r in rules]
        if counted < peeled or any(finished):
            break
    # a chunk looked at at once may hold several layers past the last that counts: the counts
    # end at the first of them, as looking after each layer would have
    return counts[: counted + 1], counted


def revealed_pixels(r, camera: Camera, mask, layer_depth=None) -> int:
    """Pixels of the chosen parts' front surface ``mask`` (a depth texture) that lie in or in
    front of ``layer_depth``, i.e. are uncovered once that layer is peeled (all of the mask's
    pixels without a layer), counted by an occlusion query and read back: depth masking."""
    prog, vao = r.fullscreen(REVEAL_FRAG)
    prog["u_depth_range"].value = depth_range(camera)
    prog["u_peel_eps"].value = peel_eps(camera)
    mask.use(units.INPUTS)
    prog["u_mask_depth"].value = units.INPUTS
    (layer_depth or mask).use(units.INPUTS + 1)
    prog["u_layer_depth"].value = units.INPUTS + 1
    prog["u_count_all"].value = layer_depth is None
    r.pool.framebuffer((r.pool.texture("reveal.scratch", tuple(mask.size), "r8"),)).use()
    query = r.queries("reveal")[0]
    with query:
        vao.render(vertices=3)
    return query.samples
