"""Pipeline files (TOML): parsing and validation, all of it before any GPU work.

A pipeline file declares the G-buffer attributes to render, image inputs, passes and the final
output::

    [pipeline]
    name = "dilated-edges"
    output = "wide"              # the pass (or attribute, or image) that is the result
    layers = 1                   # depth layers to peel at most (0: all); default 8 if any pass
                                 # runs per layer, else 1
    # min_fraction = 0.0, crease_angle = 30.0, size = [1024, 1024]

    [variables]                  # named values a run may override (--set NAME=VALUE)
    width = 1.5

    [attributes]                 # each: format (default below) and scale of the output size
    normal = { scale = 1 }
    depth = {}

    [images.photo]               # an image or a video; file relative to this file, or given
    file = "photo.png"           # at run time (--image photo=PATH, or the positional argument)

    [passes.edges]
    op = "roberts"               # an operation of the library (blueprint ops), or
    # shader = "mine.frag"       # a shader of your own beside this file, with [uniforms]
    inputs = { source = "normal" }
    params = { threshold = 0.2 }
    format = "r8"                # default: the operation's
    scale = 1                    # default: the first input's (1 for downsample, composite)
    per_layer = false            # true: run once for every peeled depth layer

    [passes.wide]
    op = "dilate"
    inputs = { source = "edges" }
    params = { radius = "= width" }   # "= expression" over [variables]: + - * / ( ) min max
    when = "= wide"              # the pass exists only where this is true (or a non-zero number)

Parts chosen at run time (``Executor.run(parts={"mine": flags})``) have G-buffer attributes of
their own: their front surface alone, captured once before the peel and readable all frame::

    [attributes]
    mine_depth = { of = "depth", parts = "mine" }    # of: depth, normal or ids

A per-layer pass with ``accumulate = true`` writes every layer into one target, cleared once a
frame (its shader discards where it has nothing to add). Stop rules beyond ``layers`` and
``min_fraction``::

    [stop.reveal]                # depth masking: stop once this fraction of the parts whose
    depth = "mine_depth"         # front depth this is is uncovered
    fraction = "= reveal"
    when = "= reveal"

Errors name the file, the key and the allowed values, in one line.
"""

from __future__ import annotations

import ast
import math
import operator
import re
import tomllib
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

from blueprint.errors import InputError, ShaderError
from blueprint.gpu.shaders import preprocess
from blueprint.gpu.targets import FORMATS
from blueprint.ops import OPS, IntParam, Op, Param

# name: (default format, allowed formats, from the renderer's G-buffer, what it holds)
ATTRIBUTES: dict[str, tuple[str, tuple[str, ...], bool, str]] = {
    "depth": ("depth", ("depth",), True, "window depth in [0, 1]; 1 where there is no surface"),
    "normal": ("rgba16f", ("rgba16f",), True, "eye-space unit normal facing the viewer, w = 1; 0 where none"),
    "ids": ("rg32i", ("rg32i",), True, "(triangle + 1, part + 1); 0 where none"),
    "linear_depth": ("r32f", ("r32f",), False, "distance along the view axis; 0 where none"),
    "position": ("rgba32f", ("rgba32f", "rgba16f"), False, "model-space position, w = 1; 0 where none"),
    "triangle": ("r32i", ("r32i",), False, "face index in the model; -1 where none"),
    "part": ("r32i", ("r32i",), False, "part index; -1 where none"),
    "base_color": ("rgba8", ("rgba8", "rgba16f"), False, "a colour per part, alpha 1; 0 where none"),
    "uv": (
        "rg32f",
        ("rg32f", "rgba16f", "rgba32f"),
        False,
        "box projection of the model bounds; 0 where none",
    ),
    "layer": ("r32i", ("r32i",), False, "index of the depth layer; -1 where none"),
}
IMAGE_FORMATS = ("rgba8", "r8", "rgba16f", "rgba32f", "r32f")
VIDEO_SUFFIXES = (".mp4", ".mov", ".avi", ".mkv", ".webm", ".gif", ".m4v")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")
# every target format a pass may write, with what its shader samples it as
ALL_FORMATS = (*FORMATS, "depth")
UNIFORM_TYPES = {"float": 1, "int": 1, "bool": 1, "vec2": 2, "vec3": 3, "vec4": 4}
MAX_SCALE = 8.0
MAX_LAYERS = 256
PRESETS = "blueprint.pipeline:presets"

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_SECTIONS = ("pipeline", "variables", "attributes", "images", "passes", "stop")
_PIPELINE_KEYS = ("name", "description", "output", "layers", "min_fraction", "crease_angle", "size")
_PASS_KEYS = (
    "op",
    "shader",
    "inputs",
    "params",
    "uniforms",
    "format",
    "scale",
    "per_layer",
    "accumulate",
    "when",
)
# attributes of the G-buffer that may be captured for chosen parts alone (``of`` and ``parts``)
PART_ATTRIBUTES = ("depth", "normal", "ids")
# stop rules a pipeline may declare, with their keys
_STOP_RULES = {"reveal": ("depth", "fraction", "when")}
_UNIFORM_KEYS = ("type", "default", "min", "max")


def fail(source: str, key: str, message: str) -> InputError:
    """The one error of a pipeline file: file, key, message (with the allowed values)."""
    return InputError(f"{source}: {key}: {message}")


def is_int_format(fmt: str) -> bool:
    return fmt.endswith("i")


def channels(fmt: str) -> int:
    return 1 if fmt == "depth" else FORMATS[fmt][0]


# -- expressions -----------------------------------------------------------------------------------
_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}
_CALLS = {"min": min, "max": max}


def evaluate(value, variables: dict, source: str, key: str):
    """``value`` itself, or for a string ``"= expr"`` the expression's value over ``variables``."""
    if not (isinstance(value, str) and value.lstrip().startswith("=")):
        return value
    text = value.lstrip()[1:].strip()
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        raise fail(source, key, f"cannot read the expression {text!r}") from None

    def walk(node):
        if isinstance(node, ast.Expression):
            return walk(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float | bool | str):
            return node.value
        if isinstance(node, ast.Name):
            if node.id not in variables:
                known = ", ".join(variables) or "none declared"
                raise fail(source, key, f"unknown variable {node.id!r} (choose {known})")
            return variables[node.id]
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            a, b = walk(node.left), walk(node.right)
            if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in (a, b)):
                raise fail(source, key, f"arithmetic on a non-number in {text!r}")
            try:
                return _BINARY[type(node.op)](a, b)
            except ZeroDivisionError:
                raise fail(source, key, f"division by zero in {text!r}") from None
        if isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            return _UNARY[type(node.op)](walk(node.operand))
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in _CALLS
            and node.args
            and not node.keywords
        ):
            return _CALLS[node.func.id](*(walk(a) for a in node.args))
        raise fail(source, key, f"{text!r}: expressions take numbers, variables, + - * / ( ), min and max")

    return walk(tree)


# -- user shaders ----------------------------------------------------------------------------------
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


# -- the parsed file -------------------------------------------------------------------------------
@dataclass(frozen=True)
class PassSpec:
    name: str
    op: str | None
    shader: Path | None
    inputs: dict[str, str]
    params: dict
    uniforms: dict[str, dict]
    format: object
    scale: object
    per_layer: object
    accumulate: object = False
    when: object = True


@dataclass(frozen=True)
class PipelineSpec:
    """A parsed pipeline file. ``bind`` resolves variables and validates the whole of it."""

    source: str
    folder: Path | None
    name: str
    description: str
    output: str
    settings: dict
    variables: dict
    attributes: dict[str, dict]
    images: dict[str, dict]
    passes: dict[str, PassSpec]
    stops: dict[str, dict] = field(default_factory=dict)
    _bound: dict = field(default_factory=dict, repr=False, compare=False)

    def bind(self, variables: dict | None = None) -> Bound:
        """The pipeline with ``variables`` (overriding the declared ones) substituted, checked
        completely: names, formats, scales, parameters and the graph."""
        values = dict(self.variables)
        for name, value in (variables or {}).items():
            if name not in self.variables:
                known = ", ".join(self.variables) or "none declared"
                raise fail(self.source, f"variables.{name}", f"unknown variable (choose {known})")
            values[name] = value
        key = tuple(sorted((k, repr(v)) for k, v in values.items()))
        bound = self._bound.get(key)
        if bound is None:
            bound = self._bound[key] = _bind(self, values)
        return bound


@dataclass(frozen=True)
class AttributeSpec:
    """``of``: the G-buffer attribute it holds (its own name but for part attributes);
    ``parts``: the run-time part set whose front surface alone it holds, or None (every layer)."""

    name: str
    format: str
    scale: float
    of: str = ""
    parts: str | None = None


@dataclass(frozen=True)
class ImageSpec:
    name: str
    file: Path | None
    format: str
    scale: float

    @property
    def video(self) -> bool:
        return self.file is not None and self.file.suffix.lower() in VIDEO_SUFFIXES


@dataclass(frozen=True)
class BoundPass:
    name: str
    op: Op
    inputs: dict[str, str]
    uniforms: dict
    format: str
    scale: float
    per_layer: bool
    user: Path | None = None
    accumulate: bool = False

    @property
    def kind(self) -> str:
        return self.op.kind

    @property
    def stacks(self) -> tuple[str, ...]:
        return self.op.stacks


@dataclass(frozen=True)
class Bound:
    """A pipeline with every value concrete and checked; the graph module plans it. ``passes``
    are in dependency order (every pass after the passes it reads)."""

    source: str
    name: str
    output: str
    layers: int | None
    min_fraction: float
    crease_angle: float
    size: tuple[int, int] | None
    attributes: dict[str, AttributeSpec]
    images: dict[str, ImageSpec]
    passes: dict[str, BoundPass]
    variables: dict
    stops: tuple[StopSpec, ...] = ()

    def format_of(self, name: str) -> str:
        for table in (self.attributes, self.images, self.passes):
            if name in table:
                return table[name].format
        raise KeyError(name)

    def scale_of(self, name: str) -> float:
        for table in (self.attributes, self.images, self.passes):
            if name in table:
                return table[name].scale
        raise KeyError(name)


@dataclass(frozen=True)
class StopSpec:
    """A declared stop rule: ``rule`` (``reveal``), the part attribute it reads, its fraction."""

    rule: str
    depth: str
    fraction: float


# -- loading ---------------------------------------------------------------------------------------
def preset_names() -> list[str]:
    folder = resources.files(PRESETS.split(":")[0]).joinpath(PRESETS.split(":")[1])
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def load_pipeline(name_or_path) -> PipelineSpec:
    """A pipeline file, or a preset by name (``blueprint``, ``edges-sobel``, ...), parsed and
    validated with its declared variables."""
    text_path = Path(name_or_path)
    if (
        isinstance(name_or_path, str)
        and not name_or_path.endswith(".toml")
        and _NAME_OR_DASH.match(name_or_path)
    ):
        if name_or_path not in preset_names():
            raise InputError(f"unknown pipeline preset {name_or_path!r} (choose {', '.join(preset_names())})")
        package, folder = PRESETS.split(":")
        text = resources.files(package).joinpath(f"{folder}/{name_or_path}.toml").read_text(encoding="utf-8")
        spec = parse(text, f"preset {name_or_path}", None)
    else:
        if text_path.suffix.lower() != ".toml":
            raise InputError(f"{text_path}: a pipeline file must end in .toml")
        if not text_path.is_file():
            raise InputError(f"{text_path}: no such pipeline file")
        try:
            text = text_path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"{text_path}: cannot read ({exc})") from None
        spec = parse(text, str(text_path), text_path.resolve().parent)
    spec.bind()
    return spec


_NAME_OR_DASH = re.compile(r"^[A-Za-z0-9_-]+$")


def _table(source: str, key: str, value) -> dict:
    if not isinstance(value, dict):
        raise fail(source, key, f"must be a table, got {type(value).__name__}")
    return value


def _only(source: str, key: str, table: dict, allowed) -> None:
    for k in table:
        if k not in allowed:
            raise fail(source, f"{key}.{k}" if key else k, f"unknown key (choose {', '.join(allowed)})")


def _name(source: str, key: str, name: str) -> str:
    if not _NAME.match(name):
        raise fail(source, key, "names are letters, digits and _, not starting with a digit")
    return name


def parse(text: str, source: str, folder: Path | None) -> PipelineSpec:
    """Parse pipeline TOML; structure only (``bind`` checks values and the graph)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: not valid TOML ({exc})") from None
    _only(source, "", data, _SECTIONS)
    head = _table(source, "pipeline", data.get("pipeline", {}))
    _only(source, "pipeline", head, _PIPELINE_KEYS)
    if "output" not in head:
        raise fail(source, "pipeline.output", "missing: name the pass, attribute or image that is the result")
    if not isinstance(head["output"], str):
        raise fail(source, "pipeline.output", "must be a name")
    variables = _table(source, "variables", data.get("variables", {}))
    for k, v in variables.items():
        _name(source, f"variables.{k}", k)
        if not isinstance(v, int | float | bool | str) or (isinstance(v, str) and v.lstrip().startswith("=")):
            raise fail(source, f"variables.{k}", "must be a number, true/false or a string")
    names: dict[str, str] = {}

    def claim(name: str, key: str) -> None:
        _name(source, key, name)
        if name in names:
            raise fail(source, key, f"name {name!r} is already used by {names[name]}")
        names[name] = key

    attributes = {}
    for name, entry in _table(source, "attributes", data.get("attributes", {})).items():
        key = f"attributes.{name}"
        entry = _table(source, key, entry)
        _only(source, key, entry, ("format", "scale", "of", "parts"))
        if ("of" in entry) != ("parts" in entry):
            raise fail(source, key, "an attribute of chosen parts gives both of (what) and parts (which)")
        if "of" in entry:
            if entry["of"] not in PART_ATTRIBUTES:
                raise fail(source, f"{key}.of", f"must be one of {', '.join(PART_ATTRIBUTES)}")
            if not isinstance(entry["parts"], str):
                raise fail(source, f"{key}.parts", "must name a set of parts given at run time")
            _name(source, f"{key}.parts", entry["parts"])
        elif name not in ATTRIBUTES:
            raise fail(source, key, f"unknown attribute (choose {', '.join(ATTRIBUTES)})")
        claim(name, key)
        attributes[name] = entry
    images = {}
    for name, entry in _table(source, "images", data.get("images", {})).items():
        key = f"images.{name}"
        entry = _table(source, key, entry)
        _only(source, key, entry, ("file", "format", "scale"))
        claim(name, key)
        images[name] = entry
    passes = {}
    for name, entry in _table(source, "passes", data.get("passes", {})).items():
        key = f"passes.{name}"
        entry = _table(source, key, entry)
        _only(source, key, entry, _PASS_KEYS)
        claim(name, key)
        if ("op" in entry) == ("shader" in entry):
            raise fail(
                source, key, "give either op (an operation of the library) or shader (a file of your own)"
            )
        if "op" in entry and "uniforms" in entry:
            raise fail(source, f"{key}.uniforms", "only a pass with its own shader declares uniforms")
        shader = None
        if "shader" in entry:
            if not isinstance(entry["shader"], str):
                raise fail(source, f"{key}.shader", "must be a file name")
            shader = Path(entry["shader"])
            if not shader.is_absolute():
                shader = (folder or Path.cwd()) / shader
        op = entry.get("op")
        if op is not None and not isinstance(op, str):
            raise fail(source, f"{key}.op", f"must be a name (choose {', '.join(OPS)})")
        inputs = _table(source, f"{key}.inputs", entry.get("inputs", {}))
        for k, v in inputs.items():
            if not isinstance(v, str):
                raise fail(source, f"{key}.inputs.{k}", "must name an attribute, image or pass")
        uniforms = _table(source, f"{key}.uniforms", entry.get("uniforms", {}))
        for k, v in uniforms.items():
            _only(source, f"{key}.uniforms.{k}", _table(source, f"{key}.uniforms.{k}", v), _UNIFORM_KEYS)
        passes[name] = PassSpec(
            name,
            op,
            shader,
            dict(inputs),
            dict(_table(source, f"{key}.params", entry.get("params", {}))),
            dict(uniforms),
            entry.get("format"),
            entry.get("scale"),
            entry.get("per_layer", False),
            entry.get("accumulate", False),
            entry.get("when", True),
        )
    stops = {}
    for rule, entry in _table(source, "stop", data.get("stop", {})).items():
        key = f"stop.{rule}"
        if rule not in _STOP_RULES:
            raise fail(source, key, f"unknown stop rule (choose {', '.join(_STOP_RULES)})")
        entry = _table(source, key, entry)
        _only(source, key, entry, _STOP_RULES[rule])
        for needed in ("depth", "fraction"):
            if needed not in entry:
                raise fail(source, f"{key}.{needed}", "missing")
        stops[rule] = dict(entry)
    settings = {k: head[k] for k in ("layers", "min_fraction", "crease_angle", "size") if k in head}
    return PipelineSpec(
        source,
        folder,
        str(head.get("name", Path(source).stem)),
        str(head.get("description", "")),
        head["output"],
        settings,
        dict(variables),
        attributes,
        images,
        passes,
        stops,
    )


# -- binding ---------------------------------------------------------------------------------------
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


def _user_op(spec: PipelineSpec, p: PassSpec, values: dict) -> Op:
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
        _name(spec.source, ukey, name)
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


def _check_params(source: str, key: str, op: Op, raw: dict, variables: dict) -> dict:
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


def _bind(spec: PipelineSpec, values: dict) -> Bound:
    src = spec.source

    def ev(value, key):
        return evaluate(value, values, src, key)

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
    attributes = {}
    for name, entry in spec.attributes.items():
        key = f"attributes.{name}"
        of = entry.get("of", name)
        default, allowed, _, _ = ATTRIBUTES[of]
        fmt = _format(ev(entry.get("format", default), f"{key}.format"), src, f"{key}.format", allowed)
        scale = _scale(ev(entry.get("scale", 1), f"{key}.scale"), src, f"{key}.scale")
        attributes[name] = AttributeSpec(name, fmt, scale, of, entry.get("parts"))
    images = {}
    for name, entry in spec.images.items():
        key = f"images.{name}"
        fmt = _format(ev(entry.get("format", "rgba8"), f"{key}.format"), src, f"{key}.format", IMAGE_FORMATS)
        file = ev(entry.get("file"), f"{key}.file")
        path = None
        if file is not None:
            if not isinstance(file, str):
                raise fail(src, f"{key}.file", "must be a file name")
            path = Path(file)
            if not path.is_absolute():
                path = (spec.folder or Path.cwd()) / path
            if path.suffix.lower() not in (*IMAGE_SUFFIXES, *VIDEO_SUFFIXES):
                raise fail(
                    src,
                    f"{key}.file",
                    f"unknown kind of file (choose {', '.join(IMAGE_SUFFIXES + VIDEO_SUFFIXES)})",
                )
        images[name] = ImageSpec(
            name, path, fmt, _scale(ev(entry.get("scale", 1), f"{key}.scale"), src, f"{key}.scale")
        )

    passes: dict[str, BoundPass] = {}
    available = [*attributes, *images, *spec.passes]
    active = {
        n for n, p in spec.passes.items() if _switch(ev(p.when, f"passes.{n}.when"), src, f"passes.{n}.when")
    }
    # formats and scales of passes depend on their inputs: settle them in dependency order
    order = _order(spec)
    for name in order:
        if name not in active:
            continue
        p = spec.passes[name]
        key = f"passes.{name}"
        if p.op is not None:
            if p.op not in OPS:
                raise fail(src, f"{key}.op", f"unknown operation {p.op!r} (choose {', '.join(OPS)})")
            op = OPS[p.op]
        else:
            op = _user_op(spec, p, values)
        for input_name in p.inputs:
            if input_name not in op.inputs:
                raise fail(
                    src,
                    f"{key}.inputs.{input_name}",
                    f"{op.name} has no input {input_name!r} (choose {', '.join(op.inputs)})",
                )
        wiring = {}
        for input_name, target in p.inputs.items():
            if target in spec.passes and target not in active:
                if input_name in op.optional:
                    continue  # an optional input of a pass that is off here is left unwired
                raise fail(src, f"{key}.inputs.{input_name}", f"{target!r} is off here (its when is false)")
            wiring[input_name] = target
        p = replace(p, inputs=wiring)
        for input_name in op.inputs:
            if input_name not in p.inputs and input_name not in op.optional:
                raise fail(
                    src,
                    f"{key}.inputs",
                    f"missing input {input_name!r} of {op.name} (it needs {', '.join(op.inputs)})",
                )
        per_layer = ev(p.per_layer, f"{key}.per_layer")
        if not isinstance(per_layer, bool):
            raise fail(src, f"{key}.per_layer", f"must be true or false, got {per_layer!r}")
        accumulate = ev(p.accumulate, f"{key}.accumulate")
        if not isinstance(accumulate, bool):
            raise fail(src, f"{key}.accumulate", f"must be true or false, got {accumulate!r}")
        if accumulate and not per_layer:
            raise fail(src, f"{key}.accumulate", "only a per-layer pass accumulates its layers")
        stacks = op.stacks
        resample = op.resample
        first_format = None
        first_scale = None
        for input_name, target in p.inputs.items():
            ikey = f"{key}.inputs.{input_name}"
            if target not in available:
                raise fail(
                    src,
                    ikey,
                    f"unknown name {target!r} (choose {', '.join(n for n in available if n != name)})",
                )
            if target in spec.attributes and target not in attributes:
                raise fail(src, ikey, f"attribute {target!r} is not declared")
            fmt = (attributes.get(target) or images.get(target) or passes[target]).format
            scale = (attributes.get(target) or images.get(target) or passes[target]).scale
            declared = op.inputs[input_name]
            if input_name in stacks:
                if target not in passes or not passes[target].per_layer:
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
            if not _accepts(declared, fmt):
                raise fail(
                    src, ikey, f"{target!r} is {fmt}, but {op.name}.{input_name} needs {_describe(declared)}"
                )
            if first_format is None:
                first_format, first_scale = fmt, scale
        if p.scale is None:
            scale = 1.0 if resample else first_scale if first_scale is not None else 1.0
        else:
            scale = _scale(ev(p.scale, f"{key}.scale"), src, f"{key}.scale")
        for input_name, target in p.inputs.items():
            in_scale = (attributes.get(target) or images.get(target) or passes[target]).scale
            ikey = f"{key}.inputs.{input_name}"
            if input_name in resample:
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
        default = op.output
        if default == "same":
            default = "r32f" if first_format == "depth" else first_format
        kind_int = is_int_format(default)
        allowed = [
            f
            for f in FORMATS
            if is_int_format(f) == kind_int and (op.kind != "composite" or channels(f) == 4)
        ]
        fmt = (
            default
            if p.format is None
            else _format(ev(p.format, f"{key}.format"), src, f"{key}.format", allowed)
        )
        uniforms = _check_params(src, f"{key}.params", op, p.params, values)
        passes[name] = BoundPass(
            name, op, dict(p.inputs), uniforms, fmt, scale, per_layer, p.shader, accumulate
        )
    output = spec.output
    if output not in available:
        raise fail(src, "pipeline.output", f"unknown name {output!r} (choose {', '.join(available)})")
    if output in spec.passes and output not in active:
        raise fail(src, "pipeline.output", f"{output!r} is off here (its when is false)")
    stops = []
    for rule, entry in spec.stops.items():
        key = f"stop.{rule}"
        if not _switch(ev(entry.get("when", True), f"{key}.when"), src, f"{key}.when"):
            continue
        depth = entry["depth"]
        held = attributes.get(depth)
        if held is None or held.parts is None or held.of != "depth":
            raise fail(
                src, f"{key}.depth", f'{depth!r} is not a depth attribute of chosen parts (of = "depth")'
            )
        fraction = _number(ev(entry["fraction"], f"{key}.fraction"), src, f"{key}.fraction", 0, 1)
        if fraction <= 0:
            raise fail(src, f"{key}.fraction", "must be above 0")
        stops.append(StopSpec(rule, depth, fraction))
    bound = Bound(
        src,
        spec.name,
        output,
        layers,
        min_fraction,
        crease,
        size,
        attributes,
        images,
        passes,
        values,
        tuple(stops),
    )
    from blueprint.pipeline.graph import plan

    plan(bound)
    return bound


def _switch(value, source: str, key: str) -> bool:
    """A ``when``: true/false, or a number (on where not 0)."""
    if isinstance(value, bool):
        return value
    if isinstance(value, int | float):
        return value != 0
    raise fail(source, key, f"must be true, false or a number, got {value!r}")


def _order(spec: PipelineSpec) -> list[str]:
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


def with_file(spec: PipelineSpec, image: str, path: Path) -> PipelineSpec:
    """The spec with image ``image``'s file set to ``path`` (run-time inputs)."""
    if image not in spec.images:
        raise InputError(
            f"{spec.source}: images.{image}: no such image "
            f"(choose {', '.join(spec.images) or 'none declared'})"
        )
    images = dict(spec.images)
    images[image] = {**images[image], "file": str(Path(path).resolve())}
    return replace(spec, images=images, _bound={})
