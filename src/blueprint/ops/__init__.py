"""Image-space operations: one fragment shader and one descriptor each.

A descriptor names the shader, its input textures with their formats, its output format and
its parameters with ranges; ``Op.uniforms`` validates values before any GPU work.
"""

from __future__ import annotations

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
    """An image-space pass over G-buffer attributes or earlier results."""

    name: str
    shader: str
    inputs: dict[str, str]
    output: str
    params: tuple[Param, ...] = ()
    doc: str = ""
    compute: str | None = None

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
    ),
    doc="edge intensity from coverage, part-ID, normal and depth discontinuities",
    compute="blueprint.ops:glsl/edges.comp",
)

DILATE = Op(
    name="dilate",
    shader="blueprint.ops:glsl/dilate.frag",
    inputs={"source": "r8"},
    output="r8",
    params=(Param("radius", 1.0, 0.0, 16.0, "disc radius in pixels"),),
    doc="grey-scale dilation by a disc with a soft rim",
    compute="blueprint.ops:glsl/dilate.comp",
)

OPS: dict[str, Op] = {op.name: op for op in (EDGES, DILATE)}

__all__ = ["DILATE", "EDGES", "OPS", "Op", "Param"]
