"""A run's layer capture (``LayerCapture``): the front surface of chosen parts, depth masking's
stop rule, one G-buffer (and the attribute pass's targets) a scale, and the frame's layers
drawn through the one layer loop (``render.capture.layer_loop``), the executor's per-layer
passes run after each layer."""

from __future__ import annotations

from dataclasses import dataclass

from blueprint.gpu import units
from blueprint.ops import EDGES
from blueprint.pipeline.arrays import ArrayPlan
from blueprint.pipeline.graph import Plan
from blueprint.pipeline.inputs import read_texture
from blueprint.pipeline.programs import FULLSCREEN
from blueprint.pipeline.state import EXTRA, Group, RunState
from blueprint.render.abuffer import Overflow
from blueprint.render.capture import Capture, GBuffer, capture_parts, layer_loop, revealed_pixels
from blueprint.render.gbuffer import depth_tolerance
from blueprint.render.remaining import layers_left
from blueprint.render.stop import EmptyLayer, MaxLayers, MinFraction, Reveal, StopRule


@dataclass(frozen=True)
class InPlace:
    """An op's forms that read layers where a capture holds them, by ``LayerSource.reads``."""

    fragment: dict[str, str]
    compute: dict[str, str]


# The in-place forms of the library's ops (those whose descriptor allows ``Op.in_place``), by
# where a capture holds the layers (``LayerSource.reads``): fragment passes of a batch of layers,
# compute passes of an array of ``SLICES`` layers.
IN_PLACE = {
    EDGES.name: InPlace(
        fragment={
            "surfaces": "blueprint.pipeline:glsl/edges_surfaces.frag",
            "lists": "blueprint.pipeline:glsl/edges_lists.frag",
        },
        compute={"lists": "blueprint.pipeline:glsl/edges_lists.comp"},
    )
}
ATTR_VERT = "blueprint.pipeline:glsl/attributes.vert"
ATTR_FRAG = "blueprint.pipeline:glsl/attributes.frag"
BASE_UNIT = units.INPUTS


class LayerCapture:
    """The capture side of ``ex``'s runs (its device, capturer, programs, passes and targets)."""

    def __init__(self, ex) -> None:
        self.ex, self.r, self.capturer, self.programs = ex, ex.r, ex.capturer, ex.programs
        # what a plan's captures are (``layout``) and which passes read the lists, by the
        # plan's id: every frame of a stream asks again
        self._layouts: dict[int, tuple[Plan, Layout]] = {}
        self._lists: dict[int, tuple[Plan, ArrayPlan, tuple[str, ...]]] = {}
        self._surface_readers: dict[int, tuple[Plan, tuple[str, ...]]] = {}
        # the last rules peeled under: whether any looks after every layer, whether only a cap
        # stops the peel (the executor keeps a frame's standard rules from one frame to the next)
        self._rules: tuple = (None, False, False)

    def capture_parts(self, st: RunState, parts: dict) -> None:
        """The front surface of every set of chosen parts an attribute reads, once a frame,
        before the peel."""
        bound = st.pl.bound
        held: dict[tuple[str, float], GBuffer] = {}
        for name in st.pl.parts:
            spec = bound.attributes[name]
            key = (spec.parts, spec.scale)
            if key not in held:
                held[key] = capture_parts(
                    self.capturer,
                    st.mesh,
                    st.camera,
                    st.size_of(spec.scale),
                    parts[spec.parts],
                    f"parts.{spec.parts}.{spec.scale:g}",
                    spec.parts,
                )
                st.draws += 1
            gb = held[key]
            st.parts[name] = {"depth": gb.depth[0], "normal": gb.normal, "ids": gb.ids}[spec.of]

    def reveal_rule(self, st: RunState) -> StopRule | None:
        """Depth masking, where the pipeline declares it: counts the chosen parts' pixels now,
        and after every layer those the layers peeled so far uncovered."""
        bound = st.pl.bound
        stops = [s for s in bound.stops if s.rule == "reveal"]
        if not stops:
            return None
        stop = stops[0]
        mask = st.parts[stop.depth]
        tolerance = depth_tolerance(st.camera, st.mesh.bounds)
        wanted = revealed_pixels(self.r, st.camera, tolerance, mask)
        st.draws += 1

        def revealed(layer: int) -> int:
            st.draws += 1
            return revealed_pixels(self.r, st.camera, tolerance, mask, st.groups[0].gb.layer_depth(layer))

        return Reveal(stop.fraction, wanted, revealed)

    def draw_layers(
        self, st: RunState, max_layers, rules, blind: bool = False
    ) -> tuple[list[int] | None, int]:
        """Peel ``st``'s layers under ``rules``, running the per-layer passes after each; the
        samples of every layer peeled and how many count (``render.capture.layer_loop``).
        Where nothing looks at a layer before the next is issued (a GPU, no rule or read-back
        per layer), the A-buffer's counts are read only once the layers are issued, so the CPU
        does not wait for the capture; one that then proves short of room is drawn again.
        ``blind``, where only a cap and empty layers stop the peel: every layer to the cap is
        issued and nothing read (the counts None): the caller issues the rest of its frame and
        then reads them (``counted``; ``abuffer.Overflow`` there means the frame must be drawn
        again). An empty layer draws nothing, so drawing to the cap changes no picture."""
        if rules is not self._rules[0]:
            self._rules = (rules, any(rule.every_layer for rule in rules), _capped(rules))
        _, every_layer, capped = self._rules
        eager = self.r.software
        defer = not eager and not st.attr_dumps and not every_layer
        blind = blind and defer and capped
        if defer:
            try:
                return self._peel(st, max_layers, rules, eager, defer=True, blind=blind)
            except Overflow:
                st.groups.clear()
        return self._peel(st, max_layers, rules, eager, defer=False, blind=False)

    def counted(self, st: RunState, rules, drawn: int) -> tuple[list[int], int]:
        """A blind peel's samples of the ``drawn`` layers it issued and how many count
        (``abuffer.Overflow`` where an A-buffer had too little room). Where every layer came
        from A-buffers (``lists_only``) this may wait until the next frame is issued."""
        for g in st.groups:
            g.capture.settle()
        g = st.groups[0]
        counts = g.capture.counts(drawn, g.queries)
        layers = min((rule.count(counts) for rule in rules), default=len(counts))
        # as a peel that looks would have stopped: at the first empty layer
        return counts[: layers + 1], layers

    def counted_late(self, st: RunState, rules, drawn: int) -> tuple[list[int], int, int]:
        """``counted`` and ``left`` of a streamed frame, once its picture is read
        (``Result.counting``)."""
        counts, layers = self.counted(st, rules, drawn)
        return counts, layers, self.left(st, rules, counts, layers)

    def _peel(
        self, st: RunState, max_layers, rules, eager: bool, defer: bool, blind: bool
    ) -> tuple[list[int] | None, int]:
        """``draw_layers``, its counts read late where ``defer``: the G-buffers and captures
        opened, the layers drawn, and the passes that read every layer from the lists run."""
        layout = self._layout(st.pl)
        self._open_groups(st, layout)
        # a software rasteriser looks at every layer's count before its passes run (``eager``),
        # and at where the layer lies, for passes that need only be drawn there (pipeline.tiles)
        tiled = self.ex.tiled and st.arrays is None
        tiled = tiled and any(self.ex.reach(st, n) is not None for n in st.pl.per_layer)
        from_lists, layer_lists, from_surfaces = self._in_place(st, rules, defer)
        for g in st.groups:
            g.capture = Capture(
                self.capturer,
                st.mesh,
                st.camera,
                g.gb,
                face_ids=layout.face_ids,
                layers=max_layers,
                tiles=tiled and g.primary,
                defer=defer,
                unpack=not (from_lists or layer_lists),
                slot=st.slot,
                surfaces=bool(from_surfaces),
            )
        if st.groups[0].capture.reads == "surfaces":
            st.from_surfaces = from_surfaces
        extras = self._attribute_programs(st) if layout.extra else None
        for name in st.pl.accumulated:
            self.r.pool.framebuffer((self.ex.target(st, name, 0),)).clear()
        lists = (from_lists, layer_lists)
        frame = _LayerPasses(self, st, max_layers, eager, tiled, lists, extras, self._rules[2])
        primary = st.groups[0]
        if blind:
            peeled = None, layer_loop(frame.draw, primary.queries, rules, look=False)[1]
        else:
            peeled = layer_loop(
                frame.draw, primary.queries, rules, samples=primary.capture.samples, eager=eager
            )
            for g in st.groups:
                g.capture.settle()
        if frame.listed:
            layers = peeled[1]
            self.ex.ensure_stacks(st, max(layers, 1))
            for name in frame.listed:
                self.ex.run_in_place(st, name, primary.capture, layers)
        return peeled

    def _in_place(self, st: RunState, rules, defer: bool) -> tuple[tuple[str, ...], ...]:
        """The passes that read the layers where the capture may hold them: from an A-buffer's
        lists every layer after the peel, or each layer as it comes, or from a k-buffer's
        surfaces."""
        # edges read straight from an A-buffer's lists, all layers after the peel, where nothing
        # else reads the layers: none is unpacked then
        from_lists = self._from_lists(st) if defer and st.arrays is not None else ()
        # ...or, where passes run a layer at a time (a software rasteriser), read each layer
        # from the lists as it comes, unless a stop rule reads the layers (depth masking)
        looks = any(rule.every_layer for rule in rules)
        layer_lists = self._from_lists(st) if st.arrays is None and not looks else ()
        # ...or from the surfaces of a k-buffer that finds every layer in one pass, where no
        # rule looks at each layer
        from_surfaces = self._from_surfaces(st) if not from_lists and not self._rules[1] else ()
        return from_lists, layer_lists, from_surfaces

    def _open_groups(self, st: RunState, layout: Layout) -> None:
        """One G-buffer (with the attribute pass's targets) for each scale of the attributes."""
        for scale, names, primary in layout.scales:
            st.groups.append(
                Group(self.r, scale, st.size_of(scale), names, primary, st.pl.bound, layout.clear_gb)
            )
        st.by_attr = {n: g for g in st.groups for n in g.names}
        self.r.ctx.depth_func = "<"

    def _from_lists(self, st: RunState) -> tuple[str, ...]:
        """The passes that may read their layers from an A-buffer's lists: every layer
        after the peel in the compute form (``Executor.run_in_place``), else each layer as it
        comes (``Executor.run_pass``); where they are the only readers of the G-buffer,
        read the renderer's own depth, normal and IDs in a form that reads them in place
        (``Op.in_place``, ``IN_PLACE``), and no layer is read back or given extra attributes."""
        pl, arrays = st.pl, st.arrays
        if st.attr_dumps:
            return ()
        held = self._lists.get(id(pl))
        if held is None or held[0] is not pl or held[1] is not arrays:
            held = self._lists[id(pl)] = (pl, arrays, _lists_readers(pl, arrays, self._layout(pl)))
        return held[2]

    def _from_surfaces(self, st: RunState) -> tuple[str, ...]:
        """The passes that may read each layer from a k-buffer's surfaces (fragment form:
        ``Executor.run_pass``), on the same terms as ``_from_lists``."""
        pl = st.pl
        if st.arrays is not None or st.attr_dumps:
            return ()
        held = self._surface_readers.get(id(pl))
        if held is None or held[0] is not pl:
            held = self._surface_readers[id(pl)] = (pl, _in_place_readers(pl, self._layout(pl), "surfaces"))
        return held[1]

    def _layout(self, pl: Plan) -> Layout:
        held = self._layouts.get(id(pl))
        if held is None or held[0] is not pl:
            held = self._layouts[id(pl)] = (pl, layout(pl))
        return held[1]

    def lists_only(self, st: RunState) -> bool:
        """Whether every capture of the run drew into an A-buffer, whose counts stay readable
        (each frame of two its own) after the next frame is issued."""
        return all(g.capture.counts_kept for g in st.groups)

    def left(self, st: RunState, rules, counts: list[int], layers: int) -> int:
        """Layers left behind the last one where the peel stopped at its cap with the last layer
        still covering pixels (one counting pass, see ``blueprint.render.remaining``); else 0,
        at no cost."""
        caps = [rule.layers for rule in rules if isinstance(rule, MaxLayers)]
        if not caps or layers < min(caps) or not counts or counts[layers - 1] == 0:
            return 0
        deepest = st.groups[0].capture.deepest()
        if deepest is not None:
            return max(0, deepest - layers)
        st.draws += 1
        return layers_left(self.capturer, st.mesh, st.camera, st.groups[0].gb.layer_depth(layers - 1))

    def _attribute_programs(self, st: RunState) -> dict:
        progs = {}
        camera, lo, hi = st.camera, *st.mesh.bounds
        for g in st.groups:
            if not g.extra:
                continue
            defines = {f"OUT_{n.upper()}": (g.extra.index(n) if n in g.extra else -1) for n in EXTRA}
            # the peel's depth rule (render.mesh.geometry_program), for attributes where its depths are
            exact = {"EXACT_DEPTH": self.capturer.table.exact_depth}
            draw = self.programs.library(
                ATTR_FRAG, ATTR_VERT, {**defines, **exact, **st.mesh.vertex_defines, "CLEAR": 0}
            )
            clear = self.programs.library(ATTR_FRAG, FULLSCREEN, {**defines, "CLEAR": 1})
            self.programs.set(draw, "u_view", camera.view_matrix().T.astype("f4").tobytes())
            self.programs.set(draw, "u_projection", camera.projection_matrix().T.astype("f4").tobytes())
            self.programs.set(draw, "u_bounds_lo", tuple(float(v) for v in lo))
            self.programs.set(draw, "u_bounds_size", tuple(float(max(v, 1e-30)) for v in hi - lo))
            self.programs.set(draw, "u_layer_depth", BASE_UNIT)
            self.programs.set(draw, "u_ids", BASE_UNIT + 1)
            self.programs.set(draw, "u_target", tuple(float(v) for v in g.gb.size))
            progs[g.scale] = (draw, clear)
        return progs


class _LayerPasses:
    """One frame's layers as the layer loop draws them (``draw``): each G-buffer's capture and
    attribute pass, the attributes read back, and the passes run after each layer, a batch of
    layers at once for those that read the layers where the capture holds them."""

    def __init__(
        self, side: LayerCapture, st: RunState, max_layers, eager: bool, tiled: bool, lists, extras, capped
    ):
        self.ex, self.programs, self.st = side.ex, side.programs, st
        self.max_layers, self.eager, self.tiled, self.extras = max_layers, eager, tiled, extras
        self.capped = capped  # only the cap and empty layers stop the peel
        # passes that read the A-buffer's lists: all layers after the peel, or each as it comes
        self.from_lists, self.layer_lists = lists
        # the passes run after each layer: not those over whole arrays after the peel, nor those
        # read from the lists (known once layer 0 is drawn)
        batches = st.arrays.batches if st.arrays is not None else ()
        self.first = [n for n in st.pl.iteration0 if n not in batches]
        self.later = [n for n in st.pl.per_layer if n not in batches]
        self.listed: list[str] = []

    def draw(self, layer: int, query, guard) -> None:
        st = self.st
        self.ex.ensure_stacks(st, layer + 1)
        self._capture(layer, query, guard)
        if layer == 0:
            self._readers_known()
        for name, held in st.attr_dumps.items():
            tex = st.by_attr[name].texture(name, layer)
            held.append(read_texture(tex, st.pl.bound.attributes[name].format))
        primary = st.groups[0]
        if self.eager and layer and not primary.capture.samples(layer, primary.queries[layer]):
            return  # an empty layer ends the peel (EmptyLayer): nothing reads its passes
        if self.tiled:
            if primary.capture.tile_layers is not None:
                self.ex.tiles.layer_of(primary.capture.tile_layers, layer, primary.size)
            else:
                self.ex.tiles.look(primary.gb.layer_depth(layer), layer)
        self._run_passes(layer)

    def _capture(self, layer: int, query, guard) -> None:
        """Layer ``layer`` of every G-buffer, and its attribute pass."""
        st = self.st
        for g in st.groups:
            if g.attr_clear is not None:
                g.attr_clear.clear()
            if g.primary:
                st.draws += g.capture.draw(layer, query, guard)
            else:
                st.draws += g.capture.draw(layer, g.queries[layer], g.queries[layer - 1] if layer else None)
            if g.extra:
                self._attributes(g, layer)

    def _attributes(self, g: Group, layer: int) -> None:
        """The attribute pass's targets of layer ``layer`` of ``g``, after its geometry pass."""
        programs = self.programs
        draw, clear = self.extras[g.scale]
        g.extra_fbo.use()
        programs.vao(clear).render(vertices=3)
        g.gb.layer_depth(layer).use(BASE_UNIT)
        g.gb.ids.use(BASE_UNIT + 1)
        programs.set(draw, "u_layer", layer)
        self.st.mesh.vao(draw).render()
        self.st.draws += 2

    def _readers_known(self) -> None:
        """Once layer 0 is drawn the capture is known to hold the layers in its lists or not:
        the passes that read them there, and how many layers each of their passes draws."""
        st, reads = self.st, self.st.groups[0].capture.reads
        if reads == "lists" and self.from_lists:
            # (an A-buffer without room in memory peeled instead, unpacking as it goes)
            self.listed.extend(self.from_lists)
            self.first[:] = [n for n in self.first if n not in self.listed]
            self.later[:] = [n for n in self.later if n not in self.listed]
        st.layer_lists = self.layer_lists if reads == "lists" else ()
        # (a pass whose layers share one target, read by the next pass of each layer, draws one
        # at a time)
        batched = self.eager and all(n in st.pl.stacked for n in (*st.layer_lists, *st.from_surfaces))
        st.edge_step = self.ex.edge_batch if batched else 1
        st.composed = self.ex.composed(st, self.capped)

    def _run_passes(self, layer: int) -> None:
        st, ex = self.st, self.ex
        for name in self.first if layer == 0 else self.later:
            if name in st.layer_lists or name in st.from_surfaces:
                # a batch of layers at once, at the batch's first
                if layer % st.edge_step:
                    continue
                span = self._batch_span(layer)
                ex.ensure_stacks(st, layer + span)
                ex.run_pass(st, name, layer, layer + 1, span)
            else:
                ex.run_pass(st, name, layer, layer + 1)

    def _batch_span(self, layer: int) -> int:
        """The layers from ``layer`` on that hold pixels and the cap allows, up to a batch; one
        where the counts are not looked at as the layers come (a GPU's frame)."""
        st = self.st
        if st.edge_step == 1:
            return 1
        capture = st.groups[0].capture
        last = layer + st.edge_step
        if self.max_layers is not None:
            last = min(last, self.max_layers)
        span = 1
        while layer + span < last and capture.samples(layer + span, None):
            span += 1
        return span


@dataclass(frozen=True)
class Layout:
    """The captures a plan's frames make, whatever their camera and size."""

    scales: tuple[tuple[float, tuple[str, ...], bool], ...]  # (scale, attributes, primary), primary first
    # normal and ids are left as they were where a layer has no surface; cleared unless every
    # reader looks at depth first (the edges operation)
    clear_gb: bool
    extra: bool  # some attribute is the attribute pass's
    # face IDs cost a software rasteriser dearly; only the extra attributes (and readers of the
    # raw ID target) need them
    face_ids: bool


def layout(pl: Plan) -> Layout:
    """The captures of ``pl``'s frames: one G-buffer a scale of the attributes of every layer."""
    bound = pl.bound
    by_scale: dict[float, list[str]] = {}
    for name in pl.attributes:
        if bound.attributes[name].parts is None:
            by_scale.setdefault(bound.attributes[name].scale, []).append(name)
    primary_scale = bound.attributes["depth"].scale if "depth" in pl.attributes else next(iter(by_scale))
    # (read back, or read by a pass that does not look at depth first: ``Op.depth_first``)
    clear_gb = any(n in ("normal", "ids") for n in pl.readback) or any(
        t in ("normal", "ids") and not bound.passes[n].op.depth_first
        for n in pl.passes
        for t in bound.passes[n].inputs.values()
    )
    extra = any(n in EXTRA for names in by_scale.values() for n in names)
    return Layout(
        tuple(
            (scale, tuple(names), scale == primary_scale)
            for scale, names in sorted(by_scale.items(), key=lambda kv: kv[0] != primary_scale)
        ),
        clear_gb,
        extra,
        extra or clear_gb or _face_ids(pl),
    )


def _lists_readers(pl: Plan, arrays: ArrayPlan | None, lay: Layout) -> tuple[str, ...]:
    """``LayerCapture._from_lists`` of a plan whose layers no one reads back, in the compute
    form ``arrays`` or (None) a pass a layer."""
    readers = _in_place_readers(pl, lay, "lists", arrays is not None)
    passes = pl.bound.passes
    if arrays is not None:
        one = all(name in arrays.slices for name in readers)
    else:
        one = all(
            passes[n].per_layer and passes[n].kind == "single" and not passes[n].accumulate for n in readers
        )
    return readers if one else ()


def _in_place_readers(pl: Plan, lay: Layout, reads: str, compute: bool = False) -> tuple[str, ...]:
    """The passes that read the layers of a plan whose layers no one reads back, where they
    all read the renderer's own depth, normal and IDs and may read them where a capture holds
    them (``Op.in_place``), in a form (``IN_PLACE``, compute or fragment) for a capture that
    ``reads`` them so; else none."""
    bound = pl.bound
    if len(lay.scales) != 1 or lay.extra:
        return ()
    layered = set(lay.scales[0][1])
    if any(n in layered for n in pl.readback):
        return ()
    readers = [n for n in pl.passes if any(pl.resolve(t) in layered for t in bound.passes[n].inputs.values())]
    wired = {"depth": "depth", "normal": "normal", "ids": "ids"}
    for name in readers:
        p = bound.passes[name]
        if p.user is not None or p.op.in_place is None or not p.op.in_place(p.uniforms):
            return ()
        forms = IN_PLACE.get(p.op.name)
        if forms is None or reads not in (forms.compute if compute else forms.fragment):
            return ()
        if {key: pl.resolve(t) for key, t in p.inputs.items()} != wired:
            return ()
    return tuple(readers)


def _capped(rules) -> bool:
    """Whether only a cap and empty layers stop a peel under ``rules``."""
    capped = any(isinstance(rule, MaxLayers) for rule in rules)
    others = (
        isinstance(r, EmptyLayer) or (isinstance(r, MinFraction) and r.fraction == 0)
        for r in rules
        if not isinstance(r, MaxLayers)
    )
    return capped and all(others)


def _face_ids(pl) -> bool:
    """Whether a pass reads face IDs (``Op.face_ids``: triangle-ID silhouettes)."""
    return any(
        p.op is not None and p.op.face_ids is not None and p.op.face_ids(p.uniforms)
        for p in pl.bound.passes.values()
    )
