"""The one compositor: the style's paper, then every layer's edge map back to front in its ink
(depth sprites), shaded parts between the layers they lie in, and the highlighted parts'
outline over everything. Fragment passes (8 layers a pass, one texture a layer) or, where the
image passes run as compute shaders, dispatches over 8-slice texture arrays."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from blueprint.compose.style import Style
from blueprint.gpu import units

PAPER_FRAG = "blueprint.compose:glsl/paper.frag"
COMPOSITE_FRAG = "blueprint.compose:glsl/composite.frag"
COMPOSE_COMP = "blueprint.compose:glsl/compose.comp"
TILES_VERT = "tiles.vert"  # blueprint.pipeline.tiles: rectangles over chosen tiles
GROUP = 8  # layers a pass composes
SHADE_INDEX_UNIT = units.INPUTS
SHADE_COLOR_UNIT = units.INPUTS + 1
LAYER_UNITS = units.INPUTS + 2  # the group's layer maps, 8 units from here


@dataclass
class Shading:
    """Shaded parts for the compositor: ``index`` (r8, 1 + the layer their surface lies in,
    0 where none) and ``color`` (premultiplied rgba8), at the edge maps' size."""

    index: object
    color: object


def inks(all_inks: np.ndarray, first: int, count: int) -> bytes:
    """``u_ink`` of a group: 8 straight colours with opacity, the group's first."""
    block = np.zeros((GROUP, 4), np.float32)
    block[:count] = all_inks[first : first + count]
    return block.tobytes()


@functools.lru_cache(maxsize=256)
def group_inks(style: Style, first: int, count: int) -> bytes:
    """``inks`` of the layers ``first`` to ``first + count`` of ``style`` (a layer's ink does
    not depend on how many follow it), kept: every frame asks for the same few."""
    return inks(style.layer_inks(first + count), first, count)


def set_paper(uniforms, prog, style: Style) -> None:
    uniforms.set(prog, "u_paper", tuple(style.paper or (0.0, 0.0, 0.0, 0.0)))
    uniforms.set(prog, "u_grid_color", tuple(style.grid_color))
    uniforms.set(prog, "u_grid", float(style.grid))


def _groups(layers: int) -> list[int]:
    """First layers of the groups, back-most first."""
    return list(range(((max(layers, 1) - 1) // GROUP) * GROUP, -1, -GROUP))


class Compositor:
    """Composes onto ``target`` (rgba8, premultiplied) with ``r``'s programs and pool."""

    def __init__(self, r) -> None:
        self.r = r

    def fragment(
        self,
        target,
        stack: Sequence,
        layers: int,
        style: Style,
        *,
        highlight=None,
        shading: Shading | None = None,
        tiles=None,
    ) -> int:
        """Compose the first ``layers`` maps of ``stack`` (one texture a layer); returns the
        draw calls issued. ``tiles(program, first, count)`` draws a group of layers over the
        tiles they have lines in (``blueprint.pipeline.tiles``; the program built with
        ``TILES_VERT``) instead of over the whole target."""
        r, ctx = self.r, self.r.ctx
        put = r.uniforms.set
        fbo = r.pool.framebuffer((target,))
        fbo.use()
        ctx.disable(ctx.BLEND)
        passes = 0
        if style.paper is None:
            fbo.clear(0.0, 0.0, 0.0, 0.0)
        else:
            prog, vao = r.fullscreen(PAPER_FRAG)
            set_paper(r.uniforms, prog, style)
            vao.render(vertices=3)
            passes += 1
        sprites = []  # (maps, inks, first layer, shading, drawn over the layers' tiles)
        if layers:
            for first in _groups(layers):
                count = min(GROUP, layers - first)
                group = stack[first : first + count]
                sprites.append((group, group_inks(style, first, count), first, shading, tiles is not None))
        if highlight is not None:
            sprites.append(([highlight], inks(np.array([style.highlight]), 0, 1), 0, None, False))
        ctx.enable(ctx.BLEND)
        ctx.blend_func = ctx.ONE, ctx.ONE_MINUS_SRC_ALPHA
        for maps, ink, first, shaded, tiled in sprites:
            factor = max(1, maps[0].size[0] // target.size[0])
            defines = {"LAYERS_FACTOR": factor, "SHADED": shaded is not None, "COUNT": len(maps)}
            if tiled:
                prog = r.program(COMPOSITE_FRAG, TILES_VERT, defines)
            else:
                prog, vao = r.fullscreen(COMPOSITE_FRAG, defines)
            put(prog, "u_threshold", bool(style.threshold))
            for k, tex in enumerate(maps):
                tex.use(LAYER_UNITS + k)
                put(prog, f"u_layers{k}", LAYER_UNITS + k)
            put(prog, "u_ink", ink[: 16 * len(maps)])
            if shaded is not None:
                self._bind_shading(prog, shaded, first)
            if tiled:
                passes += tiles(prog, first, len(maps))
            else:
                vao.render(vertices=3)
                passes += 1
        ctx.disable(ctx.BLEND)
        return passes

    def compute(
        self,
        target,
        arrays: Sequence,
        layers: int,
        style: Style,
        *,
        highlight=None,
        shading: Shading | None = None,
    ) -> int:
        """Compose the first ``layers`` slices of ``arrays`` (8-slice r8 texture arrays) by
        compute dispatches; returns the dispatches run."""
        r, ctx = self.r, self.r.ctx
        put = r.uniforms.set
        target.bind_to_image(0, read=True, write=True)
        groups = _groups(layers)
        supersample = max(1, arrays[0].size[0] // target.size[0])
        dispatches = [(arrays[f // GROUP], min(GROUP, layers - f) if layers else 0, f, False) for f in groups]
        if highlight is not None:
            dispatches.append((highlight, 1, 0, True))
        for maps, count, first, overlay in dispatches:
            prog = r.compute(COMPOSE_COMP, {"OVERLAY": overlay})
            set_paper(r.uniforms, prog, style)
            put(prog, "u_supersample", supersample)
            put(prog, "u_threshold", bool(style.threshold))
            put(prog, "u_has_paper", style.paper is not None)
            maps.use(LAYER_UNITS)
            put(prog, "u_edges", LAYER_UNITS)
            put(prog, "u_first", first == groups[0] and not overlay)
            put(prog, "u_layers", count)
            ink = inks(np.array([style.highlight]), 0, 1) if overlay else group_inks(style, first, count)
            put(prog, "u_ink", ink)
            shaded = shading is not None and not overlay
            put(prog, "u_shaded", shaded)
            if shaded:
                self._bind_shading(prog, shading, first)
            prog.run((target.size[0] + 7) // 8, (target.size[1] + 7) // 8)
            ctx.memory_barrier(ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)
        ctx.memory_barrier(
            ctx.TEXTURE_FETCH_BARRIER_BIT | ctx.TEXTURE_UPDATE_BARRIER_BIT | ctx.FRAMEBUFFER_BARRIER_BIT
        )
        return len(dispatches)

    def _bind_shading(self, prog, shading: Shading, first: int) -> None:
        put = self.r.uniforms.set
        shading.index.use(SHADE_INDEX_UNIT)
        shading.color.use(SHADE_COLOR_UNIT)
        put(prog, "u_shade_index", SHADE_INDEX_UNIT)
        put(prog, "u_shade_color", SHADE_COLOR_UNIT)
        put(prog, "u_first_layer", first)
