"""Image-space operations: one fragment shader and one descriptor each.

A descriptor names the shader, its input textures with their formats, its output format and
its parameters with ranges; ``Op.uniforms`` validates values before any GPU work.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from blueprint.errors import InputError


@dataclass(frozen=True)
class Param:
    """A uniform of an operation, with its allowed range."""

    name: str
    default: float | bool
    minimum: float | None = None
    maximum: float | None = None
    doc: str = ""

    def check(self, op: str, value) -> float | bool:
        if isinstance(self.default, bool):
            if not isinstance(value, bool):
                raise InputError(f"{op}.{self.name} must be true or false, got {value!r}")
            return value
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise InputError(f"{op}.{self.name} must be a number, got {value!r}") from None
        low = -float("inf") if self.minimum is None else self.minimum
        high = float("inf") if self.maximum is None else self.maximum
        if not low <= number <= high:
            raise InputError(f"{op}.{self.name} must be in [{low:g}, {high:g}], got {number:g}")
        return number


@dataclass(frozen=True)
class Op:
    """An image-space pass over G-buffer attributes or earlier results.

    ``kind`` says how the executor runs it: ``single`` (one full-screen pass), ``separable``
    (a pass along x into a float scratch target, then along y) or ``composite`` (depth-sprite
    composition of a stack of layers over the style's paper, eight layers a pass). ``stacks``
    are inputs that take every depth layer of a per-layer pass; ``resample`` inputs may be an
    integer multiple of the output's size (the others must match it); ``optional`` inputs may
    be left unwired. ``derive`` turns checked parameter values into further uniforms;
    ``identity`` says when a pass does nothing, so the executor can skip it. ``support`` and
    ``reach`` say where the result can be non-zero: within ``reach(uniforms)`` pixels of where
    input ``support`` holds something (a covered pixel of a depth attribute, a non-zero one of
    a pass's result), so a software rasteriser may draw the pass over those tiles alone
    (``blueprint.pipeline.tiles``).

    What the pipeline plans by (never an op's name): ``compute_form`` says how the ``compute``
    shader runs: ``"slice"`` (one layer's slice of an r8 array from attributes, a dispatch a
    layer) or ``"array"`` (a whole array into another, a dispatch an array); ``depth_first``:
    the normal and ID inputs are read only where the depth input holds a surface, so a layer's
    stale ones need no clearing; ``face_ids(uniforms)``: the pass reads face IDs, which the
    capture must then track; ``in_place(uniforms)``: a per-layer pass reads its layer's depth,
    normal and IDs alone, so it may read them where a capture holds them (the pipeline's in-place
    forms of the op: a k-buffer's surfaces, an A-buffer's lists) instead of from the G-buffer.
    What lines drawn into its result beside it (a frame's smooth contours) take from it:
    ``widens(uniforms)``, (pixels added to a line's width, the share of the width hidden
    layers' lines keep) of a pass that widens its input's lines; ``hidden_ink(uniforms)``, the
    share of ink hidden layers' lines get from a pass that draws lines.
    """

    name: str
    shader: str
    inputs: dict[str, str]
    output: str
    params: tuple[Param, ...] = ()
    doc: str = ""
    compute: str | None = None
    # boolean parameters compiled in as defines (NAME in capitals) instead of set as uniforms:
    # a software rasteriser runs a branch a uniform turns off on every pixel all the same
    switches: tuple[str, ...] = ()
    kind: str = "single"
    stacks: tuple[str, ...] = ()
    resample: tuple[str, ...] = ()
    optional: tuple[str, ...] = ()
    derive: Callable[[dict], dict] | None = None
    identity: Callable[[dict], bool] | None = None
    support: str | None = None
    reach: Callable[[dict], int] | None = None
    compute_form: str | None = None
    depth_first: bool = False
    face_ids: Callable[[dict], bool] | None = None
    in_place: Callable[[dict], bool] | None = None
    widens: Callable[[dict], tuple[float, float]] | None = None
    hidden_ink: Callable[[dict], float] | None = None

    def defines(self, uniforms: dict[str, float | bool]) -> dict[str, bool]:
        """Compile-time defines of checked uniform values (see ``switches``)."""
        return {name.upper(): bool(uniforms[f"u_{name}"]) for name in self.switches}

    def uniforms(self, **values) -> dict[str, float | bool]:
        """Validated parameter values, defaults filled in, keyed by uniform name (``u_<name>``)."""
        known = {p.name: p for p in self.params}
        unknown = set(values) - set(known)
        if unknown:
            raise InputError(
                f"{self.name}: unknown parameter {sorted(unknown)[0]!r} (choose {', '.join(known) or 'none'})"
            )
        return {f"u_{p.name}": p.check(self.name, values.get(p.name, p.default)) for p in self.params}


EDGES = Op(
    name="edges",
    shader="blueprint.ops:glsl/edges.frag",
    inputs={"depth": "depth", "normal": "rgba16f", "ids": "rg32i"},
    output="r8",
    params=(
        Param("depth_threshold", 4.0, 0.1, 1000.0, "depth jump, in pixel footprints, of a silhouette"),
        Param("part_edges", True, doc="draw boundaries between parts"),
        Param(
            "id_silhouettes",
            False,
            doc="also mark neighbours whose triangles share no vertex (paper 002); needs face IDs",
        ),
        Param(
            "hidden_ink", 1.0, 0.0, 1.0, "ink of the lines of layers >= 1 of a per-layer pass over layer 0's"
        ),
        Param(
            "smooth_contours",
            False,
            doc="leave the outline of smooth faces to contour lines drawn with the run; needs face IDs",
        ),
    ),
    doc="edge intensity from coverage, part-ID, normal and depth discontinuities",
    compute="blueprint.ops:glsl/edges.comp",
    switches=("id_silhouettes", "smooth_contours"),
    # an empty pixel beside a covered one is marked too (both sides of a border)
    support="depth",
    reach=lambda u: 1,
    compute_form="slice",
    depth_first=True,
    # triangle-ID silhouettes compare the faces' corners, which no in-place form reads; the
    # contoured faces are looked up by face
    face_ids=lambda u: bool(u["u_id_silhouettes"]) or bool(u["u_smooth_contours"]),
    in_place=lambda u: not u["u_id_silhouettes"],
    hidden_ink=lambda u: float(u["u_hidden_ink"]),
)

DILATE = Op(
    name="dilate",
    shader="blueprint.ops:glsl/dilate.frag",
    inputs={"source": "r8"},
    output="r8",
    params=(
        Param("radius", 1.0, 0.0, 16.0, "disc radius in pixels (of layer 0's lines in a per-layer pass)"),
        Param(
            "hidden_width",
            1.0,
            0.05,
            1.0,
            "width of the lines of layers >= 1 of a per-layer pass over layer 0's; below the "
            "edges' own width they keep that share of their ink",
        ),
    ),
    doc="grey-scale dilation by a disc with a soft rim; hidden layers' lines narrower",
    compute="blueprint.ops:glsl/dilate.comp",
    identity=lambda u: u["u_radius"] <= 0.0 and u["u_hidden_width"] >= 1.0,
    support="source",
    reach=lambda u: math.ceil(u["u_radius"]),
    compute_form="array",
    widens=lambda u: (float(u["u_radius"]), float(u["u_hidden_width"])),
)

OPS: dict[str, Op] = {op.name: op for op in (EDGES, DILATE)}

# -- the pipeline operation library (blueprint.pipeline) ------------------------------------------
# Input formats are a format name ("r8": that kind of texture with at least its channels),
# "float" (any non-integer target, depth included), "int" (an integer target) or "depth" (a depth
# attribute only). An output of "same" takes the first input's format.


@dataclass(frozen=True)
class IntParam(Param):
    """An integer uniform with a range."""

    def check(self, op: str, value) -> int:
        if isinstance(value, bool) or not isinstance(value, int | float) or int(value) != value:
            raise InputError(f"{op}.{self.name} must be a whole number, got {value!r}")
        super().check(op, value)
        return int(value)


@dataclass(frozen=True)
class ChoiceParam(Param):
    """One of a few names; the uniform gets the index of the choice."""

    choices: tuple[str, ...] = ()

    def check(self, op: str, value) -> int:
        if value not in self.choices:
            raise InputError(f"{op}.{self.name} must be one of {', '.join(self.choices)}, got {value!r}")
        return self.choices.index(value)


def _glsl(name: str) -> str:
    return f"blueprint.ops:glsl/{name}.frag"


def _light(values: dict) -> dict:
    az, el = math.radians(values["u_azimuth"]), math.radians(values["u_elevation"])
    return {"u_light": (math.cos(el) * math.sin(az), math.sin(el), math.cos(el) * math.cos(az))}


def _gaussian(values: dict) -> dict:
    sigma = values["u_sigma"]
    radius = min(BLUR_MAX_RADIUS, math.ceil(3.0 * sigma))
    weights = [math.exp(-(i * i) / (2.0 * sigma * sigma)) for i in range(radius + 1)]
    total = weights[0] + 2.0 * sum(weights[1:])
    padded = [w / total for w in weights] + [0.0] * (BLUR_MAX_RADIUS + 1 - len(weights))
    return {"u_radius": radius, "u_weights": tuple(padded)}


BLUR_MAX_RADIUS = 48
_EDGE_PARAMS = (
    Param(
        "threshold", 0.0, 0.0, 100.0, "0: the gradient magnitude; above 0: 1 where the magnitude exceeds it"
    ),
    IntParam("channels", 3, 1, 4, "channels that take part (3: the xyz of a normal)"),
    Param("invert", False, doc="dark edges on white (1 - value), as the paper draws them"),
)
_LIGHT_PARAMS = (
    Param("azimuth", -30.0, -180.0, 180.0, "light direction in eye space, degrees right of the view axis"),
    Param("elevation", 40.0, -90.0, 90.0, "light direction in eye space, degrees above the horizon"),
    Param("ambient", 0.2, 0.0, 1.0, "light that reaches every surface"),
    Param("background", 0.0, 0.0, 1.0, "grey where there is no surface (0: transparent)"),
)

ROBERTS = Op(
    name="roberts",
    shader=_glsl("roberts"),
    inputs={"source": "float"},
    output="r8",
    params=_EDGE_PARAMS,
    doc="Roberts cross: |f(x,y) - f(x+1,y+1)| + |f(x+1,y) - f(x,y+1)| over the chosen channels",
)
SOBEL = Op(
    name="sobel",
    shader=_glsl("sobel"),
    inputs={"source": "float"},
    output="r8",
    params=_EDGE_PARAMS,
    doc="Sobel gradient magnitude / 4 (a unit step gives 1) over the chosen channels",
)
ERODE = Op(
    name="erode",
    shader=_glsl("erode"),
    inputs={"source": "r8"},
    output="r8",
    params=(Param("radius", 1.0, 0.0, 16.0, "disc radius in pixels"),),
    doc="grey-scale erosion by a disc with a soft rim (the dual of dilate)",
    identity=lambda v: v["u_radius"] <= 0.0,
)
BLUR = Op(
    name="blur",
    shader=_glsl("blur"),
    inputs={"source": "float"},
    output="same",
    params=(
        Param("sigma", 1.0, 0.3, 16.0, "standard deviation in pixels (taps out to 3 sigma, at most 48)"),
    ),
    doc="separable Gaussian blur: a pass along x into a float scratch target, then along y",
    kind="separable",
    derive=_gaussian,
)
DOWNSAMPLE = Op(
    name="downsample",
    shader=_glsl("downsample"),
    inputs={"source": "float"},
    output="same",
    params=(
        ChoiceParam(
            "filter",
            "box",
            doc="box: mean of each block; gaussian: sigma = factor / 2",
            choices=("box", "gaussian"),
        ),
    ),
    doc="shrink by the integer ratio of input to output scale (supersampling)",
    resample=("source",),
)
THRESHOLD = Op(
    name="threshold",
    shader=_glsl("threshold"),
    inputs={"source": "float"},
    output="same",
    params=(
        Param("level", 0.5, 0.0, 1.0, "values at or above it become 1, below it 0 (alpha kept)"),
        Param("invert", False, doc="1 below the level, 0 at or above it"),
    ),
    doc="binary threshold of the colour channels",
)
INVERT = Op(
    name="invert",
    shader=_glsl("invert"),
    inputs={"source": "float"},
    output="same",
    doc="1 - value in the colour channels (alpha kept)",
)
MIX = Op(
    name="mix",
    shader=_glsl("mix"),
    inputs={"a": "float", "b": "float"},
    output="same",
    params=(
        ChoiceParam(
            "mode",
            "mix",
            doc="r(a, b): mix: b, multiply: a*b, add: a+b, subtract: a-b, min, max, screen: 1-(1-a)(1-b)",
            choices=("mix", "multiply", "add", "subtract", "min", "max", "screen"),
        ),
        Param("factor", 0.5, 0.0, 1.0, "output = a + factor * (r(a, b) - a), all four channels"),
    ),
    doc="blend two images of one size (a one-channel input counts as grey)",
)
CONTRAST = Op(
    name="contrast",
    shader=_glsl("contrast"),
    inputs={"source": "float"},
    output="same",
    params=(
        Param("contrast", 1.5, 0.0, 16.0, "gain about mid-grey"),
        Param("brightness", 0.0, -1.0, 1.0, "added after the gain"),
    ),
    doc="(value - 0.5) * contrast + 0.5 + brightness in the colour channels",
)
SCREEN = Op(
    name="screen",
    shader=_glsl("screen"),
    inputs={"source": "float"},
    output="r8",
    params=(
        Param("period", 6.0, 2.0, 64.0, "dot spacing in pixels"),
        Param("angle", 45.0, -90.0, 90.0, "screen angle in degrees"),
    ),
    doc="halftone screening: 1 where the intensity (luminance, or the only channel) exceeds a dot screen",
)
LAMBERT = Op(
    name="lambert",
    shader=_glsl("lambert"),
    inputs={"normal": "rgba16f", "depth": "depth", "color": "float"},
    output="rgba8",
    params=_LIGHT_PARAMS,
    doc="deferred Lambert shading: colour * (ambient + (1 - ambient) max(n.l, 0)), opaque",
    derive=_light,
)
TOON = Op(
    name="toon",
    shader=_glsl("toon"),
    inputs={"normal": "rgba16f", "depth": "depth", "color": "float"},
    output="rgba8",
    params=(*_LIGHT_PARAMS, IntParam("bands", 3, 2, 16, "light levels")),
    doc="deferred toon shading: the Lambert term quantised to bands levels",
    derive=_light,
)
NORMAL_EDGES = Op(
    name="normal_edges",
    shader=_glsl("normal_edges"),
    inputs={"normal": "rgba16f", "depth": "depth"},
    output="r8",
    params=(Param("angle", 30.0, 0.5, 180.0, "degrees between neighbouring normals that make an edge"),),
    doc="1 at a covered pixel whose normal turns more than angle from a covered 4-neighbour's",
    derive=lambda v: {"u_cos": math.cos(math.radians(v["u_angle"]))},
)
DEPTH_EDGES = Op(
    name="depth_edges",
    shader=_glsl("depth_edges"),
    inputs={"depth": "float"},
    output="r8",
    params=(
        Param(
            "threshold", 0.001, 0.0, 1e6, "second difference of depth (in its own units) that makes an edge"
        ),
    ),
    doc="1 where the second difference of depth along x or y exceeds threshold (planes: 0; border: 0)",
)
ID_EDGES = Op(
    name="id_edges",
    shader=_glsl("id_edges"),
    inputs={"ids": "int"},
    output="r8",
    params=(IntParam("channel", 0, 0, 1, "which channel holds the ID (ids: 0 triangle, 1 part)"),),
    doc="1 where a 4-neighbour has another ID (integer compare: exact)",
)
SHADE = Op(
    name="shade",
    shader=_glsl("shade"),
    inputs={"depth": "depth", "normal": "rgba16f"},
    output="rgba8",
    params=(Param("opacity", 1.0, 0.0, 1.0, "opacity of the shading"),),
    doc="Lambert shading (headlight and ambient) of a surface in the style's shade colour, premultiplied",
)
SHADE_LAYER = Op(
    name="shade_layer",
    shader=_glsl("shade_layer"),
    inputs={"surface": "depth", "depth": "depth"},
    output="r8",
    doc="per layer, accumulating: 1 + the layer's index where the surface lies in it "
    "(where a composite puts shading between layers)",
)
for _op in (
    ROBERTS,
    SOBEL,
    ERODE,
    BLUR,
    DOWNSAMPLE,
    THRESHOLD,
    INVERT,
    MIX,
    CONTRAST,
    SCREEN,
    LAMBERT,
    TOON,
    NORMAL_EDGES,
    DEPTH_EDGES,
    ID_EDGES,
    SHADE,
    SHADE_LAYER,
):
    OPS[_op.name] = _op
del _op

__all__ = [
    "BLUR",
    "DILATE",
    "EDGES",
    "OPS",
    "ChoiceParam",
    "IntParam",
    "Op",
    "Param",
]
