"""The one compositor: the style's paper, then every layer's edge map back to front in its ink
(depth sprites), shaded parts between the layers they lie in, and the highlighted parts'
outline over everything. Fragment passes (8 layers a pass, one texture a layer) or, where the
image passes run as compute shaders, dispatches over 8-slice texture arrays."""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from blueprint.compose.style import STYLES, Style
from blueprint.gpu import units
from blueprint.ops import ChoiceParam, Op

PAPER_FRAG = "blueprint.compose:glsl/paper.frag"
COMPOSITE_FRAG = "blueprint.compose:glsl/composite.frag"
COMPOSE_COMP = "blueprint.compose:glsl/compose.comp"
TILES_VERT = "tiles.vert"  # blueprint.pipeline.tiles: rectangles over chosen tiles
GROUP = 8  # layers a pass composes
SHADE_INDEX_UNIT = units.INPUTS
SHADE_COLOR_UNIT = units.INPUTS + 1
LAYER_UNITS = units.INPUTS + 2  # the group's layer maps, 8 units from here


#: The compositor as a pipeline operation (``blueprint.pipeline.spec.OPERATIONS`` lists it with the
#: library of ``blueprint.ops``): declared here, beside its shader and the styles it names.
COMPOSITE = Op(
    name="composite",
    shader=COMPOSITE_FRAG,
    inputs={"layers": "r8", "highlight": "r8", "shade_color": "rgba8", "shade_index": "r8"},
    output="rgba8",
    params=(ChoiceParam("style", "blueprint", doc="paper and inks", choices=tuple(STYLES)),),
    doc="depth-sprite composite: the style's paper, then every layer's map back to front in its ink, "
    "box-filtered down by the ratio of input to output size (premultiplied alpha); optionally "
    "shading between the layers (shade_color, shade_index) and a highlight map over everything",
    kind="composite",
    stacks=("layers",),
    resample=("layers", "highlight", "shade_color", "shade_index"),
    optional=("highlight", "shade_color", "shade_index"),
)


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


@functools.lru_cache(maxsize=64)
def _dispatches(style: Style, layers: int, supersample: int, highlight: bool, shaded: bool) -> tuple:
    """(overlay, first layer, uniforms) of each dispatch ``Compositor.compute`` runs: the groups
    of layers back-most first, then the highlight's overlay; kept, as every frame of a stream
    asks for the same."""
    common = {
        "u_paper": tuple(style.paper or (0.0, 0.0, 0.0, 0.0)),
        "u_grid_color": tuple(style.grid_color),
        "u_grid": float(style.grid),
        "u_supersample": supersample,
        "u_threshold": bool(style.threshold),
        "u_has_paper": style.paper is not None,
        "u_edges": LAYER_UNITS,
    }
    groups = _groups(layers)
    out = []
    for first in groups:
        count = min(GROUP, layers - first) if layers else 0
        ink = group_inks(style, first, count)
        values = {"u_first": first == groups[0], "u_layers": count, "u_ink": ink, "u_shaded": shaded}
        out.append((False, first, {**common, **values}))
    if highlight:
        ink = inks(np.array([style.highlight]), 0, 1)
        values = {"u_first": False, "u_layers": 1, "u_ink": ink, "u_shaded": False}
        out.append((True, 0, {**common, **values}))
    return tuple(out)


def _groups(layers: int) -> list[int]:
    """First layers of the groups, back-most first."""
    return list(range(((max(layers, 1) - 1) // GROUP) * GROUP, -1, -GROUP))


class Compositor:
    """Composes onto ``target`` (rgba8, premultiplied) with ``r``'s programs and pool."""

    def __init__(self, r) -> None:
        self.r = r
        self._compose: dict[bool, object] = {}  # compose.comp without and with OVERLAY

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
        passes = self.paper(target, style)
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

    def paper(self, target, style: Style) -> int:
        """``target`` made the style's paper, left bound for drawing with blending off; returns
        the draw calls issued."""
        r, ctx = self.r, self.r.ctx
        fbo = r.pool.framebuffer((target,))
        fbo.use()
        ctx.disable(ctx.BLEND)
        if style.paper is None:
            fbo.clear(0.0, 0.0, 0.0, 0.0)
            return 0
        if not style.grid:
            # plain paper is one colour: a clear, far cheaper than a full-screen pass on a
            # software rasteriser; paper.glsl's premultiplication, in float32
            paper = np.asarray(style.paper, np.float32)
            fbo.clear(*(float(v) for v in paper[:3] * paper[3]), float(paper[3]))
            return 0
        prog, vao = r.fullscreen(PAPER_FRAG)
        set_paper(r.uniforms, prog, style)
        vao.render(vertices=3)
        return 1

    def composed_in_place(self, target, prog, style: Style, layers: int, batch: int, draw) -> int:
        """Compose ``layers`` layers onto ``target`` through ``prog``, a pass that composes its
        batch of ``batch`` layers' edge values where it finds them (compose_batch.glsl) instead
        of writing a map a layer for ``fragment`` to read: the paper, then ``draw()`` (the
        pass's draw calls, returned) blended over it as ``fragment`` blends its sprites.
        Returns the draw calls issued."""
        r, ctx = self.r, self.r.ctx
        passes = self.paper(target, style)
        put = r.uniforms.set
        put(prog, "u_threshold", bool(style.threshold))
        # the layers' inks, none past them (their values are 0, whatever the ink)
        put(prog, "u_ink", group_inks(style, 0, layers)[: 16 * batch])
        ctx.enable(ctx.BLEND)
        ctx.blend_func = ctx.ONE, ctx.ONE_MINUS_SRC_ALPHA
        passes += draw()
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
        target.bind_to_image(0, read=True, write=True)
        w, h = target.size
        supersample = max(1, arrays[0].size[0] // w)
        dispatches = _dispatches(style, layers, supersample, highlight is not None, shading is not None)
        for overlay, first, values in dispatches:
            prog = self._compose.get(overlay)
            if prog is None:
                prog = self._compose[overlay] = r.compute(COMPOSE_COMP, {"OVERLAY": overlay})
            r.uniforms.update(prog, values)
            (highlight if overlay else arrays[first // GROUP]).use(LAYER_UNITS)
            if shading is not None and not overlay:
                self._bind_shading(prog, shading, first)
            prog.run((w + 7) // 8, (h + 7) // 8)
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
