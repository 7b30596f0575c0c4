"""The compute form of a plan (GL 4.3): where the renderer runs image passes as compute
shaders and every per-layer pass has a compute form (a slice operation on attributes, then
operations over whole arrays) feeding only composites, the per-layer results live in r8
texture arrays of ``SLICES`` slices, one dispatch a layer (slices) or an array (batches: an
invocation a pixel of every slice holding a layer, ``u_slices``)."""

from __future__ import annotations

from dataclasses import dataclass

from blueprint.pipeline.graph import Plan

SLICES = 8


@dataclass(frozen=True)
class ArrayPlan:
    arrays: frozenset[str]  # passes whose results are arrays
    slices: tuple[str, ...]  # run a slice a layer, during the peel
    batches: tuple[str, ...]  # run over whole arrays, after the peel


def array_plan(pl: Plan) -> ArrayPlan | None:
    """The compute form of ``pl``, or None where some pass has none."""
    if not pl.per_layer:
        return None
    b = pl.bound
    arrays: set[str] = set()
    slices, batches = [], []
    for name in pl.per_layer:
        p = b.passes[name]
        if p.accumulate:
            continue  # a fragment pass into its own target, in either form
        sources = [pl.resolve(t) for t in p.inputs.values()]
        if p.user is not None or p.format != "r8" or p.op.compute is None:
            return None
        # (``Op.compute_form``: a slice a layer from attributes, or a whole array into another)
        if p.op.compute_form == "slice" and all(t in b.attributes for t in sources):
            slices.append(name)
        elif p.op.compute_form == "array" and len(sources) == 1 and sources[0] in arrays:
            batches.append(name)
        else:
            return None
        arrays.add(name)
    for name in pl.passes:
        p = b.passes[name]
        for key, target in p.inputs.items():
            target = pl.resolve(target)
            if target in arrays and name not in arrays and not (p.kind == "composite" and key in p.stacks):
                return None
    if any(n in arrays for n in pl.readback):
        return None
    return ArrayPlan(frozenset(arrays), tuple(slices), tuple(batches))
