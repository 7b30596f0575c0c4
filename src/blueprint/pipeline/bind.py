"""Binding a parsed pipeline: variables substituted, every value, format, scale, input and
stop rule checked, passes that are off dropped, and the graph planned once to prove it runs;
all before any GPU work, each error one line naming the file and the key."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

from blueprint.errors import InputError
from blueprint.ops import Op
from blueprint.pipeline.expressions import evaluate
from blueprint.pipeline.graph import plan
from blueprint.pipeline.schema import (
    ALL_FORMATS,
    ATTRIBUTES,
    FORMATS,
    IMAGE_FORMATS,
    IMAGE_SUFFIXES,
    MAX_LAYERS,
    MAX_SCALE,
    OPERATIONS,
    VIDEO_SUFFIXES,
    AttributeSpec,
    Bound,
    BoundPass,
    ImageSpec,
    ParsedPipeline,
    StopSpec,
    channels,
    fail,
    is_int_format,
)
from blueprint.pipeline.user import user_op


def _number(value, source: str, key: str, low: float, high: float, integer: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise fail(source, key, f"must be a number in [{low:g}, {high:g}], got {value!r}")
    if integer and int(value) != value:
        raise fail(source, key, f"must be a whole number in [{low:g}, {high:g}], got {value!r}")
    if not low <= value <= high:
        raise fail(source, key, f"must be in [{low:g}, {high:g}], got {value:g}")
    return int(value) if integer else float(value)


def _scale(value, source: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value <= MAX_SCALE:
        raise fail(
            source,
            key,
            f"scale must be a number in (0, {MAX_SCALE:g}] (times the output size), got {value!r}",
        )
    return float(value)


def _format(value, source: str, key: str, allowed) -> str:
    if value not in allowed:
        raise fail(source, key, f"format {value!r} is not allowed here (choose {', '.join(allowed)})")
    return value


def _accepts(declared: str, fmt: str) -> bool:
    """Whether a target of format ``fmt`` can feed an input declared as ``declared``."""
    if declared == "depth":
        return fmt == "depth"
    if declared == "int":
        return is_int_format(fmt)
    if declared == "float":
        return not is_int_format(fmt)
    if is_int_format(declared) != is_int_format(fmt):
        return False
    return channels(fmt) >= channels(declared)


def _describe(declared: str) -> str:
    if declared == "depth":
        return "the depth attribute"
    if declared == "int":
        return f"an integer format ({', '.join(f for f in ALL_FORMATS if is_int_format(f))})"
    if declared == "float":
        return f"a non-integer format ({', '.join(f for f in ALL_FORMATS if not is_int_format(f))})"
    fits = [f for f in ALL_FORMATS if f != "depth" and _accepts(declared, f)]
    return f"{declared} or wider ({', '.join(fits)})"


def check_params(source: str, key: str, op: Op, raw: dict, variables: dict) -> dict:
    known = {p.name: p for p in op.params}
    out = {}
    for name, value in raw.items():
        if name not in known:
            raise fail(
                source,
                f"{key}.{name}",
                f"unknown parameter of {op.name} (choose {', '.join(known) or 'none'})",
            )
        value = evaluate(value, variables, source, f"{key}.{name}")
        try:
            out[f"u_{name}"] = known[name].check(op.name, value)
        except InputError as exc:
            raise fail(source, f"{key}.{name}", str(exc)) from None
    for p in op.params:
        if f"u_{p.name}" not in out:
            out[f"u_{p.name}"] = p.check(op.name, p.default)
    derive = op.derive
    if derive is not None:
        out.update(derive(out))
    return out


def bind(spec: ParsedPipeline, values: dict) -> Bound:
    """``spec`` with the variables ``values`` substituted, every value checked, the passes that
    are off dropped and the rest in dependency order, planned once to prove the graph runs."""
    binding = _Binding(spec, values)
    layers, min_fraction, crease, size = binding.settings()
    binding.bind_attributes()
    binding.bind_images()
    binding.bind_passes()
    binding.check_output()
    bound = Bound(
        spec.source,
        spec.name,
        spec.output,
        layers,
        min_fraction,
        crease,
        size,
        binding.attributes,
        binding.images,
        binding.passes,
        values,
        binding.stops(),
    )
    plan(bound)
    return bound


class _Binding:
    """One binding of a parsed pipeline: its values evaluated, its attributes, images and
    passes bound in turn (each pass after those it reads)."""

    def __init__(self, spec: ParsedPipeline, values: dict) -> None:
        self.spec, self.values, self.src = spec, values, spec.source
        self.attributes: dict[str, AttributeSpec] = {}
        self.images: dict[str, ImageSpec] = {}
        self.passes: dict[str, BoundPass] = {}
        self.available = [*spec.attributes, *spec.images, *spec.passes]
        self.active: set[str] = set()

    def ev(self, value, key: str):
        return evaluate(value, self.values, self.src, key)

    def settings(self) -> tuple:
        """(layers, min_fraction, crease_angle, size) of ``[pipeline]``."""
        spec, src, ev = self.spec, self.src, self.ev
        layers = ev(spec.settings.get("layers"), "pipeline.layers")
        if layers is not None:
            layers = _number(layers, src, "pipeline.layers", 0, MAX_LAYERS, integer=True)
        min_fraction = _number(
            ev(spec.settings.get("min_fraction", 0.0), "pipeline.min_fraction"),
            src,
            "pipeline.min_fraction",
            0,
            1,
        )
        crease = _number(
            ev(spec.settings.get("crease_angle", 30.0), "pipeline.crease_angle"),
            src,
            "pipeline.crease_angle",
            0,
            180,
        )
        size = spec.settings.get("size")
        if size is not None:
            if not (isinstance(size, list) and len(size) == 2):
                raise fail(src, "pipeline.size", "must be [width, height] in pixels")
            size = tuple(
                _number(ev(v, "pipeline.size"), src, "pipeline.size", 1, 16384, integer=True) for v in size
            )
        return layers, min_fraction, crease, size

    def bind_attributes(self) -> None:
        src, ev = self.src, self.ev
        for name, entry in self.spec.attributes.items():
            key = f"attributes.{name}"
            of = entry.get("of", name)
            default, allowed, _, _ = ATTRIBUTES[of]
            fmt = _format(ev(entry.get("format", default), f"{key}.format"), src, f"{key}.format", allowed)
            scale = _scale(ev(entry.get("scale", 1), f"{key}.scale"), src, f"{key}.scale")
            self.attributes[name] = AttributeSpec(name, fmt, scale, of, entry.get("parts"))

    def bind_images(self) -> None:
        src, ev = self.src, self.ev
        for name, entry in self.spec.images.items():
            key = f"images.{name}"
            fmt = _format(
                ev(entry.get("format", "rgba8"), f"{key}.format"), src, f"{key}.format", IMAGE_FORMATS
            )
            file = ev(entry.get("file"), f"{key}.file")
            path = None
            if file is not None:
                if not isinstance(file, str):
                    raise fail(src, f"{key}.file", "must be a file name")
                path = Path(file)
                if not path.is_absolute():
                    path = (self.spec.folder or Path.cwd()) / path
                if path.suffix.lower() not in (*IMAGE_SUFFIXES, *VIDEO_SUFFIXES):
                    raise fail(
                        src,
                        f"{key}.file",
                        f"unknown kind of file (choose {', '.join(IMAGE_SUFFIXES + VIDEO_SUFFIXES)})",
                    )
            scale = _scale(ev(entry.get("scale", 1), f"{key}.scale"), src, f"{key}.scale")
            self.images[name] = ImageSpec(name, path, fmt, scale)

    def bind_passes(self) -> None:
        """Every pass that is on, in dependency order: its format and scale follow its inputs'."""
        self.active = {
            n
            for n, p in self.spec.passes.items()
            if _switch(self.ev(p.when, f"passes.{n}.when"), self.src, f"passes.{n}.when")
        }
        for name in _order(self.spec):
            if name in self.active:
                self.passes[name] = self.bind_pass(name)

    def bind_pass(self, name: str) -> BoundPass:
        p, key = self.spec.passes[name], f"passes.{name}"
        op = self._operation(p, key)
        p = replace(p, inputs=self._wiring(p, op, key))
        per_layer = self._flag(p.per_layer, f"{key}.per_layer")
        accumulate = self._flag(p.accumulate, f"{key}.accumulate")
        if accumulate and not per_layer:
            raise fail(self.src, f"{key}.accumulate", "only a per-layer pass accumulates its layers")
        first_format, first_scale = self._check_inputs(name, p, op, per_layer)
        if p.scale is None:
            scale = 1.0 if op.resample else first_scale if first_scale is not None else 1.0
        else:
            scale = _scale(self.ev(p.scale, f"{key}.scale"), self.src, f"{key}.scale")
        self._check_scales(p, op, scale, key)
        fmt = self._output_format(p, op, first_format, key)
        uniforms = check_params(self.src, f"{key}.params", op, p.params, self.values)
        return BoundPass(name, op, dict(p.inputs), uniforms, fmt, scale, per_layer, p.shader, accumulate)

    def _operation(self, p, key: str) -> Op:
        """The library's operation a pass names, or its own shader's."""
        if p.op is None:
            return user_op(self.spec, p, self.values)
        if p.op not in OPERATIONS:
            raise fail(self.src, f"{key}.op", f"unknown operation {p.op!r} (choose {', '.join(OPERATIONS)})")
        return OPERATIONS[p.op]

    def _wiring(self, p, op: Op, key: str) -> dict[str, str]:
        """The pass's inputs, those from passes that are off left out where ``op`` may go without."""
        src = self.src
        for input_name in p.inputs:
            if input_name not in op.inputs:
                raise fail(
                    src,
                    f"{key}.inputs.{input_name}",
                    f"{op.name} has no input {input_name!r} (choose {', '.join(op.inputs)})",
                )
        wiring = {}
        for input_name, target in p.inputs.items():
            if target in self.spec.passes and target not in self.active:
                if input_name in op.optional:
                    continue  # an optional input of a pass that is off here is left unwired
                raise fail(src, f"{key}.inputs.{input_name}", f"{target!r} is off here (its when is false)")
            wiring[input_name] = target
        for input_name in op.inputs:
            if input_name not in wiring and input_name not in op.optional:
                raise fail(
                    src,
                    f"{key}.inputs",
                    f"missing input {input_name!r} of {op.name} (it needs {', '.join(op.inputs)})",
                )
        return wiring

    def _flag(self, value, key: str) -> bool:
        value = self.ev(value, key)
        if not isinstance(value, bool):
            raise fail(self.src, key, f"must be true or false, got {value!r}")
        return value

    def _bound_of(self, target: str):
        """The bound attribute, image or pass called ``target``."""
        return self.attributes.get(target) or self.images.get(target) or self.passes[target]

    def _check_inputs(self, name: str, p, op: Op, per_layer: bool) -> tuple[str | None, float | None]:
        """Every input names something bound, of a format ``op`` reads (every layer of a
        per-layer pass for a stack input); the first input's (format, scale)."""
        src, key = self.src, f"passes.{name}"
        first_format = first_scale = None
        for input_name, target in p.inputs.items():
            ikey = f"{key}.inputs.{input_name}"
            if target not in self.available:
                choices = ", ".join(n for n in self.available if n != name)
                raise fail(src, ikey, f"unknown name {target!r} (choose {choices})")
            if target in self.spec.attributes and target not in self.attributes:
                raise fail(src, ikey, f"attribute {target!r} is not declared")
            held = self._bound_of(target)
            declared = op.inputs[input_name]
            if input_name in op.stacks:
                if target not in self.passes or not self.passes[target].per_layer:
                    raise fail(
                        src,
                        ikey,
                        f"{op.name} takes every depth layer of a per-layer pass; {target!r} is not one "
                        "(set per_layer = true on it)",
                    )
                if per_layer:
                    raise fail(
                        src,
                        f"{key}.per_layer",
                        f"{op.name} reads all layers at once, so it cannot run per layer",
                    )
            if not _accepts(declared, held.format):
                raise fail(
                    src,
                    ikey,
                    f"{target!r} is {held.format}, but {op.name}.{input_name} needs {_describe(declared)}",
                )
            if first_format is None:
                first_format, first_scale = held.format, held.scale
        return first_format, first_scale

    def _check_scales(self, p, op: Op, scale: float, key: str) -> None:
        """Inputs at the pass's scale, or at a whole ratio from 1 to 8 where ``op`` resamples them."""
        src = self.src
        for input_name, target in p.inputs.items():
            in_scale = self._bound_of(target).scale
            ikey = f"{key}.inputs.{input_name}"
            if input_name in op.resample:
                ratio = in_scale / scale
                if ratio < 1 - 1e-9 or abs(ratio - round(ratio)) > 1e-6 or round(ratio) > 8:
                    raise fail(
                        src,
                        ikey,
                        f"{target!r} is at scale {in_scale:g} and this pass at {scale:g}: "
                        f"{op.name} needs a whole ratio from 1 to 8",
                    )
            elif abs(in_scale - scale) > 1e-9:
                raise fail(
                    src,
                    ikey,
                    f"{target!r} is at scale {in_scale:g} but this pass is at {scale:g}; "
                    f"{op.name} needs equal scales (choose scale = {in_scale:g}, or downsample first)",
                )

    def _output_format(self, p, op: Op, first_format: str | None, key: str) -> str:
        """The pass's format: its own, of the kind (integer or not, four channels for a
        composite) of ``op``'s output, else that output's (``same``: the first input's)."""
        default = op.output
        if default == "same":
            default = "r32f" if first_format == "depth" else first_format
        kind_int = is_int_format(default)
        allowed = [
            f
            for f in FORMATS
            if is_int_format(f) == kind_int and (op.kind != "composite" or channels(f) == 4)
        ]
        if p.format is None:
            return default
        return _format(self.ev(p.format, f"{key}.format"), self.src, f"{key}.format", allowed)

    def check_output(self) -> None:
        output, src = self.spec.output, self.src
        if output not in self.available:
            raise fail(
                src, "pipeline.output", f"unknown name {output!r} (choose {', '.join(self.available)})"
            )
        if output in self.spec.passes and output not in self.active:
            raise fail(src, "pipeline.output", f"{output!r} is off here (its when is false)")

    def stops(self) -> tuple[StopSpec, ...]:
        """The stop rules that are on, each reading a depth of chosen parts at the layers' scale."""
        src, ev = self.src, self.ev
        stops = []
        for rule, entry in self.spec.stops.items():
            key = f"stop.{rule}"
            if not _switch(ev(entry.get("when", True), f"{key}.when"), src, f"{key}.when"):
                continue
            depth = entry["depth"]
            held = self.attributes.get(depth)
            if held is None or held.parts is None or held.of != "depth":
                raise fail(
                    src, f"{key}.depth", f'{depth!r} is not a depth attribute of chosen parts (of = "depth")'
                )
            fraction = _number(ev(entry["fraction"], f"{key}.fraction"), src, f"{key}.fraction", 0, 1)
            if fraction <= 0:
                raise fail(src, f"{key}.fraction", "must be above 0")
            of_layers = self.attributes.get("depth")
            if of_layers is None or abs(of_layers.scale - held.scale) > 1e-9:
                raise fail(
                    src,
                    f"{key}.depth",
                    f"{depth!r} is compared with every layer's depth: "
                    "declare the depth attribute at its scale",
                )
            stops.append(StopSpec(rule, depth, fraction))
        return tuple(stops)


def _switch(value, source: str, key: str) -> bool:
    """A ``when``: true/false, or a number (on where not 0)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int | float):
        return value != 0
    raise fail(source, key, f"must be true, false or a number, got {value!r}")


def _order(spec: ParsedPipeline) -> list[str]:
    """Passes in dependency order; a cycle is an error naming it."""
    state: dict[str, int] = {}
    order: list[str] = []

    def visit(name: str, path: tuple[str, ...]) -> None:
        mark = state.get(name)
        if mark == 2:
            return
        if mark == 1:
            cycle = path[path.index(name) :] + (name,)
            raise fail(
                spec.source,
                f"passes.{name}.inputs",
                f"cycle {' -> '.join(cycle)} (passes must form a graph without loops)",
            )
        state[name] = 1
        for target in spec.passes[name].inputs.values():
            if target in spec.passes:
                visit(target, (*path, name))
        state[name] = 2
        order.append(name)

    for name in spec.passes:
        visit(name, ())
    return order
