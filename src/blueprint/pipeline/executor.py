"""Runs bound pipelines on a layer renderer's context, with targets from its pool.

Per frame: upload image inputs; capture the front surface of the chosen parts that attributes
ask for; if any other attribute is read, peel the model in the one peel loop
(``blueprint.render.capture.layer_loop``, with its stop rules), one G-buffer per attribute scale,
plus this package's attribute pass for the attributes the renderer's G-buffer lacks; run the
per-layer passes after each layer (and the once-passes at layer 0); then the passes that need
every layer (the compositor); read back the output and any dumps.

Every pass is a full-screen triangle into its target. Inputs are bound to texture units from
``units.INPUTS`` up (the peel keeps its depth textures on its own units across the loop).
Uniforms the executor sets whenever a program declares them:

``u_texel``, ``u_size``                     1 / size and size of the target, in pixels
``u_<input>_texel``, ``u_<input>_size``      the same for each input
``u_<input>_components``                     channels of the input's format
``u_<input>_factor``                         input size / target size (resampling inputs)
``u_depth_range``, ``u_pixel_angle``         camera depth range, pixel footprint (see depth.glsl)
``u_peel_eps``                               the depth tolerance in eye depth (gbuffer.depth_tolerance)
``u_normal_cos``                             crease thresholds from the crease angle (edges)
``u_view``, ``u_projection``                 camera matrices
``u_layer``, ``u_frame``                     depth layer of a per-layer pass; frame of a video
``u_shade_ink``                              the style's colour of shaded parts

A uniform is written only when its value changed since the program last got it. A run's
keywords are a ``RunRequest``; what one run holds (its plan, camera, stacks of layers, targets
of chosen parts, passes counted) is a ``RunState``, made anew for each run, and what its frame
drew and read a ``Drawn``.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Iterable, Iterator
from dataclasses import replace

import numpy as np

from blueprint.compose.compositor import TILES_VERT, Compositor, Shading
from blueprint.compose.lookup import get_style
from blueprint.compose.style import STYLES, Style
from blueprint.errors import InputError
from blueprint.gpu import units
from blueprint.gpu.device import Device
from blueprint.gpu.tables import TABLE_WIDTH, table_rows
from blueprint.pipeline.arrays import SLICES, ArrayPlan, array_plan
from blueprint.pipeline.contours import LineWidths, draw_contours
from blueprint.pipeline.graph import Plan, plan
from blueprint.pipeline.inputs import (
    ImageInputs,
    output_size,
    read_texture,
    read_texture_later,
    texture_bytes,
)
from blueprint.pipeline.layers import IN_PLACE, LayerCapture
from blueprint.pipeline.programs import FULLSCREEN, Programs
from blueprint.pipeline.schema import Bound
from blueprint.pipeline.spec import PipelineSpec
from blueprint.pipeline.state import FROM_FILE, Drawn, Result, RunRequest, RunState, Sizes
from blueprint.pipeline.tiles import Tiles
from blueprint.render.abuffer import Overflow
from blueprint.render.gbuffer import depth_range, depth_tolerance
from blueprint.render.renderer import Capturer, check_frame_args
from blueprint.render.stop import standard_rules
from blueprint.scene.camera import Camera, fit_camera
from blueprint.scene.model import Model

BASE_UNIT = units.INPUTS
# the most layers an edges pass read from a capture's lists or surfaces draws at once
# (Executor.edge_batch), the most render targets GL asks every driver for
EDGE_BATCH = 8
# the uniforms every pass may take (see the module's docstring), in the groups that are computed
# together: of the target and the run, of the camera, the camera's matrices
_FRAME_UNIFORMS = ("u_texel", "u_size", "u_layer", "u_frame", "u_shade_ink")
_CAMERA_SCALARS = ("u_depth_range", "u_peel_eps", "u_pixel_angle", "u_normal_cos")
_CAMERA_MATRICES = ("u_view", "u_projection")


class Executor:
    """Runs pipelines on ``device`` (its context, pool and programs), capturing the layers of
    models with ``capturer`` (``render.renderer.Capturer``: uploads, capture table). A
    ``blueprint.Renderer`` composes one (``Renderer.executor``) with its device and capturer."""

    def __init__(self, device: Device, capturer: Capturer) -> None:
        self.r, self.capturer = device, capturer
        self.ctx = device.ctx
        self.programs = Programs(device)
        self.images = ImageInputs(device.pool)
        self.compositor = Compositor(device)
        self.capture = LayerCapture(self)
        self._plans: dict[tuple, Plan] = {}
        # each plan's compute form (``array_plan``), by the plan's id
        self._array_plans: dict[int, tuple[Plan, ArrayPlan | None]] = {}
        self._frame = 0
        self._buffers: dict[int, object] = {}
        # which groups of the frame uniforms (``_frame_uniforms``) each program declares
        self._declared: dict[object, tuple[bool, bool, bool, bool]] = {}
        self._rules: tuple = (None, ())  # (settings, rules): _standard_rules
        # (pipeline, variables, dumps, plan) of the last ``plan`` asked for
        self._last_plan: tuple | None = None
        # the sizes of each plan's scales at the last output size it ran at, all checked
        self._sizes: dict[int, tuple[Plan, Sizes]] = {}
        self._checked: tuple | None = None  # the last peel settings check_frame_args passed
        self.last_run: RunState | None = None
        self.tiles = Tiles(device.ctx)
        # passes drawn over the tiles their layer covers, found by reading each layer's depth
        # back: only where that costs less than the pixels it saves (pipeline.tiles)
        self.tiled = device.software
        # layers an edges pass read from an A-buffer's lists or a k-buffer's surfaces draws at
        # once, a target each: the layer counts (and cursors) are read once a batch, not once a
        # layer
        self.edge_batch = min(EDGE_BATCH, device.max_draw_buffers)
        # an edges pass whose one batch holds every layer of the frame, read from a k-buffer's
        # surfaces, composes them where it finds them when the composite would only read its
        # maps (``composed``): a software rasteriser pays for every map written and read again
        self.compose_in_place = True

    def release(self) -> None:
        """Programs of user shaders and pixel buffers (pool targets belong to the renderer)."""
        self.programs.release()
        self.images.clear()
        self.tiles.release()
        for buffer in self._buffers.values():
            buffer.release()
        self._buffers.clear()

    # -- plans ---------------------------------------------------------------------------------
    def plan(self, pipeline: PipelineSpec | Bound, variables=None, dumps=()) -> Plan:
        # a stream asks for the last plan again: its variables compared, not bound and keyed
        last = self._last_plan
        if last is not None and last[0] is pipeline and last[1] == variables and last[2] == dumps:
            return last[3]
        bound = pipeline.bind(variables) if isinstance(pipeline, PipelineSpec) else pipeline
        key = (id(bound), tuple(dumps))
        held = self._plans.get(key)
        if held is None or held.bound is not bound:
            held = self._plans[key] = plan(bound, tuple(dumps))
        self._last_plan = (pipeline, None if variables is None else dict(variables), tuple(dumps), held)
        return held

    def _arrays(self, pl: Plan) -> ArrayPlan | None:
        held = self._array_plans.get(id(pl))
        if held is None or held[0] is not pl:
            held = self._array_plans[id(pl)] = pl, array_plan(pl)
        return held[1]

    # -- running -------------------------------------------------------------------------------
    def run(
        self,
        pipeline: PipelineSpec | Bound,
        model: Model | None = None,
        camera: Camera | None = None,
        **request,
    ) -> Result:
        """Run a pipeline once.

        Parameters
        ----------
        pipeline : PipelineSpec or Bound
            From ``load_pipeline``; ``variables`` override its declared variables.
        model, camera
            The model whose attributes are rendered (needed when any attribute is read);
            ``camera`` defaults to ``fit_camera`` from ``view``.
        **request
            The fields of ``RunRequest``: ``size``, ``view``, ``variables``, ``images``,
            ``style``, ``max_layers``, ``min_fraction``, ``crease_angle``, ``parts``,
            ``dumps``, ``profile``, ``frame``, ``read_later``, ``keep``, ``slot``.
        """
        req = RunRequest(**request)
        watch = _Stopwatch(self.ctx, req.profile)
        self.r.make_current()
        st = self.last_run = self._start(pipeline, model, camera, req)
        bound, images = st.pl.bound, req.images or {}
        if st.pl.needs_model:
            # sized before anything is allocated: the mesh in chunks, or the run refused
            pixels = sum(w * h for w, h in map(st.size_of, {bound.scale_of(n) for n in st.pl.attributes}))
            self.capturer.check_memory(model, pixels, st.max_layers, st.crease)
        for name in st.pl.images:
            self.images.upload(bound, name, images.get(name), st.size_of(bound.images[name].scale))
        watch.stage("upload")
        self.ctx.enable_only(self.ctx.NOTHING)
        self.tiles.forget()  # what an earlier run found, even one an error ended
        if st.pl.needs_model:
            st.mesh = self.capturer.mesh(model, st.crease)
            self.capture.capture_parts(st, req.parts or {})
        try:
            drawn = self._draw(st, req, watch, blind=True)
        except Overflow:
            # a frame issued whole found its A-buffer short of room once read: again, looking
            st.groups.clear()
            drawn = self._draw(st, req, watch, blind=False)
        watch.stage("read")
        out = st.pl.output
        return Result(
            output=drawn.outputs.get(out),
            format=bound.format_of(out),
            premultiplied=out in bound.passes and bound.passes[out].kind == "composite",
            layers=drawn.layers,
            layer_pixels=drawn.layer_pixels,
            camera=st.camera,
            ms=watch.ms(),
            draws=st.draws,
            stages=watch.stages,
            dumps={d: drawn.outputs[st.pl.resolve(d)] for d in req.dumps},
            revealed=drawn.revealed,
            layers_left=drawn.layers_left,
            pending=drawn.pending,
            counting=drawn.counting,
            texture=drawn.texture,
        )

    def _start(
        self, pipeline: PipelineSpec | Bound, model: Model | None, camera: Camera | None, req
    ) -> RunState:
        """A run's state: its plan, the sizes of its scales, its peel settings and camera, with
        what the plan reads (images, parts, the model) checked given."""
        pl = self.plan(pipeline, req.variables, req.dumps)
        bound = pl.bound
        images = req.images or {}
        for name in images:
            if name not in bound.images:
                raise InputError(
                    f"{bound.source}: no image called {name!r} (choose {', '.join(bound.images) or 'none'})"
                )
        size = output_size(bound, pl.images, req.size, images, self.r.max_texture)
        sizes = self._sizes_of(pl, size)
        max_layers, min_fraction, crease = self._peel_settings(pl, req)
        parts = req.parts or {}
        for name in pl.parts:
            wanted = bound.attributes[name].parts
            if parts.get(wanted) is None:
                raise InputError(
                    f"{bound.source}: attributes.{name}: give the parts {wanted!r} "
                    f"(--parts {wanted}=GLOBS; parts= in Python)"
                )
        if pl.needs_model:
            if model is None:
                raise InputError(
                    f"{bound.source}: this pipeline renders attributes ({', '.join(pl.attributes)}): "
                    "give a model"
                )
            camera = camera or fit_camera(model, size, req.view)
        self._frame = self._frame + 1 if req.frame is None else req.frame
        chosen = None if req.style is None else get_style(req.style)
        st = RunState(
            pl=pl,
            camera=camera,
            crease=crease,
            style=chosen,
            shade_ink=tuple((chosen or _named_style(bound)).shade),
            size_of=sizes,
            frame=self._frame,
            slot=req.slot,
            arrays=self._arrays(pl) if self.r.use_compute else None,
            max_layers=max_layers,
            min_fraction=min_fraction,
        )
        st.attr_dumps = {
            n: [] for n in pl.readback if n in bound.attributes and bound.attributes[n].parts is None
        }
        if req.contours is not None:
            st.contours = req.contours
            contoured = req.contours.contoured
            # where every face is contoured the edges read no table (EVERY_FACE_CONTOURED)
            st.contoured = None if every_face(contoured) else self._contoured_table(contoured)
        return st

    def _contoured_table(self, contoured: np.ndarray):
        """``contoured`` (F,) bool as a table (gpu/tables.py) by face + 1, as the IDs hold a
        face (row 0, no face, is never read), in a pool texture kept for the next frame."""
        rows = table_rows(len(contoured) + 1)
        data = np.zeros(rows, np.int32)
        data[1 : len(contoured) + 1] = contoured
        texture = self.r.pool.texture("pipeline.contoured", (TABLE_WIDTH, rows // TABLE_WIDTH), "r32i")
        texture.write(data.tobytes())
        return texture

    def _sizes_of(self, pl: Plan, size: tuple[int, int]) -> Sizes:
        """The sizes of ``pl``'s scales at output size ``size``, every one checked: kept, so that
        later runs of the plan at this size need not check them again."""
        held = self._sizes.get(id(pl))
        if held is not None and held[0] is pl and held[1].size == size:
            return held[1]
        sizes = Sizes(size, self.r.max_texture)
        bound = pl.bound
        for scale in {bound.scale_of(n) for n in (*pl.attributes, *pl.images)} | {
            bound.passes[n].scale for n in pl.passes
        }:
            sizes(scale)
        self._sizes[id(pl)] = (pl, sizes)
        return sizes

    def _peel_settings(self, pl: Plan, req: RunRequest) -> tuple[int | None, float, float]:
        """(max_layers, min_fraction, crease_angle) of a run: the request's, else the file's;
        one layer where no pass runs per layer."""
        bound = pl.bound
        max_layers = req.max_layers
        if max_layers is FROM_FILE:
            max_layers = bound.layers if bound.layers is not None else 8
            max_layers = max_layers or None
        if not pl.layered:
            max_layers = 1
        min_fraction = bound.min_fraction if req.min_fraction is None else req.min_fraction
        crease = bound.crease_angle if req.crease_angle is None else req.crease_angle
        if (max_layers, min_fraction, crease) != self._checked:
            check_frame_args(max_layers, min_fraction, crease, 1.0)
            self._checked = (max_layers, min_fraction, crease)
        return max_layers, min_fraction, crease

    def _draw(self, st: RunState, req: RunRequest, watch: _Stopwatch, blind: bool) -> Drawn:
        """The frame from its layers to its read-back; ``blind`` as ``LayerCapture.draw_layers``."""
        ctx, pl = self.ctx, st.pl
        drawn = Drawn()
        if pl.peel:
            self._draw_layers(st, drawn, blind)
        else:
            self.ensure_stacks(st, 1)
            for name in pl.iteration0:
                self.run_pass(st, name, 0, 1)
            drawn.layers = 1
        if st.arrays is not None:
            self._run_batches(st, drawn.layers)
        if st.contours is not None:
            self._draw_contours(st, drawn.layers)
        watch.stage("peel_edges")
        for name in pl.after:
            if st.composed is None or name != st.composed[1]:  # (drawn with the edges)
                self.run_pass(st, name, 0, drawn.layers)
        self.tiles.forget()
        watch.stage("compose")
        ctx.disable(ctx.BLEND)
        if self.r.use_compute:
            ctx.memory_barrier(ctx.TEXTURE_UPDATE_BARRIER_BIT | ctx.FRAMEBUFFER_BARRIER_BIT)
        self._read_back(st, req, drawn)
        if pl.peel:
            self._count(st, req, drawn)
        return drawn

    def _draw_layers(self, st: RunState, drawn: Drawn, blind: bool) -> None:
        """The frame's layers under its stop rules, the per-layer passes run after each."""
        pl = st.pl
        reveal = self.capture.reveal_rule(st)
        # depth masking peels as deep as it needs: the cap would stop it short silently
        if reveal is None:
            drawn.rules = self._standard_rules(st.max_layers, st.min_fraction)
        else:
            drawn.rules = (*standard_rules(None, st.min_fraction), reveal)
        # a frame that reads back its output alone, once a frame, can be issued whole before its
        # counts are known
        out = pl.bound.passes.get(pl.output)
        blind = blind and pl.readback == [pl.output] and out is not None and not out.per_layer
        drawn.layer_pixels, drawn.layers = self.capture.draw_layers(st, st.max_layers, drawn.rules, blind)
        drawn.revealed = None if reveal is None else reveal.shown

    def _read_back(self, st: RunState, req: RunRequest, drawn: Drawn) -> None:
        """The outputs and dumps read back; a one-texture output left on the GPU (``keep``) or
        copied to be read late (``read_later``) instead."""
        pl, out = st.pl, st.pl.output
        if out in pl.bound.passes and out not in pl.stacked:
            if req.keep:
                drawn.texture = self._value(st, out, 0)
            elif req.read_later is not None:
                tex = self._value(st, out, 0)
                drawn.pending = read_texture_later(tex, pl.bound.format_of(out), req.read_later(tex))
        late = drawn.pending is not None or drawn.texture is not None
        drawn.outputs = {
            name: self._read(st, name, drawn.layers) for name in pl.readback if not late or name != out
        }

    def _count(self, st: RunState, req: RunRequest, drawn: Drawn) -> None:
        """The layers drawn counted, where a blind peel left them uncounted, and the layers a cap
        left; a streamed frame's counted with its picture, after the next frame is issued."""
        if drawn.layer_pixels is None and drawn.pending is not None and self.capture.lists_only(st):
            drawn.counting = functools.partial(self.capture.counted_late, st, drawn.rules, drawn.layers)
            return
        if drawn.layer_pixels is None:
            drawn.layer_pixels, drawn.layers = self.capture.counted(st, drawn.rules, drawn.layers)
        # a window's frame shows no count: its pass and read-back would be a stall
        if not req.keep:
            drawn.layers_left = self.capture.left(st, drawn.rules, drawn.layer_pixels, drawn.layers)

    def stream(
        self, pipeline: PipelineSpec | Bound, model: Model | None, frames: Iterable[dict], **options
    ) -> Iterator[Result]:
        """Run a pipeline once for each entry of ``frames`` (the arguments of ``run`` that change
        from frame to frame: ``camera``, ``frame``, ``images``...; ``options`` hold the rest),
        yielding the results in order. Each frame's output is copied into a pixel buffer and
        read back only once the next frame is issued, so the transfer overlaps the GPU's work.
        ``Result.ms`` is a frame's share of the stream: from its start to the next frame's
        (the last one's: to its read-back), so the times add up to the stream's."""
        pending: tuple[Result, float, dict, int] | None = None
        # bound once: ``options`` hold for every frame (a frame giving variables binds its own)
        bound = pipeline.bind(options.get("variables")) if isinstance(pipeline, PipelineSpec) else pipeline

        def collected(result: Result, arguments: dict, k: int, ms: float) -> Result:
            try:
                return result.collected(ms=ms)
            except Overflow:
                # its A-buffer proved short of room once read: drawn again, now with room, in
                # its own slot (the next frame's is still to be read)
                return replace(self.run(pipeline, model, **{**options, **arguments}, slot=k % 2), ms=ms)

        for k, arguments in enumerate(frames):
            start = time.perf_counter()
            result = self.run(
                pipeline if "variables" in arguments else bound,
                model,
                **{**options, **arguments},
                read_later=lambda t, k=k: self._pixel_buffer(k % 2, t),
                slot=k % 2,
            )
            if pending is not None:
                before, began, its_arguments, j = pending
                yield collected(before, its_arguments, j, (start - began) * 1e3)
            pending = result, start, arguments, k
        if pending is not None:
            before, began, its_arguments, j = pending
            yield collected(before, its_arguments, j, (time.perf_counter() - began) * 1e3)

    def _standard_rules(self, max_layers: int | None, min_fraction: float) -> tuple:
        """``standard_rules``, the same tuple while the settings stay (none of them holds
        state): the capture then knows them again without looking (``LayerCapture.draw_layers``)."""
        if self._rules[0] != (max_layers, min_fraction):
            self._rules = (max_layers, min_fraction), tuple(standard_rules(max_layers, min_fraction))
        return self._rules[1]

    def _pixel_buffer(self, slot: int, tex):
        """Pixel buffer ``slot`` of two (frames alternate), large enough for ``tex``."""
        need = texture_bytes(tex)
        held = self._buffers.get(slot)
        if held is None or held.size < need:
            if held is not None:
                held.release()
            held = self._buffers[slot] = self.ctx.buffer(reserve=need)
        return held

    # -- targets -------------------------------------------------------------------------------
    def ensure_stacks(self, st: RunState, layers: int) -> None:
        if layers <= st.stacked_layers:
            return  # asked again after every layer
        st.stacked_layers = layers
        pl = st.pl
        arrays = st.arrays.arrays if st.arrays else frozenset()
        count = -(-layers // SLICES)
        if arrays and count > st.stacked_arrays:
            st.stacked_arrays = count
            for name in arrays:
                size = st.size_of(pl.bound.passes[name].scale)
                st.stacks[name] = self._stack(f"pipeline.array.{name}", size, "r8", count, SLICES)
        for name in pl.stacked - arrays:
            p = pl.bound.passes[name]
            st.stacks[name] = self._stack(f"pipeline.stack.{name}", st.size_of(p.scale), p.format, layers, 0)

    def _stack(self, name: str, size, fmt: str, count: int, slices: int) -> list:
        """``count`` textures (arrays of ``slices`` where > 0) named ``name.K``, kept by the pool
        as one list (never changed: a run wanting more takes a longer one)."""
        pool = self.r.pool
        return pool.held(
            ("pipeline.stack", name, size, fmt, count, slices),
            lambda: [pool.texture(f"{name}.{k}", size, fmt, slices) for k in range(count)],
        )

    def _value(self, st: RunState, name: str, layer: int):
        """The texture holding ``name`` for a pass at ``layer``."""
        bound = st.pl.bound
        if name in st.parts:
            return st.parts[name]
        if name in bound.attributes:
            return st.by_attr[name].texture(name, layer)
        if name in bound.images:
            return self.images.texture(name)
        return self.target(st, name, layer)

    def target(self, st: RunState, name: str, layer: int):
        pl = st.pl
        if name in pl.stacked:
            p = pl.bound.passes[name]
            return st.stacks[name][layer if p.per_layer else 0]
        slot = pl.slots[name]
        return self.r.pool.texture(slot.name, st.size_of(slot.scale), slot.format)

    # -- passes --------------------------------------------------------------------------------
    def _frame_uniforms(self, st: RunState, prog, size, layer: int) -> None:
        declared = self._declared.get(prog)
        if declared is None:
            has = self.programs.has
            declared = self._declared[prog] = (
                any(has(prog, name) for name in _FRAME_UNIFORMS),
                any(has(prog, name) for name in _CAMERA_SCALARS),
                any(has(prog, name) for name in _CAMERA_MATRICES),
                has(prog, "u_corners"),
                has(prog, "u_contour_layers"),
            )
        frame, scalars, matrices, corners, contoured = declared
        put = self.programs.update
        if frame:
            w, h = size
            put(
                prog,
                {
                    "u_texel": (1.0 / w, 1.0 / h),
                    "u_size": (float(w), float(h)),
                    "u_layer": layer,
                    "u_frame": st.frame,
                    "u_shade_ink": st.shade_ink,
                },
            )
        if st.camera is None:
            return
        if scalars:
            # without a model there are no surfaces to tell apart
            tolerance = depth_tolerance(st.camera, st.mesh.bounds) if st.mesh is not None else 0.0
            put(prog, _camera_scalars(st.camera, st.crease, size[1], tolerance))
        if matrices:
            put(prog, _camera_matrices(st.camera))
        if corners and st.mesh is not None:
            st.mesh.bind_corners(prog, units.CORNERS)
        if contoured and st.contours is not None:
            self.programs.set(prog, "u_contour_layers", st.contours.layers)
            if st.contoured is not None:
                st.contoured.use(units.CONTOURED)
                self.programs.set(prog, "u_contoured", units.CONTOURED)

    def _bind_input(self, prog, key: str, tex, unit: int, size) -> None:
        put = self.programs.set
        tex.use(unit)
        put(prog, f"u_{key}", unit)
        w, h = tex.size[:2]
        put(prog, f"u_{key}_texel", (1.0 / w, 1.0 / h))
        put(prog, f"u_{key}_size", (float(w), float(h)))
        put(prog, f"u_{key}_components", tex.components)
        put(prog, f"u_{key}_factor", max(1, w // size[0]))

    def run_pass(self, st: RunState, name: str, layer: int, layers: int, span: int = 1) -> None:
        """Pass ``name`` at ``layer`` (``layers`` peeled so far); an edges pass read from an
        A-buffer's lists or a k-buffer's surfaces draws ``span`` layers from ``layer`` on at
        once (``edge_batch``)."""
        pl = st.pl
        p = pl.bound.passes[name]
        if st.arrays is not None:
            if name in st.arrays.batches:
                return  # the whole arrays, after the peel
            if name in st.arrays.slices:
                self._run_slice(st, name, p, layer)
                return
        if p.kind == "composite":
            self._composite(st, p, self.target(st, name, layer), layers)
            return
        composed = st.composed is not None and st.composed[0] == name
        target = self.target(st, st.composed[1] if composed else name, layer)
        size = tuple(target.size)
        inputs = {key: pl.resolve(t) for key, t in p.inputs.items()}
        reach = self.reach(st, name) if size == self.tiles.size else None
        vertex = FULLSCREEN if reach is None else TILES_VERT
        # an op's in-place form reads its batch of layers where the capture holds them (an
        # A-buffer's lists, a k-buffer's surfaces) instead of from the G-buffer's textures
        in_place = name in st.layer_lists or name in st.from_surfaces
        if p.user is not None:
            prog = self.programs.user(p.user)
        elif in_place:
            capture = st.groups[0].capture
            shader = IN_PLACE[p.op.name].fragment[capture.reads]
            defines = {**_defines(p, st), **capture.defines, "BATCH": self.edge_batch, "COMPOSE": composed}
            prog = self.programs.library(shader, vertex, defines, modern=True)
        else:
            prog = self.programs.library(p.op.shader, vertex, _defines(p, st))
        self._frame_uniforms(st, prog, size, layer)
        self.programs.update(prog, p.uniforms)
        if in_place:
            self._bind_in_place(st, name, prog, layer)
            self.programs.set(prog, "u_batch", span)
        else:
            for unit, (key, source) in enumerate(inputs.items(), BASE_UNIT):
                self._bind_input(prog, key, self._value(st, source, layer), unit, size)
        if composed:

            def draw() -> int:
                if reach is not None:
                    return self.tiles.draw(prog, reach)
                self.programs.vao(prog).render(vertices=3)
                return 1

            style = self._style(st, pl.bound.passes[st.composed[1]])
            st.draws += self.compositor.composed_in_place(target, prog, style, span, self.edge_batch, draw)
            return
        if span > 1:
            targets = tuple(self.target(st, name, k) for k in range(layer, layer + span))
        else:
            targets = (target,)
        fbo = self.r.pool.framebuffer(targets)
        if reach is not None:
            fbo.use()
            fbo.clear()
            st.draws += self.tiles.draw(prog, reach)
            return
        vao = self.programs.vao(prog)
        if p.kind == "separable":
            scratch_slot = pl.scratch[name]
            scratch = self.r.pool.texture(
                scratch_slot.name, st.size_of(scratch_slot.scale), scratch_slot.format
            )
            self.programs.set(prog, "u_direction", (1, 0))
            self.r.pool.framebuffer((scratch,)).use()
            vao.render(vertices=3)
            self._bind_input(prog, next(iter(inputs)), scratch, BASE_UNIT, size)
            self.programs.set(prog, "u_direction", (0, 1))
            st.draws += 1
        fbo.use()
        vao.render(vertices=3)
        st.draws += 1

    def reach(self, st: RunState, name: str) -> int | None:
        """How far from the covered pixels of the layer being drawn pass ``name``'s result can
        be non-zero, through the passes it reads (``Op.support``); None: anywhere, or unknown.
        Only passes of one layer at a time qualify (a pass that accumulates layers does not)."""
        if name not in st.reach:
            pl = st.pl
            p = pl.bound.passes[name]
            reach = None
            if p.per_layer and p.user is None and p.kind == "single" and not p.accumulate and p.op.reach:
                source = pl.resolve(p.inputs[p.op.support]) if p.op.support in p.inputs else None
                attribute = pl.bound.attributes.get(source)
                if attribute is not None:
                    depth = attribute.parts is None and (attribute.of or source) == "depth"
                    base = 0 if depth and st.by_attr[source].primary else None
                else:
                    base = self.reach(st, source) if source in pl.bound.passes else None
                if base is not None:
                    reach = base + p.op.reach(p.uniforms)
            st.reach[name] = reach
        return st.reach[name]

    def _run_slice(self, st: RunState, name: str, p, layer: int) -> None:
        prog = self.programs.compute(p.op.compute, _defines(p, st))
        array = st.stacks[name][layer // SLICES]
        size = tuple(array.size[:2])
        self._frame_uniforms(st, prog, size, layer)
        self.programs.update(prog, p.uniforms)
        for unit, (key, source) in enumerate(p.inputs.items(), BASE_UNIT):
            self._bind_input(prog, key, self._value(st, st.pl.resolve(source), layer), unit, size)
        self.programs.set(prog, "u_layer", layer % SLICES)
        self.programs.set(prog, "u_first_layer", layer - layer % SLICES)
        array.bind_to_image(1, read=False, write=True)
        prog.run((size[0] + 7) // 8, (size[1] + 7) // 8)
        st.draws += 1

    def run_in_place(self, st: RunState, name: str, capture, layers: int) -> None:
        """Slice pass ``name`` on all ``layers`` layers in its compute in-place form, read
        where ``capture`` holds them (an A-buffer's sorted lists): a dispatch an array of
        ``SLICES`` layers, each pixel's chain carried from one to the next."""
        p = st.pl.bound.passes[name]
        shader = IN_PLACE[p.op.name].compute[capture.reads]
        prog = self.programs.compute(shader, {**_defines(p, st), **capture.defines})
        size = st.groups[0].size
        self._frame_uniforms(st, prog, size, 0)
        self.programs.update(prog, p.uniforms)
        for k in range(-(-layers // SLICES)):
            capture.bind(prog, k * SLICES, SLICES)
            st.stacks[name][k].bind_to_image(1, read=False, write=True)
            self.programs.update(
                prog, {"u_first_layer": k * SLICES, "u_layers": min(SLICES, layers - k * SLICES)}
            )
            prog.run((size[0] + 7) // 8, (size[1] + 7) // 8)
            st.draws += 1
        # between batches the capture's bind orders the cursors; this orders the stacks
        self.ctx.memory_barrier(self.ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)

    def _bind_in_place(self, st: RunState, name: str, prog, layer: int) -> None:
        """The capture's layers bound for pass ``name``'s in-place form ``prog`` to read the
        batch of layers from ``layer`` on (``LayerSource.bind``), none unpacked."""
        st.groups[0].capture.bind(prog, layer, st.edge_step)

    def _run_batches(self, st: RunState, layers: int) -> None:
        ctx, pl = self.ctx, st.pl
        ctx.memory_barrier(ctx.TEXTURE_FETCH_BARRIER_BIT | ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)
        used = (max(layers, 1) + SLICES - 1) // SLICES
        for name in st.arrays.batches:
            p = pl.bound.passes[name]
            prog = self.programs.compute(p.op.compute)
            self.programs.update(prog, p.uniforms)
            ((key, source),) = p.inputs.items()
            source = pl.resolve(source)
            w, h = st.size_of(p.scale)
            for k in range(used):
                st.stacks[source][k].use(BASE_UNIT)
                self.programs.update(
                    prog,
                    {
                        f"u_{key}": BASE_UNIT,
                        "u_layer": k * SLICES,  # the depth layer of slice 0
                        "u_slices": min(SLICES, layers - k * SLICES),
                    },
                )
                st.stacks[name][k].bind_to_image(1, read=False, write=True)
                prog.run((w + 7) // 8, (h + 7) // 8)
                st.draws += 1
            ctx.memory_barrier(ctx.TEXTURE_FETCH_BARRIER_BIT | ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)

    def _draw_contours(self, st: RunState, layers: int) -> None:
        """The run's contour lines into the maps each composite reads, each piece into its
        level's map, as wide and in the share of ink the edges and lines passes give lines."""
        pl = st.pl
        passes = pl.bound.passes
        for name in pl.after:
            p = passes[name]
            if p.kind != "composite":
                continue
            source = pl.resolve(p.inputs[p.stacks[0]])
            if source not in st.stacks:
                continue
            widths = _line_widths(pl, source)
            slices = SLICES if st.arrays is not None and source in st.arrays.arrays else 0
            st.draws += draw_contours(self.r, st.contours, st.stacks[source], layers, widths, slices)

    def composed(self, st: RunState, capped: bool) -> tuple[str, str] | None:
        """(edges pass, composite pass) where the one pass reading the layers from a k-buffer's
        surfaces draws every layer of the frame in one batch (a cap of at most a batch, and
        ``capped``: no rule but the cap and empty layers stops the peel, so the batch's layers
        are those drawn) and the one pass reading it is a composite of its maps alone at their
        size, shading and highlight aside: then it composes them where it finds them, into the
        composite's target, which is not drawn again; else None."""
        pl = st.pl
        if not (self.compose_in_place and capped and st.edge_step > 1 and len(st.from_surfaces) == 1):
            return None
        if st.contours is not None:
            return None  # the contour lines go into the maps before they are composed
        if st.max_layers is None or st.max_layers > st.edge_step:
            return None
        (name,) = st.from_surfaces
        if name in pl.readback:
            return None
        passes = pl.bound.passes
        readers = [n for n in pl.passes if any(pl.resolve(t) == name for t in passes[n].inputs.values())]
        if len(readers) != 1:
            return None
        p = passes[readers[0]]
        if p.kind != "composite" or {k: pl.resolve(t) for k, t in p.inputs.items()} != {"layers": name}:
            return None
        if st.size_of(p.scale) != st.size_of(passes[name].scale):
            return None
        return name, readers[0]

    @staticmethod
    def _style(st: RunState, p) -> Style:
        """The style composite pass ``p`` draws in: the run's, else its own parameter's."""
        return st.style or STYLES[p.op.params[0].choices[p.uniforms["u_style"]]]

    def _composite(self, st: RunState, p, target, layers: int) -> None:
        """The compositor over the pass's stack of layers, with the shading and highlight
        maps wired to it; in compute form where the layers live in 8-slice arrays."""
        pl = st.pl
        style = self._style(st, p)
        wired = {key: pl.resolve(t) for key, t in p.inputs.items()}
        highlight = self._value(st, wired["highlight"], 0) if "highlight" in wired else None
        shading = None
        if "shade_color" in wired or "shade_index" in wired:
            if not ("shade_color" in wired and "shade_index" in wired):
                raise InputError(
                    f"{pl.bound.source}: passes.{p.name}.inputs: give shade_color and shade_index together"
                )
            shading = Shading(
                self._value(st, wired["shade_index"], 0), self._value(st, wired["shade_color"], 0)
            )
        source = wired[p.stacks[0]]
        if st.arrays is not None and source in st.arrays.arrays:
            compose = self.compositor.compute
        else:
            compose = self.compositor.fragment
            # tiles where a layer lies, widened by a tile past the reach: the contour lines lie
            # on the faces drawn, their widths within that
            tiled = self.tiles.layers and shading is None
            reach = self.reach(st, source) if tiled else None
            if reach is not None and tuple(st.stacks[source][0].size) == self.tiles.size:
                compose = functools.partial(
                    compose, tiles=functools.partial(self.tiles.draw_layers, reach=reach)
                )
        st.draws += compose(target, st.stacks[source], layers, style, highlight=highlight, shading=shading)

    # -- read back -----------------------------------------------------------------------------
    def _read(self, st: RunState, name: str, layers: int) -> np.ndarray:
        pl, bound = st.pl, st.pl.bound
        if name in st.parts:
            return read_texture(st.parts[name], bound.attributes[name].format)
        if name in bound.attributes:
            held = st.attr_dumps[name]
            return np.stack(held[: max(layers, 1)]) if pl.layered else held[0]
        fmt = bound.format_of(name)
        if name in pl.stacked and bound.passes[name].per_layer:
            count = max(1, min(layers, len(st.stacks[name])))
            return np.stack([read_texture(t, fmt) for t in st.stacks[name][:count]])
        tex = self._value(st, name, 0)
        # through a pixel buffer, faster than a plain texture read: the copy into the buffer
        # runs on the GPU's copy engine
        buffer = self.r.pool.buffer("pipeline.readback", texture_bytes(tex))
        return read_texture_later(tex, fmt, buffer).collect()

    # -- single operations (tests, tools) --------------------------------------------------------
    def run_op(
        self,
        op_name: str,
        inputs: dict,
        params: dict | None = None,
        *,
        formats: dict[str, str] | None = None,
        output: str | None = None,
        scale: float = 1.0,
        style: str | Style | None = None,
        camera: Camera | None = None,
        crease_angle: float = 30.0,
    ) -> np.ndarray:
        """Run one operation of the library on arrays, through the same pass code as pipelines.

        Each input is (H, W, C) in texture row order (row 0 is texture row 0), uploaded in
        ``formats[name]`` (default: r8/rgba8 for uint8, r32i/rg32i for other integers,
        r32f/rg32f/rgba32f for floats; "depth" makes a depth texture); a stack input takes a
        list of such arrays, one per layer. ``scale`` is the output size relative to the
        first input. Returns the output (H', W', C) in the same row order.
        """
        from blueprint.pipeline.inputs import upload_array
        from blueprint.pipeline.single import single_op

        bound, arrays = single_op(op_name, inputs, params, formats, output, scale)
        pl = plan(bound)
        fh, fw = arrays[next(iter(arrays))][0].shape[:2]
        chosen = None if style is None else get_style(style)
        st = self.last_run = RunState(
            pl=pl,
            camera=camera,
            crease=crease_angle,
            style=chosen,
            shade_ink=tuple((chosen or STYLES["blueprint"]).shade),
            size_of=lambda s: (max(1, round(fw * s)), max(1, round(fh * s))),
            frame=0,
            arrays=None,
        )
        self.r.make_current()
        self.ctx.enable_only(self.ctx.NOTHING)
        op = bound.passes["out"].op
        for key, layers in arrays.items():
            fmt_in = bound.images[f"in_{key}"].format
            textures = [
                upload_array(self.r.pool, f"pipeline.test.{key}.{k}", a, fmt_in) for k, a in enumerate(layers)
            ]
            if key in op.stacks:
                st.stacks[f"in_{key}"] = textures
            else:
                self.images.put(f"in_{key}", textures[0])
        count = len(arrays[op.stacks[0]]) if op.stacks else 1
        self.run_pass(st, "out", 0, count)
        return read_texture(self.target(st, "out", 0), bound.passes["out"].format)[::-1]


class _Stopwatch:
    """A run's milliseconds, and with ``profile`` its milliseconds per stage, each stage's GPU
    work waited for."""

    def __init__(self, ctx, profile: bool) -> None:
        self.ctx, self.profile = ctx, profile
        self.start = self.clock = time.perf_counter()
        self.stages: dict[str, float] = {}

    def stage(self, name: str) -> None:
        if self.profile:
            self.ctx.finish()
            now = time.perf_counter()
            self.stages[name] = (now - self.clock) * 1e3
            self.clock = now

    def ms(self) -> float:
        return (time.perf_counter() - self.start) * 1e3


@functools.lru_cache(maxsize=16)
def _camera_scalars(camera: Camera, crease: float, height: int, tolerance: float) -> dict:
    """The uniforms a pass takes from ``camera`` but its matrices, for targets ``height``
    pixels high, with the model's depth ``tolerance`` (kept by the camera's value: a frame runs
    dozens of passes, a stream may draw from one camera again and again)."""
    half = math.radians(crease)
    return {
        "u_depth_range": depth_range(camera),
        "u_peel_eps": tolerance,
        "u_pixel_angle": camera.pixel_angle(height),
        # The mesh splits normals across edges past the crease angle, but a pixel beside one
        # blends its corners' split normals with the smooth ones of the triangles' other
        # corners, so on small triangles the sides differ by well under the angle: ink from
        # 40 % of it, full from 70 % (from 50 and 80 %, crease chains broke into dots).
        "u_normal_cos": (math.cos(0.4 * half), math.cos(0.7 * half)),
    }


@functools.lru_cache(maxsize=16)
def _camera_matrices(camera: Camera) -> dict:
    """``u_view`` and ``u_projection`` of ``camera`` (passes that draw no geometry seldom read
    them)."""
    return {
        "u_view": camera.view_matrix().T.astype("f4").tobytes(),
        "u_projection": camera.projection_matrix().T.astype("f4").tobytes(),
    }


def every_face(contoured: np.ndarray) -> bool:
    """Whether the contour lines draw the outline of every face (``contoured`` (F,) bool): a
    scan's, whose faces are all smooth."""
    return bool(contoured.all())


def _defines(p, st: RunState) -> dict:
    """The defines of pass ``p``'s program in run ``st``: its switches', and where it leaves
    the contoured faces' outline to the contour lines and every face of the run is one, that,
    whether the lines' levels count every layer the run may draw, and whether its mesh is one
    part."""
    if not p.op.switches:
        return {}
    defines = p.op.defines(p.uniforms)
    if defines.get("SMOOTH_CONTOURS") and st.contours is not None and st.contoured is None:
        every_layer = st.max_layers is not None and st.contours.layers >= st.max_layers
        one_part = st.mesh.part_count == 1
        found = {"EVERY_FACE_CONTOURED": True, "CONTOURS_EVERY_LAYER": every_layer, "ONE_PART": one_part}
        defines = {**defines, **found}
    return defines


def _line_widths(pl: Plan, source: str) -> LineWidths:
    """The widths of the lines in the maps of pass ``source``: an edges pass's own (the two
    pixels beside a discontinuity), hidden ones in its share of the ink; widened by a
    dilation's radius where ``source`` is one, hidden ones to its share of the width (the
    blueprint preset never makes that narrower than the edges' own)."""
    passes = pl.bound.passes
    p = passes[source]
    radius, hidden_width = 0.0, 1.0
    if p.op.widens is not None:
        radius, hidden_width = p.op.widens(p.uniforms)
        p = passes[pl.resolve(next(iter(p.inputs.values())))]
    hidden_ink = 1.0 if p.op.hidden_ink is None else p.op.hidden_ink(p.uniforms)
    return LineWidths(1.0 + radius, (1.0 + radius) * hidden_width, hidden_ink)


def part_color(part: np.ndarray) -> np.ndarray:
    """(..., 3) float: the base colour the attribute pass gives part indices (see attributes.frag)."""
    h = np.modf(np.asarray(part, np.float64) * 0.61803398875)[0][..., None]
    p = np.abs(np.modf(h + np.array([1.0, 2.0 / 3.0, 1.0 / 3.0]))[0] * 6.0 - 3.0)
    return 0.9 * (1.0 + (np.clip(p - 1.0, 0.0, 1.0) - 1.0) * 0.45)


def _named_style(bound: Bound) -> Style:
    """The style a pipeline names in its ``style`` variable, else the blueprint's."""
    name = bound.variables.get("style")
    return STYLES[name] if name in STYLES else STYLES["blueprint"]
