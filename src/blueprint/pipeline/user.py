"""Users' own shaders as operations: their source through the package's preprocessor, the
uniforms they declare checked against the pipeline file's, their inputs typed by sampler."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from blueprint.errors import InputError, ShaderError
from blueprint.gpu.shaders import preprocess
from blueprint.ops import IntParam, Op, Param
from blueprint.pipeline.schema import UNIFORM_TYPES, ParsedPipeline, PassSpec, check_name, fail

_UNIFORM = re.compile(r"\buniform\s+(?:(?:lowp|mediump|highp)\s+)?(\w+)\s+(\w+)\s*(\[[^\]]*\])?\s*;")


def user_source(path: Path, source: str, key: str) -> tuple[str, list[str]]:
    """A user's shader with its includes expanded (next to it first, then blueprint's own
    ``gpu/glsl`` files such as ``depth.glsl``) by the package's preprocessor. Returns the text
    (without ``#version``) and the file names its ``#line`` directives number."""
    try:
        return preprocess(Path(path), version=None)
    except ShaderError as exc:
        raise fail(source, key, str(exc)) from None


def declared_uniforms(text: str) -> dict[str, str]:
    """uniform name -> GLSL type (with [N] for arrays) as declared in shader text."""
    return {m.group(2): m.group(1) + (m.group(3) or "") for m in _UNIFORM.finditer(text)}


@dataclass(frozen=True)
class VecParam(Param):
    """A vecN uniform of a user shader: N numbers, each within the range."""

    size: int = 2

    def check(self, op: str, value):
        if not isinstance(value, list | tuple) or len(value) != self.size:
            raise InputError(f"{op}.{self.name} must be a list of {self.size} numbers, got {value!r}")
        return tuple(Param(self.name, 0.0, self.minimum, self.maximum).check(op, v) for v in value)


def user_op(spec: ParsedPipeline, p: PassSpec, values: dict) -> Op:
    key = f"passes.{p.name}"
    assert p.shader is not None
    if not p.shader.is_file():
        raise fail(spec.source, f"{key}.shader", f"shader file {p.shader} not found")
    text, _ = user_source(p.shader, spec.source, f"{key}.shader")
    declared = declared_uniforms(text)
    inputs = {}
    for name in p.inputs:
        glsl = declared.get(f"u_{name}")
        if glsl not in ("sampler2D", "isampler2D"):
            raise fail(
                spec.source,
                f"{key}.inputs.{name}",
                f"{p.shader.name} declares no 'uniform sampler2D u_{name};' "
                "(or isampler2D for integer inputs)",
            )
        inputs[name] = "int" if glsl == "isampler2D" else "float"
    params = []
    for name, decl in p.uniforms.items():
        ukey = f"{key}.uniforms.{name}"
        check_name(spec.source, ukey, name)
        kind = decl.get("type", "float")
        if kind not in UNIFORM_TYPES:
            raise fail(
                spec.source, f"{ukey}.type", f"unknown type {kind!r} (choose {', '.join(UNIFORM_TYPES)})"
            )
        if declared.get(f"u_{name}") != kind:
            found = declared.get(f"u_{name}")
            raise fail(
                spec.source,
                ukey,
                f"{p.shader.name} must declare 'uniform {kind} u_{name};'"
                + (f" (it declares {found})" if found else ""),
            )
        if "default" not in decl:
            raise fail(spec.source, f"{ukey}.default", "missing: every uniform needs a default")
        low = decl.get("min")
        high = decl.get("max")
        for bound_key, bound in (("min", low), ("max", high)):
            if bound is not None and (isinstance(bound, bool) or not isinstance(bound, int | float)):
                raise fail(spec.source, f"{ukey}.{bound_key}", f"must be a number, got {bound!r}")
        if kind == "bool":
            param = Param(name, bool(decl["default"]))
        elif kind == "int":
            param = IntParam(name, decl["default"], low, high)
        elif kind == "float":
            param = Param(name, decl["default"], low, high)
        else:
            param = VecParam(name, decl["default"], low, high, size=UNIFORM_TYPES[kind])
        try:
            param.check(p.name, decl["default"])
        except InputError as exc:
            raise fail(spec.source, f"{ukey}.default", str(exc)) from None
        params.append(param)
    return Op(
        name=f"shader {p.shader.name}",
        shader=str(p.shader),
        inputs=inputs,
        output="rgba8",
        params=tuple(params),
        doc=f"user shader {p.shader}",
    )
