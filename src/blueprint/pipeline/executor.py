"""Runs bound pipelines on a Renderer's context, with targets from its pool.

Per frame: upload image inputs; capture the front surface of the chosen parts that attributes
ask for; if any other attribute is read, peel the model in the one peel loop
(``blueprint.render.capture.peel``, with its stop rules), one G-buffer per attribute scale,
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
``u_peel_eps``                               the peel's tolerance in eye depth
``u_normal_cos``                             crease thresholds from the crease angle (edges)
``u_view``, ``u_projection``                 camera matrices
``u_layer``, ``u_frame``                     depth layer of a per-layer pass; frame of a video
``u_shade_ink``                              the style's colour of shaded parts

A uniform is written only when its value changed since the program last got it.
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass, field

import numpy as np

from blueprint.compose.compositor import Compositor, Shading
from blueprint.compose.style import STYLES, Style, get_style
from blueprint.errors import InputError, ShaderError
from blueprint.gpu import units
from blueprint.gpu.shaders import VERSION, _explain, preprocess
from blueprint.gpu.targets import FORMATS
from blueprint.pipeline.graph import Plan, plan
from blueprint.pipeline.spec import Bound, PipelineSpec, user_source
from blueprint.render.capture import (
    KBUFFER_MAX,
    Capture,
    GBuffer,
    capture_parts,
    depth_range,
    gbuffer,
    peel,
    peel_eps,
    revealed_pixels,
)
from blueprint.render.renderer import Renderer, check_frame_args, check_size, straight_alpha
from blueprint.render.stop import Reveal, StopRule, standard_rules
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model

BASE_UNIT = units.INPUTS
FULLSCREEN = "fullscreen.vert"
ATTR_VERT = "blueprint.pipeline:glsl/attributes.vert"
ATTR_FRAG = "blueprint.pipeline:glsl/attributes.frag"
EXTRA = ("linear_depth", "position", "uv", "base_color", "triangle", "part", "layer")
# programs of the pipeline are built with this define, so they are instances of their own and
# the uniform cache is never fooled by the renderer setting the same program's uniforms
OWN = {"BLUEPRINT_PIPELINE": 1}
_UNSET = object()
# GL 4.3 compute forms (renderer.use_compute): an operation whose compute shader writes one
# slice (u_layer) of an r8 array, or maps a whole array to another (every slice a dispatch)
SLICE_OPS = {"edges"}
ARRAY_OPS = {"dilate"}
SLICES = 8


@dataclass
class Result:
    """What a pipeline run produced.

    output : ndarray
        (H, W, C) for a once-result, (L, H, W, C) for a per-layer one (every layer); uint8 for
        8-bit formats, float32 or int32 otherwise; row 0 at the top.
    premultiplied : bool
        The output is premultiplied colour (composite); ``image`` gives straight alpha.
    dumps : dict
        Name -> array like ``output`` for every ``dumps`` name asked for.
    revealed : float or None
        Where a ``reveal`` stop rule peeled: the fraction of its parts uncovered.
    """

    output: np.ndarray
    format: str
    premultiplied: bool
    layers: int
    layer_pixels: list[int]
    camera: Camera | None
    ms: float
    draws: int
    stages: dict[str, float] = field(default_factory=dict)
    dumps: dict[str, np.ndarray] = field(default_factory=dict)
    revealed: float | None = None

    @property
    def image(self) -> np.ndarray:
        """The output as an 8-bit picture: straight alpha, row 0 at the top."""
        out = self.output
        if out.dtype != np.uint8:
            raise InputError(f"the output is {self.format}, not an 8-bit image: write it as .npz")
        if self.premultiplied and out.shape[-1] == 4:
            return straight_alpha(out)
        return out


class _Group:
    """The G-buffer of one attribute scale, its geometry passes and queries, plus the attribute
    pass's targets."""

    def __init__(
        self, ex: Executor, scale: float, size, names: list[str], primary: bool, bound: Bound, clear_gb
    ):
        r = ex.r
        self.scale, self.size, self.names = scale, size, names
        self.gb: GBuffer = gbuffer(r.pool, size, "gb" if primary else f"pipeline.gb{scale:g}")
        self.queries = r.queries("peel" if primary else f"peel.pipeline.gb{scale:g}")
        self.primary = primary
        self.capture: Capture | None = None
        self.attr_clear = r.pool.framebuffer((self.gb.normal, self.gb.ids)) if clear_gb else None
        self.extra = [n for n in EXTRA if n in names]
        self.textures = {}
        for name in self.extra:
            fmt = bound.attributes[name].format
            self.textures[name] = r.pool.texture(f"pipeline.attr{scale:g}.{name}", size, fmt)
        self.extra_fbo = (
            r.pool.framebuffer(tuple(self.textures[n] for n in self.extra)) if self.extra else None
        )

    def texture(self, name: str, layer: int):
        if name == "depth":
            return self.gb.layer_depth(layer)
        if name == "normal":
            return self.gb.normal
        if name == "ids":
            return self.gb.ids
        return self.textures[name]


class Executor:
    """Runs pipelines on ``renderer`` (its context, pool, programs and peel)."""

    def __init__(self, renderer: Renderer) -> None:
        self.r = renderer
        self.ctx = renderer.ctx
        self._values: dict[tuple[int, str], object] = {}
        self._members: dict[int, set[str]] = {}
        self._vaos: dict[int, object] = {}
        self._user: dict[tuple, object] = {}
        self._images: dict[str, tuple[tuple, object]] = {}
        self._plans: dict[tuple, Plan] = {}
        self._parts: dict[str, object] = {}
        self._frame = 0
        self.draws = 0
        self.compositor = Compositor(renderer)

    def release(self) -> None:
        """Programs and queries of user shaders (pool targets belong to the renderer)."""
        for prog in self._user.values():
            prog.release()
        for vao in self._vaos.values():
            vao.release()
        self._user.clear()
        self._vaos.clear()
        self._images.clear()

    def _current(self) -> None:
        """Direct GL calls to the renderer's context (a process may hold several)."""
        make_current = getattr(self.r, "make_current", None)
        if make_current is not None:
            make_current()
        else:
            self.ctx.__enter__()

    # -- programs and uniforms ------------------------------------------------------------------
    def _program(self, fragment: str, vertex: str = FULLSCREEN, defines=None):
        return self.r.program(fragment, vertex, {**OWN, **(defines or {})})

    def _user_program(self, path):
        stamp = path.stat().st_mtime_ns
        key = (str(path), stamp)
        prog = self._user.get(key)
        if prog is None:
            text, files = user_source(path, str(path), "shader")
            vs, _ = preprocess(FULLSCREEN)
            try:
                prog = self.ctx.program(vertex_shader=vs, fragment_shader=f"{VERSION}\n{text}")
            except Exception as exc:
                raise ShaderError(f"shader error: {_explain(str(exc), files)}") from None
            self._user[key] = prog
        return prog

    def _vao(self, prog):
        vao = self._vaos.get(prog.glo)
        if vao is None:
            vao = self._vaos[prog.glo] = self.ctx.vertex_array(prog, [])
        return vao

    def _has(self, prog, name: str) -> bool:
        members = self._members.get(prog.glo)
        if members is None:
            members = self._members[prog.glo] = set(prog)
        return name in members

    def _set(self, prog, name: str, value) -> None:
        if not self._has(prog, name):
            return
        key = (prog.glo, name)
        if self._values.get(key) == value:
            return
        self._values[key] = value
        member = prog[name]
        if isinstance(value, bytes):
            member.write(value)
        else:
            member.value = value

    # -- plans ---------------------------------------------------------------------------------
    def plan(self, pipeline: PipelineSpec | Bound, variables=None, dumps=()) -> Plan:
        bound = pipeline.bind(variables) if isinstance(pipeline, PipelineSpec) else pipeline
        key = (id(bound), tuple(dumps))
        held = self._plans.get(key)
        if held is None or held.bound is not bound:
            held = self._plans[key] = plan(bound, tuple(dumps))
        return held

    # -- running -------------------------------------------------------------------------------
    def run(
        self,
        pipeline: PipelineSpec | Bound,
        model: Model | None = None,
        camera: Camera | None = None,
        *,
        size: tuple[int, int] | None = None,
        view: str = "iso",
        variables: dict | None = None,
        images: dict | None = None,
        style: str | Style | None = None,
        max_layers=_UNSET,
        min_fraction: float | None = None,
        crease_angle: float | None = None,
        parts: dict[str, np.ndarray] | None = None,
        dumps: tuple[str, ...] = (),
        profile: bool = False,
        frame: int | None = None,
    ) -> Result:
        """Run a pipeline once.

        Parameters
        ----------
        pipeline : PipelineSpec or Bound
            From ``load_pipeline``; ``variables`` override its declared variables.
        model, camera
            The model whose attributes are rendered (needed when any attribute is read);
            ``camera`` defaults to ``Camera.fit`` from ``view``.
        size : (int, int), optional
            Output size; default the file's ``size``, else the first image input's, else 1024².
        images : dict, optional
            Image inputs by name: (H, W, 3 or 4) uint8 arrays (row 0 at the top) or file paths,
            overriding the files the pipeline names.
        style : str or Style, optional
            Paper and inks of every composite pass (default: the pass's ``style`` parameter).
        max_layers, min_fraction, crease_angle
            Override the file's peeling settings (``max_layers=None``: every layer).
        parts : dict, optional
            Sets of parts by name, (P,) bool each, for the attributes of chosen parts
            (``{ of = "depth", parts = "NAME" }``) that the pipeline reads.
        dumps : names whose targets are read back into ``Result.dumps``.
        """
        t0 = clock = time.perf_counter()
        ctx = self.ctx
        self._current()
        stages: dict[str, float] = {}

        def stage(name: str) -> None:
            nonlocal clock
            if profile:
                ctx.finish()
                now = time.perf_counter()
                stages[name] = (now - clock) * 1e3
                clock = now

        pl = self.plan(pipeline, variables, dumps)
        bound = pl.bound
        images = dict(images or {})
        for name in images:
            if name not in bound.images:
                raise InputError(
                    f"{bound.source}: no image called {name!r} (choose {', '.join(bound.images) or 'none'})"
                )
        w, h = self._output_size(pl, size, images)
        sizes: dict[float, tuple[int, int]] = {}

        def size_of(scale: float) -> tuple[int, int]:
            if scale not in sizes:
                sizes[scale] = (max(1, round(w * scale)), max(1, round(h * scale)))
                if max(sizes[scale]) > self.r.max_texture:
                    raise InputError(
                        f"size {w}x{h} at scale {scale:g} is {sizes[scale][0]}x{sizes[scale][1]}: "
                        f"this GPU allows {self.r.max_texture} pixels per side"
                    )
            return sizes[scale]

        for scale in {bound.scale_of(n) for n in (*pl.attributes, *pl.images)} | {
            bound.passes[n].scale for n in pl.passes
        }:
            size_of(scale)
        if max_layers is _UNSET:
            max_layers = bound.layers if bound.layers is not None else 8
            max_layers = max_layers or None
        if not pl.layered:
            max_layers = 1
        min_fraction = bound.min_fraction if min_fraction is None else min_fraction
        crease = bound.crease_angle if crease_angle is None else crease_angle
        check_frame_args(max_layers, min_fraction, crease, 1.0)
        parts = dict(parts or {})
        for name in pl.parts:
            wanted = bound.attributes[name].parts
            if parts.get(wanted) is None:
                raise InputError(
                    f"{bound.source}: attributes.{name}: give the parts {wanted!r} (run it with parts)"
                )
        if pl.peel:
            if model is None:
                raise InputError(
                    f"{bound.source}: this pipeline renders attributes ({', '.join(pl.attributes)}): "
                    "give a model"
                )
            camera = camera or self.r.camera_for(model, (w, h), view)
        self.draws = 0
        self._frame = self._frame + 1 if frame is None else frame
        self._style = None if style is None else get_style(style)
        self._shade_ink = (self._style or _named_style(bound)).shade
        self._camera = camera
        self._crease = crease
        self._mesh = None
        self._size_of = size_of
        self._pl = pl
        self._stacks: dict[str, list] = {}
        self._arrays = self._array_plan(pl)
        self._attr_dumps: dict[str, list] = {
            n: [] for n in pl.readback if n in bound.attributes and bound.attributes[n].parts is None
        }
        for name in pl.images:
            self._upload(bound, name, images.get(name), size_of(bound.images[name].scale))
        stage("upload")

        ctx.enable_only(ctx.NOTHING)
        counts: list[int] = []
        revealed = None
        if pl.peel:
            mesh = self._mesh = self.r.mesh(model, crease)
            self._capture_parts(pl, mesh, camera, parts, size_of)
            rules = standard_rules(max_layers, min_fraction)
            reveal = self._reveal_rule(pl, camera)
            if reveal is not None:
                rules.append(reveal)
            counts, layers = self._peel(pl, mesh, camera, max_layers, size_of, rules)
            revealed = None if reveal is None else reveal.shown
        else:
            self._ensure_stacks(1)
            for name in pl.iteration0:
                self._run_pass(name, 0, 1)
            layers = 1
        if self._arrays is not None:
            self._run_batches(layers)
        stage("peel_edges")
        for name in pl.after:
            self._run_pass(name, 0, layers)
        stage("compose")
        ctx.disable(ctx.BLEND)
        if self.r.use_compute:
            ctx.memory_barrier(ctx.TEXTURE_UPDATE_BARRIER_BIT | ctx.FRAMEBUFFER_BARRIER_BIT)
        dumps_out = {}
        for name in pl.readback:
            dumps_out[name] = self._read(name, layers)
        stage("read")
        out_name = pl.output
        output = dumps_out[out_name]
        fmt = bound.format_of(out_name)
        premultiplied = out_name in bound.passes and bound.passes[out_name].kind == "composite"
        result_dumps = {d: dumps_out[pl.resolve(d)] for d in dumps}
        ms = (time.perf_counter() - t0) * 1e3
        return Result(
            output, fmt, premultiplied, layers, counts, camera, ms, self.draws, stages, result_dumps, revealed
        )

    def _output_size(self, pl: Plan, size, images) -> tuple[int, int]:
        if size is not None:
            w, h = check_size(size, 1, self.r.max_texture)
            return w, h
        if pl.bound.size is not None:
            return pl.bound.size
        from blueprint.pipeline.media import image_size

        for name in pl.images:
            spec = pl.bound.images[name]
            given = images.get(name)
            if isinstance(given, np.ndarray):
                return round(given.shape[1] / spec.scale), round(given.shape[0] / spec.scale)
            path = given if given is not None else spec.file
            if path is not None:
                iw, ih = image_size(path)
                return round(iw / spec.scale), round(ih / spec.scale)
        return 1024, 1024

    def _upload(self, bound: Bound, name: str, given, size) -> None:
        from pathlib import Path

        from blueprint.pipeline.media import read_image, to_format

        spec = bound.images[name]
        fmt = spec.format
        if isinstance(given, np.ndarray):
            if given.ndim == 2:
                given = np.repeat(given[..., None], 3, axis=2)
            data = given
            if data.shape[:2] != (size[1], size[0]):
                from PIL import Image

                data = np.asarray(
                    Image.fromarray(np.ascontiguousarray(data)).resize(size, Image.Resampling.BILINEAR)
                )
            data = to_format(np.ascontiguousarray(data, np.uint8), fmt)
            key = None
        else:
            path = Path(given) if given is not None else spec.file
            if path is None:
                raise InputError(
                    f"{bound.source}: images.{name}: no file given (set file, or give one when running)"
                )
            if spec.video:
                raise InputError(
                    f"{bound.source}: images.{name}: {path} is a video: "
                    "run it frame by frame (blueprint.pipeline.run.run_pipeline)"
                )
            try:
                stamp = path.stat().st_mtime_ns
            except OSError:
                raise InputError(f"{path}: no such image file") from None
            key = (str(path), stamp, fmt, size)
            held = self._images.get(name)
            if held is not None and held[0] == key:
                return
            data = read_image(path, fmt, size)
        tex = self.r.pool.texture(f"pipeline.image.{name}", size, fmt)
        tex.write(np.ascontiguousarray(data[::-1]).tobytes())
        self._images[name] = (key, tex)

    # -- the peel ------------------------------------------------------------------------------
    def _capture_parts(self, pl: Plan, mesh, camera: Camera, parts: dict, size_of) -> None:
        """The front surface of every set of chosen parts an attribute reads, once a frame,
        before the peel."""
        bound = pl.bound
        self._parts = {}
        held: dict[tuple[str, float], GBuffer] = {}
        for name in pl.parts:
            spec = bound.attributes[name]
            key = (spec.parts, spec.scale)
            if key not in held:
                held[key] = capture_parts(
                    self.r,
                    mesh,
                    camera,
                    size_of(spec.scale),
                    parts[spec.parts],
                    f"parts.{spec.parts}.{spec.scale:g}",
                    spec.parts,
                )
                self.draws += 1
            gb = held[key]
            self._parts[name] = {"depth": gb.depth[0], "normal": gb.normal, "ids": gb.ids}[spec.of]

    def _reveal_rule(self, pl: Plan, camera: Camera) -> StopRule | None:
        """Depth masking, where the pipeline declares it: counts the chosen parts' pixels now,
        and after every layer those the layers peeled so far uncovered."""
        (stop,) = [s for s in pl.bound.stops if s.rule == "reveal"] or [None]
        if stop is None:
            return None
        mask = self._parts[stop.depth]
        primary_scale = pl.bound.attributes["depth"].scale if "depth" in pl.bound.attributes else None
        if primary_scale is not None and abs(pl.bound.attributes[stop.depth].scale - primary_scale) > 1e-9:
            raise InputError(
                f"{pl.bound.source}: stop.reveal.depth: {stop.depth!r} must be at the scale of depth"
            )
        wanted = revealed_pixels(self.r, camera, mask)
        self.draws += 1

        def revealed(layer: int) -> int:
            self.draws += 1
            return revealed_pixels(self.r, camera, mask, self._groups[0].gb.layer_depth(layer))

        return Reveal(stop.fraction, wanted, revealed)

    def _peel(self, pl: Plan, mesh, camera: Camera, max_layers, size_of, rules) -> tuple[list[int], int]:
        r, ctx, bound = self.r, self.ctx, pl.bound
        by_scale: dict[float, list[str]] = {}
        for name in pl.attributes:
            if bound.attributes[name].parts is None:
                by_scale.setdefault(bound.attributes[name].scale, []).append(name)
        if not by_scale:  # attributes of chosen parts alone: nothing to peel
            self._groups = []
            self._ensure_stacks(1)
            for name in pl.iteration0:
                self._run_pass(name, 0, 1)
            return [], 1
        primary_scale = bound.attributes["depth"].scale if "depth" in pl.attributes else next(iter(by_scale))
        # normal and ids are left as they were where a layer has no surface; clear them unless
        # every reader looks at depth first (the edges operation)
        readers = {
            (t, bound.passes[n].op.name) for n in pl.passes for t in bound.passes[n].inputs.values()
        } | {(n, "readback") for n in pl.readback}
        clear_gb = any(t in ("normal", "ids") and op != "edges" for t, op in readers)
        groups = []
        for scale, names in sorted(by_scale.items(), key=lambda kv: kv[0] != primary_scale):
            groups.append(_Group(self, scale, size_of(scale), names, scale == primary_scale, bound, clear_gb))
        self._groups = groups
        self._by_attr = {n: g for g in groups for n in g.names}
        ctx.depth_func = "<"
        # face IDs cost a software rasteriser dearly; only the extra attributes (and readers of
        # the raw ID target) need them
        face_ids = any(g.extra for g in groups) or clear_gb or self._id_silhouettes(pl)
        for g in groups:
            g.capture = Capture(r, mesh, camera, g.gb, face_ids=face_ids, batch=max_layers or KBUFFER_MAX)
        extras = self._extras_programs(groups, camera, mesh) if any(g.extra for g in groups) else None
        for name in pl.accumulated:
            self.r.pool.framebuffer((self._target(name, 0),)).clear()

        def draw(layer: int, query, guard) -> None:
            self._ensure_stacks(layer + 1)
            for g in groups:
                if g.attr_clear is not None:
                    g.attr_clear.clear()
                if g.primary:
                    g.capture.draw(layer, query, guard)
                else:
                    g.capture.draw(layer, g.queries[layer], g.queries[layer - 1] if layer else None)
                self.draws += 3
                if g.extra:
                    self._extras(g, layer, extras, mesh)
            for name, held in self._attr_dumps.items():
                held.append(
                    self._read_texture(
                        self._by_attr[name].texture(name, layer), bound.attributes[name].format
                    )
                )
            for name in pl.iteration0 if layer == 0 else pl.per_layer:
                self._run_pass(name, layer, layer + 1)

        return peel(draw, groups[0].queries, rules)

    def _extras_programs(self, groups, camera: Camera, mesh):
        progs = {}
        for g in groups:
            if not g.extra:
                continue
            defines = {f"OUT_{n.upper()}": (g.extra.index(n) if n in g.extra else -1) for n in EXTRA}
            draw = self._program(ATTR_FRAG, ATTR_VERT, {**defines, "CLEAR": 0})
            clear = self._program(ATTR_FRAG, FULLSCREEN, {**defines, "CLEAR": 1})
            self._set(draw, "u_view", camera.view_matrix().T.astype("f4").tobytes())
            self._set(draw, "u_projection", camera.projection_matrix().T.astype("f4").tobytes())
            lo, hi = mesh_bounds(mesh)
            self._set(draw, "u_bounds_lo", tuple(float(v) for v in lo))
            self._set(draw, "u_bounds_size", tuple(float(max(v, 1e-30)) for v in hi - lo))
            self._set(draw, "u_layer_depth", BASE_UNIT)
            self._set(draw, "u_ids", BASE_UNIT + 1)
            progs[g.scale] = (draw, clear)
        return progs

    def _extras(self, g: _Group, layer: int, progs, mesh) -> None:
        draw, clear = progs[g.scale]
        g.extra_fbo.use()
        self._vao(clear).render(vertices=3)
        g.gb.layer_depth(layer).use(BASE_UNIT)
        g.gb.ids.use(BASE_UNIT + 1)
        self._set(draw, "u_layer", layer)
        mesh.vao(draw).render()
        self.draws += 2

    # -- passes --------------------------------------------------------------------------------
    def _ensure_stacks(self, layers: int) -> None:
        pl = self._pl
        arrays = self._arrays["arrays"] if self._arrays else set()
        for name in arrays:
            held = self._stacks.setdefault(name, [])
            size = self._size_of(pl.bound.passes[name].scale)
            while len(held) * SLICES < layers:
                held.append(self.r.pool.texture(f"pipeline.array.{name}.{len(held)}", size, "r8", SLICES))
        for name in pl.stacked - arrays:
            p = pl.bound.passes[name]
            held = self._stacks.setdefault(name, [])
            size = self._size_of(p.scale)
            while len(held) < layers:
                held.append(self.r.pool.texture(f"pipeline.stack.{name}.{len(held)}", size, p.format))

    def _value(self, name: str, layer: int):
        """The texture holding ``name`` for a pass at ``layer``."""
        pl, bound = self._pl, self._pl.bound
        if name in self._parts:
            return self._parts[name]
        if name in bound.attributes:
            return self._by_attr[name].texture(name, layer)
        if name in bound.images:
            return self._images[name][1]
        if name in pl.stacked:
            p = bound.passes[name]
            return self._stacks[name][layer if p.per_layer else 0]
        slot = pl.slots[name]
        return self.r.pool.texture(slot.name, self._size_of(slot.scale), slot.format)

    def _target(self, name: str, layer: int):
        pl = self._pl
        if name in pl.stacked:
            p = pl.bound.passes[name]
            return self._stacks[name][layer if p.per_layer else 0]
        slot = pl.slots[name]
        return self.r.pool.texture(slot.name, self._size_of(slot.scale), slot.format)

    @staticmethod
    def _defines(p) -> dict:
        return p.op.defines(p.uniforms) if p.op.switches else {}

    @staticmethod
    def _id_silhouettes(pl: Plan) -> bool:
        """Whether an edges pass draws triangle-ID silhouettes (they need face IDs)."""
        return any(
            p.op is not None and p.op.name == "edges" and p.uniforms.get("u_id_silhouettes")
            for p in pl.bound.passes.values()
        )

    def _frame_uniforms(self, prog, target, layer: int) -> None:
        w, h = target.size
        self._set(prog, "u_texel", (1.0 / w, 1.0 / h))
        self._set(prog, "u_size", (float(w), float(h)))
        self._set(prog, "u_layer", layer)
        self._set(prog, "u_frame", self._frame)
        camera = self._camera
        if camera is not None:
            self._set(prog, "u_depth_range", depth_range(camera))
            self._set(prog, "u_peel_eps", peel_eps(camera))
            self._set(prog, "u_pixel_angle", camera.pixel_angle(h))
            half = math.radians(self._crease)
            self._set(prog, "u_normal_cos", (math.cos(0.5 * half), math.cos(0.8 * half)))
            if self._has(prog, "u_corners") and self._mesh is not None:
                self._mesh.bind_corners(prog, units.CORNERS)
        if self._has(prog, "u_shade_ink"):
            self._set(prog, "u_shade_ink", tuple(self._shade_ink))
            if self._has(prog, "u_view"):
                self._set(prog, "u_view", camera.view_matrix().T.astype("f4").tobytes())
                self._set(prog, "u_projection", camera.projection_matrix().T.astype("f4").tobytes())

    def _bind_input(self, prog, key: str, tex, unit: int, target) -> None:
        tex.use(unit)
        self._set(prog, f"u_{key}", unit)
        w, h = tex.size[:2]
        self._set(prog, f"u_{key}_texel", (1.0 / w, 1.0 / h))
        self._set(prog, f"u_{key}_size", (float(w), float(h)))
        self._set(prog, f"u_{key}_components", tex.components)
        self._set(prog, f"u_{key}_factor", max(1, w // target.size[0]))

    def _run_pass(self, name: str, layer: int, layers: int) -> None:
        pl = self._pl
        p = pl.bound.passes[name]
        if self._arrays is not None:
            if name in self._arrays["batch"]:
                return  # the whole arrays, after the peel
            if name in self._arrays["slice"]:
                self._run_slice(name, p, layer)
                return
        if p.kind == "composite":
            self._composite(p, self._target(name, layer), layers)
            return
        target = self._target(name, layer)
        inputs = {key: pl.resolve(t) for key, t in p.inputs.items()}
        if p.user is not None:
            prog = self._user_program(p.user)
        else:
            prog = self._program(p.op.shader, defines=self._defines(p))
        self._frame_uniforms(prog, target, layer)
        for uniform, value in p.uniforms.items():
            self._set(prog, uniform, value)
        unit = BASE_UNIT
        for key, source in inputs.items():
            self._bind_input(prog, key, self._value(source, layer), unit, target)
            unit += 1
        vao = self._vao(prog)
        if p.kind == "separable":
            scratch_slot = pl.scratch[name]
            scratch = self.r.pool.texture(
                scratch_slot.name, self._size_of(scratch_slot.scale), scratch_slot.format
            )
            self._set(prog, "u_direction", (1, 0))
            self.r.pool.framebuffer((scratch,)).use()
            vao.render(vertices=3)
            self._bind_input(prog, next(iter(inputs)), scratch, BASE_UNIT, target)
            self._set(prog, "u_direction", (0, 1))
            self.draws += 1
        self.r.pool.framebuffer((target,)).use()
        vao.render(vertices=3)
        self.draws += 1

    # -- the compute forms (GL 4.3) -------------------------------------------------------------------
    def _array_plan(self, pl: Plan):
        """When the renderer runs image passes as compute shaders and every per-layer pass has
        a compute form (a slice op on attributes, then array ops) feeding only composites,
        the per-layer results live in r8 arrays of 8 slices, as the renderer's own edges do."""
        if not self.r.use_compute or not pl.per_layer:
            return None
        b = pl.bound
        arrays: set[str] = set()
        slices, batch = [], []
        for name in pl.per_layer:
            p = b.passes[name]
            if p.accumulate:
                continue  # a fragment pass into its own target, in either form
            sources = [pl.resolve(t) for t in p.inputs.values()]
            if p.user is not None or p.format != "r8" or p.op.compute is None:
                return None
            if p.op.name in SLICE_OPS and all(t in b.attributes for t in sources):
                slices.append(name)
            elif p.op.name in ARRAY_OPS and len(sources) == 1 and sources[0] in arrays:
                batch.append(name)
            else:
                return None
            arrays.add(name)
        for name in pl.passes:
            p = b.passes[name]
            for key, target in p.inputs.items():
                target = pl.resolve(target)
                if (
                    target in arrays
                    and name not in arrays
                    and not (p.kind == "composite" and key in p.stacks)
                ):
                    return None
        if any(n in arrays for n in pl.readback):
            return None
        return {"arrays": arrays, "slice": slices, "batch": batch}

    def _run_slice(self, name: str, p, layer: int) -> None:
        prog = self.r.compute(p.op.compute, {**OWN, **self._defines(p)})
        array = self._stacks[name][layer // SLICES]
        size = array.size[:2]
        self._frame_uniforms(prog, _Sized(size), layer)
        for uniform, value in p.uniforms.items():
            self._set(prog, uniform, value)
        unit = BASE_UNIT
        for key, source in p.inputs.items():
            self._bind_input(prog, key, self._value(self._pl.resolve(source), layer), unit, _Sized(size))
            unit += 1
        self._set(prog, "u_layer", layer % SLICES)
        array.bind_to_image(1, read=False, write=True)
        prog.run((size[0] + 7) // 8, (size[1] + 7) // 8)
        self.draws += 1

    def _run_batches(self, layers: int) -> None:
        ctx, pl = self.ctx, self._pl
        ctx.memory_barrier(ctx.TEXTURE_FETCH_BARRIER_BIT | ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)
        used = (max(layers, 1) + SLICES - 1) // SLICES
        for name in self._arrays["batch"]:
            p = pl.bound.passes[name]
            prog = self.r.compute(p.op.compute, OWN)
            for uniform, value in p.uniforms.items():
                self._set(prog, uniform, value)
            (source,) = (pl.resolve(t) for t in p.inputs.values())
            (key,) = p.inputs
            self._set(prog, f"u_{key}", BASE_UNIT)
            for k in range(used):
                src, dst = self._stacks[source][k], self._stacks[name][k]
                src.use(BASE_UNIT)
                dst.bind_to_image(1, read=False, write=True)
                prog.run((dst.size[0] + 7) // 8, (dst.size[1] + 7) // 8, SLICES)
                self.draws += 1
            ctx.memory_barrier(ctx.TEXTURE_FETCH_BARRIER_BIT | ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)

    def _composite(self, p, target, layers: int) -> None:
        """The compositor over the pass's stack of layers, with the shading and highlight
        maps wired to it; in compute form where the layers live in 8-slice arrays."""
        pl = self._pl
        style = self._style or STYLES[p.op.params[0].choices[p.uniforms["u_style"]]]
        wired = {key: pl.resolve(t) for key, t in p.inputs.items()}
        highlight = self._value(wired["highlight"], 0) if "highlight" in wired else None
        shading = None
        if "shade_color" in wired or "shade_index" in wired:
            if not ("shade_color" in wired and "shade_index" in wired):
                raise InputError(
                    f"{pl.bound.source}: passes.{p.name}.inputs: give shade_color and shade_index together"
                )
            shading = Shading(self._value(wired["shade_index"], 0), self._value(wired["shade_color"], 0))
        source = wired[p.stacks[0]]
        if self._arrays is not None and source in self._arrays["arrays"]:
            self.draws += self.compositor.compute(
                target, self._stacks[source], layers, style, highlight=highlight, shading=shading
            )
        else:
            self.draws += self.compositor.fragment(
                target, self._stacks[source], layers, style, highlight=highlight, shading=shading
            )

    # -- read back -----------------------------------------------------------------------------
    def _read(self, name: str, layers: int) -> np.ndarray:
        pl, bound = self._pl, self._pl.bound
        if name in self._parts:
            return self._read_texture(self._parts[name], bound.attributes[name].format)
        if name in bound.attributes:
            held = self._attr_dumps[name]
            return np.stack(held[: max(layers, 1)]) if pl.layered else held[0]
        fmt = bound.format_of(name)
        if name in pl.stacked and bound.passes[name].per_layer:
            count = max(1, min(layers, len(self._stacks[name])))
            return np.stack([self._read_texture(t, fmt) for t in self._stacks[name][:count]])
        return self._read_texture(self._value(name, 0), fmt)

    def _read_texture(self, tex, fmt: str) -> np.ndarray:
        w, h = tex.size[:2]
        if fmt == "depth":
            data = np.frombuffer(tex.read(), np.float32).reshape(h, w, 1)
        else:
            components, dtype = FORMATS[fmt]
            np_dtype = {"f1": np.uint8, "f2": np.float16, "f4": np.float32, "i4": np.int32}[dtype]
            data = np.frombuffer(tex.read(), np_dtype).reshape(h, w, components)
            if np_dtype == np.float16:
                data = data.astype(np.float32)
        return np.ascontiguousarray(data[::-1])

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
        from blueprint.ops import OPS
        from blueprint.pipeline.spec import BoundPass, ImageSpec, _check_params

        op = OPS[op_name]
        stacks = op.stacks
        formats = dict(formats or {})
        images, wiring, arrays = {}, {}, {}
        for key, value in inputs.items():
            layers = value if isinstance(value, list) else [value]
            fmt = formats.get(key) or _default_format(layers[0])
            images[f"in_{key}"] = ImageSpec(f"in_{key}", None, fmt, 1.0)
            wiring[key] = f"in_{key}"
            arrays[key] = layers
        first_fmt = next(iter(images.values())).format
        fmt = output or op.output
        if fmt == "same":
            fmt = "r32f" if first_fmt == "depth" else first_fmt
        uniforms = _check_params(f"run_op {op_name}", "params", op, params or {}, {})
        bound = Bound(
            f"run_op {op_name}",
            op_name,
            "out",
            1,
            0.0,
            30.0,
            None,
            {},
            images,
            {"out": BoundPass("out", op, wiring, uniforms, fmt, scale, False)},
            {},
        )
        pl = plan(bound)
        first = arrays[next(iter(arrays))][0]
        fh, fw = first.shape[:2]
        self._pl, self._camera, self._crease = pl, camera, crease_angle
        self._style = None if style is None else get_style(style)
        self._shade_ink = (self._style or STYLES["blueprint"]).shade
        self._stacks, self._by_attr, self._parts, self._frame, self._arrays = {}, {}, {}, 0, None
        self._mesh = None
        self._size_of = lambda s: (max(1, round(fw * s)), max(1, round(fh * s)))
        self._current()
        self.ctx.enable_only(self.ctx.NOTHING)
        self.draws = 0
        for key, layers in arrays.items():
            fmt_in = images[f"in_{key}"].format
            textures = [
                self._upload_array(f"pipeline.test.{key}.{k}", a, fmt_in) for k, a in enumerate(layers)
            ]
            if key in stacks:
                self._stacks[f"in_{key}"] = textures
            else:
                self._images[f"in_{key}"] = (None, textures[0])
        count = len(arrays[stacks[0]]) if stacks else 1
        self._run_pass("out", 0, count)
        return self._read_texture(self._target("out", 0), fmt)[::-1]

    def _upload_array(self, name: str, array: np.ndarray, fmt: str):
        h, w = array.shape[:2]
        if fmt == "depth":
            tex = self.r.pool.depth(name, (w, h))
            tex.write(np.ascontiguousarray(array, np.float32).tobytes())
            return tex
        components, dtype = FORMATS[fmt]
        np_dtype = {"f1": np.uint8, "f2": np.float16, "f4": np.float32, "i4": np.int32}[dtype]
        tex = self.r.pool.texture(name, (w, h), fmt)
        tex.write(np.ascontiguousarray(np.asarray(array).reshape(h, w, components), np_dtype).tobytes())
        return tex


class _Sized:
    """Stands in for a target where only its size matters (compute passes into arrays)."""

    def __init__(self, size) -> None:
        self.size = tuple(size)


def _default_format(array: np.ndarray) -> str:
    c = array.shape[2] if array.ndim == 3 else 1
    if array.dtype == np.uint8:
        return {1: "r8", 4: "rgba8"}[c]
    if np.issubdtype(array.dtype, np.integer):
        return {1: "r32i", 2: "rg32i"}[c]
    return {1: "r32f", 2: "rg32f", 4: "rgba32f"}[c]


def mesh_bounds(mesh) -> tuple[np.ndarray, np.ndarray]:
    """Model-space bounds of an uploaded mesh (kept on the mesh after the first look)."""
    held = getattr(mesh, "_pipeline_bounds", None)
    if held is None:
        data = np.frombuffer(mesh.vbo.read(), np.float32).reshape(-1, 6)[:, :3]
        held = (data.min(axis=0).astype(np.float64), data.max(axis=0).astype(np.float64))
        mesh._pipeline_bounds = held
    return held


def part_color(part: np.ndarray) -> np.ndarray:
    """(..., 3) float: the base colour the attribute pass gives part indices (see attributes.frag)."""
    h = np.modf(np.asarray(part, np.float64) * 0.61803398875)[0][..., None]
    p = np.abs(np.modf(h + np.array([1.0, 2.0 / 3.0, 1.0 / 3.0]))[0] * 6.0 - 3.0)
    return 0.9 * (1.0 + (np.clip(p - 1.0, 0.0, 1.0) - 1.0) * 0.45)


_executors: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def executor_for(renderer: Renderer) -> Executor:
    """One executor per renderer (it holds caches of programs and plans)."""
    ex = _executors.get(renderer)
    if ex is None:
        ex = _executors[renderer] = Executor(renderer)
    return ex


def _named_style(bound: Bound) -> Style:
    """The style a pipeline names in its ``style`` variable, else the blueprint's."""
    name = bound.variables.get("style")
    return STYLES[name] if name in STYLES else STYLES["blueprint"]
