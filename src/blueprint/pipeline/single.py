"""One operation of the library as a pipeline of its own, for ``Executor.run_op``: the arrays
given become image inputs ``in_<name>``, the operation the pass ``out``."""

from __future__ import annotations

import numpy as np

from blueprint.pipeline.bind import check_params
from blueprint.pipeline.inputs import default_format
from blueprint.pipeline.schema import OPERATIONS, Bound, BoundPass, ImageSpec


def single_op(
    op_name: str,
    inputs: dict,
    params: dict | None,
    formats: dict[str, str] | None,
    output: str | None,
    scale: float,
) -> tuple[Bound, dict[str, list[np.ndarray]]]:
    """The bound one-pass pipeline and each input's arrays (one, or one a layer for a stack)."""
    op = OPERATIONS[op_name]
    formats = dict(formats or {})
    images, wiring, arrays = {}, {}, {}
    for key, value in inputs.items():
        layers = value if isinstance(value, list) else [value]
        fmt = formats.get(key) or default_format(layers[0])
        images[f"in_{key}"] = ImageSpec(f"in_{key}", None, fmt, 1.0)
        wiring[key] = f"in_{key}"
        arrays[key] = layers
    first_fmt = next(iter(images.values())).format
    fmt = output or op.output
    if fmt == "same":
        fmt = "r32f" if first_fmt == "depth" else first_fmt
    uniforms = check_params(f"run_op {op_name}", "params", op, params or {}, {})
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
    return bound, arrays
