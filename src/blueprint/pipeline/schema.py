"""What a pipeline file may say and what it binds to: the attributes, formats and limits it
chooses from, the one error of a pipeline file, the parsed file and the bound pipeline. The leaf
of the package: parsing (``spec``), binding (``bind``, ``user``, ``expressions``) and planning
(``graph``) all build on it, and it on none of them."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from blueprint.compose.compositor import COMPOSITE
from blueprint.errors import InputError
from blueprint.gpu.targets import FORMATS
from blueprint.ops import OPS, Op

#: The operations a pass may name: the image-space library (``blueprint.ops.OPS``) and the
#: compositor, which compose declares beside its shader and styles.
OPERATIONS: dict[str, Op] = {**OPS, COMPOSITE.name: COMPOSITE}

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
# attributes of the G-buffer that may be captured for chosen parts alone (``of`` and ``parts``)
PART_ATTRIBUTES = ("depth", "normal", "ids")

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def fail(source: str, key: str, message: str) -> InputError:
    """The one error of a pipeline file: file, key, message (with the allowed values)."""
    return InputError(f"{source}: {key}: {message}")


def is_int_format(fmt: str) -> bool:
    return fmt.endswith("i")


def channels(fmt: str) -> int:
    return 1 if fmt == "depth" else FORMATS[fmt][0]


def check_name(source: str, key: str, name: str) -> str:
    """``name`` where it is a name a pipeline may give a thing (letters, digits and _)."""
    if not _NAME.match(name):
        raise fail(source, key, "names are letters, digits and _, not starting with a digit")
    return name


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
class ParsedPipeline:
    """What a pipeline file says, its structure checked (``spec.parse``); ``spec.PipelineSpec``
    binds it."""

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
