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

import re
from dataclasses import dataclass, field, replace
from pathlib import Path

from blueprint.errors import InputError
from blueprint.gpu.shaders import package_files
from blueprint.pipeline.bind import bind
from blueprint.pipeline.schema import (
    ATTRIBUTES,
    OPERATIONS,
    PART_ATTRIBUTES,
    Bound,
    ParsedPipeline,
    PassSpec,
    check_name,
    fail,
)
from blueprint.settings import SETTINGS_FILE_LIMIT, parse_text, read_file

PRESETS = "blueprint.pipeline:presets"

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
# stop rules a pipeline may declare, with their keys
_STOP_RULES = {"reveal": ("depth", "fraction", "when")}
_UNIFORM_KEYS = ("type", "default", "min", "max")


# -- the parsed file -------------------------------------------------------------------------------
@dataclass(frozen=True)
class PipelineSpec(ParsedPipeline):
    """A parsed pipeline file. ``bind`` resolves variables and validates the whole of it."""

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
            bound = self._bound[key] = bind(self, values)
        return bound


#: The preset every picture is drawn with (``blueprint.pipeline.blueprint``).
CORE_PRESET = "blueprint"


# -- loading ---------------------------------------------------------------------------------------
def preset_names() -> list[str]:
    folder = package_files(PRESETS.split(":")[0]).joinpath(PRESETS.split(":")[1])
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
        package, folder = PRESETS.split(":")
        if name_or_path not in preset_names():
            if name_or_path == CORE_PRESET:
                # every picture is drawn by it: without it the installation is broken, not the input
                place = package_files(package).joinpath(folder)
                raise InputError(
                    f"{place}/{CORE_PRESET}.toml is missing: the installation is incomplete "
                    "(reinstall blueprint-drawings)"
                )
            raise InputError(f"unknown pipeline preset {name_or_path!r} (choose {', '.join(preset_names())})")
        text = package_files(package).joinpath(f"{folder}/{name_or_path}.toml").read_text(encoding="utf-8")
        spec = parse(text, f"preset {name_or_path}", None)
    else:
        if text_path.suffix.lower() != ".toml":
            raise InputError(f"{text_path}: a pipeline file must end in .toml")
        if not text_path.exists():
            raise InputError(f"{text_path}: no such pipeline file")
        try:
            text = read_file(text_path, SETTINGS_FILE_LIMIT, "a pipeline file").decode("utf-8")
        except UnicodeDecodeError:
            raise InputError(f"{text_path}: not UTF-8 text") from None
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


def parse(text: str, source: str, folder: Path | None) -> PipelineSpec:
    """Parse pipeline TOML; structure only (``bind`` checks values and the graph)."""
    data = parse_text(text, source, "toml")
    _only(source, "", data, _SECTIONS)
    head = _head(source, data)
    variables = _variables(source, data)
    names = _Names(source)
    attributes = _attributes(source, data, names)
    images = {}
    for name, entry in _table(source, "images", data.get("images", {})).items():
        key = f"images.{name}"
        entry = _table(source, key, entry)
        _only(source, key, entry, ("file", "format", "scale"))
        names.claim(name, key)
        images[name] = entry
    passes = {}
    for name, entry in _table(source, "passes", data.get("passes", {})).items():
        key = f"passes.{name}"
        entry = _table(source, key, entry)
        _only(source, key, entry, _PASS_KEYS)
        names.claim(name, key)
        passes[name] = _pass(source, folder, name, entry)
    settings = {k: head[k] for k in ("layers", "min_fraction", "crease_angle", "size") if k in head}
    return PipelineSpec(
        source,
        folder,
        str(head.get("name", Path(source).stem)),
        str(head.get("description", "")),
        head["output"],
        settings,
        variables,
        attributes,
        images,
        passes,
        _stops(source, data),
    )


class _Names:
    """The names of a file's attributes, images and passes: each names one thing."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.taken: dict[str, str] = {}

    def claim(self, name: str, key: str) -> None:
        check_name(self.source, key, name)
        if name in self.taken:
            raise fail(self.source, key, f"name {name!r} is already used by {self.taken[name]}")
        self.taken[name] = key


def _head(source: str, data: dict) -> dict:
    """The ``[pipeline]`` table, which names the output."""
    head = _table(source, "pipeline", data.get("pipeline", {}))
    _only(source, "pipeline", head, _PIPELINE_KEYS)
    if "output" not in head:
        raise fail(source, "pipeline.output", "missing: name the pass, attribute or image that is the result")
    if not isinstance(head["output"], str):
        raise fail(source, "pipeline.output", "must be a name")
    return head


def _variables(source: str, data: dict) -> dict:
    """The ``[variables]``: plain values, which expressions elsewhere read."""
    variables = _table(source, "variables", data.get("variables", {}))
    for k, v in variables.items():
        check_name(source, f"variables.{k}", k)
        if not isinstance(v, int | float | bool | str) or (isinstance(v, str) and v.lstrip().startswith("=")):
            raise fail(source, f"variables.{k}", "must be a number, true/false or a string")
    return dict(variables)


def _attributes(source: str, data: dict, names: _Names) -> dict[str, dict]:
    """The ``[attributes]``: of every layer by their own name, or of chosen parts (``of`` and
    ``parts``)."""
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
            check_name(source, f"{key}.parts", entry["parts"])
        elif name not in ATTRIBUTES:
            raise fail(source, key, f"unknown attribute (choose {', '.join(ATTRIBUTES)})")
        names.claim(name, key)
        attributes[name] = entry
    return attributes


def _pass(source: str, folder: Path | None, name: str, entry: dict) -> PassSpec:
    """A ``[passes.NAME]`` table: an operation of the library or a shader of the user's own,
    its inputs, parameters and switches as written (``bind`` evaluates them)."""
    key = f"passes.{name}"
    if ("op" in entry) == ("shader" in entry):
        raise fail(source, key, "give either op (an operation of the library) or shader (a file of your own)")
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
        raise fail(source, f"{key}.op", f"must be a name (choose {', '.join(OPERATIONS)})")
    inputs = _table(source, f"{key}.inputs", entry.get("inputs", {}))
    for k, v in inputs.items():
        if not isinstance(v, str):
            raise fail(source, f"{key}.inputs.{k}", "must name an attribute, image or pass")
    uniforms = _table(source, f"{key}.uniforms", entry.get("uniforms", {}))
    for k, v in uniforms.items():
        _only(source, f"{key}.uniforms.{k}", _table(source, f"{key}.uniforms.{k}", v), _UNIFORM_KEYS)
    return PassSpec(
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


def _stops(source: str, data: dict) -> dict[str, dict]:
    """The ``[stop.RULE]`` tables, each with the keys its rule needs."""
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
    return stops


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
