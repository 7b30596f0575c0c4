"""The pass graph of a bound pipeline: what runs when, and which target each result lives in.

Stages. A pass with ``per_layer`` runs once for every peeled depth layer and sees that layer's
attributes. A pass without it runs once: while layer 0 is on the GPU (it sees the visible
surfaces), unless it needs every layer of some per-layer pass (a stack input, as composite
has), directly or through other passes; then it runs after the peel. So the peel loop body is
the per-layer passes, plus at layer 0 the once-passes interleaved in dependency order.

Targets. Results that must outlive an iteration of the loop are *stacked*: one target per layer
(every layer of a stack input, a per-layer result read after the peel, the output, dumps).
Every other result takes a slot, a pool target of its (format, scale), as late as possible and
gives it back after its last reader, so a chain of passes ping-pongs between a few targets.
Per-layer results and once-results take slots from separate sets: a per-layer result is
rewritten at every layer, so it must never share a slot with a result that is still read later.
An accumulating per-layer pass writes every layer into one target of its own, held all frame.
Attributes of chosen parts are captured once, before the peel, and live all frame too.
Plans are GPU-free and computed once per bound pipeline.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from blueprint.pipeline.spec import Bound, fail

SCRATCH_FORMAT = "rgba32f"


@dataclass(frozen=True)
class Slot:
    space: str  # "L": per-layer results; "F": once-results
    format: str
    scale: float
    index: int

    @property
    def name(self) -> str:
        return f"pipeline.{self.space}{self.index}.{self.format}.{self.scale:g}"


@dataclass
class Plan:
    bound: Bound
    output: str
    aliases: dict[str, str]
    passes: list[str]  # live passes, dependency order
    iteration0: list[str]  # per-layer passes and once-passes run at layer 0, in order
    per_layer: list[str]  # the per-layer passes, in order (every layer)
    after: list[str]  # once-passes that need all layers
    stacked: set[str]
    slots: dict[str, Slot]
    scratch: dict[str, Slot]
    attributes: list[str]  # attributes read
    images: list[str]  # images read
    readback: list[str]  # output and dumps (resolved names)
    peel: bool  # attributes of every layer are read: the model is peeled
    layered: bool
    free_after: dict[str, list[str]] = field(default_factory=dict)
    needs_model: bool = False  # any attribute is read, of every layer or of chosen parts
    parts: list[str] = field(default_factory=list)  # attributes of chosen parts read
    accumulated: list[str] = field(default_factory=list)

    def resolve(self, name: str) -> str:
        while name in self.aliases:
            name = self.aliases[name]
        return name


def _identity(bound: Bound, name: str) -> bool:
    p = bound.passes[name]
    test = p.op.identity
    if p.user is not None or test is None or not test(p.uniforms):
        return False
    (target,) = p.inputs.values()
    source = bound.passes.get(target)
    return (
        source is not None
        and source.per_layer == p.per_layer
        and source.format == p.format
        and abs(source.scale - p.scale) < 1e-9
    )


def plan(bound: Bound, dumps: tuple[str, ...] = ()) -> Plan:
    """Plan a bound pipeline; raises the pipeline's InputError for graphs that cannot run."""
    src = bound.source
    known = [*bound.attributes, *bound.images, *bound.passes]
    for name in dumps:
        if name not in known:
            raise fail(src, "--dump", f"unknown name {name!r} (choose {', '.join(known)})")
    order = list(bound.passes)  # bind settles them in dependency order
    aliases = {}
    for name in order:
        if _identity(bound, name):
            (target,) = bound.passes[name].inputs.values()
            aliases[name] = target

    def resolve(name: str) -> str:
        while name in aliases:
            name = aliases[name]
        return name

    def inputs(name: str) -> list[tuple[str, str]]:
        return [(k, resolve(t)) for k, t in bound.passes[name].inputs.items()]

    output = resolve(bound.output)
    readback = list(dict.fromkeys([output, *(resolve(d) for d in dumps)]))
    live: set[str] = set()
    stack = [n for n in readback if n in bound.passes]
    while stack:
        name = stack.pop()
        if name in live:
            continue
        live.add(name)
        stack += [t for _, t in inputs(name) if t in bound.passes]
    passes = [n for n in order if n in live]

    accumulated = [n for n in passes if bound.passes[n].accumulate]
    after: set[str] = set()
    for name in passes:
        p = bound.passes[name]
        needs_all = any(k in p.stacks for k, _ in inputs(name)) or any(
            t in after or (t in accumulated and not p.per_layer) for _, t in inputs(name)
        )
        if needs_all:
            if p.per_layer:
                culprit = next(t for _, t in inputs(name) if t in after)
                raise fail(
                    src,
                    f"passes.{name}.inputs",
                    f"{culprit!r} needs every depth layer, so it is ready only after the peel; "
                    "a per-layer pass cannot read it",
                )
            after.add(name)
    stacked: set[str] = set()
    for name in passes:
        p = bound.passes[name]
        for key, target in inputs(name):
            if key in p.stacks:
                stacked.add(target)
            elif name in after:
                if target in bound.attributes and bound.attributes[target].parts is None:
                    raise fail(
                        src,
                        f"passes.{name}.inputs.{key}",
                        f"attribute {target!r} is gone once every layer is peeled, and this pass needs every "
                        f"layer; read {target!r} through a pass of its own (without per_layer) instead",
                    )
                if target in bound.passes and bound.passes[target].per_layer and target not in accumulated:
                    stacked.add(target)  # read as layer 0 after the peel
    for name in readback:
        if name in bound.passes and bound.passes[name].per_layer and name not in accumulated:
            stacked.add(name)

    attributes = sorted(
        {t for n in passes for _, t in inputs(n) if t in bound.attributes}
        | {n for n in readback if n in bound.attributes}
        | {name for stop in bound.stops for name in (stop.depth, "depth")}  # layers against parts
    )
    parts = [n for n in attributes if bound.attributes[n].parts is not None]
    images = sorted(
        {t for n in passes for _, t in inputs(n) if t in bound.images}
        | {n for n in readback if n in bound.images}
    )
    per_layer = [n for n in passes if bound.passes[n].per_layer]
    iteration0 = [n for n in passes if n not in after]
    after_list = [n for n in passes if n in after]
    layered = bool(per_layer)

    # -- slots: linear scan over the timeline iteration0 | loop end | after -------------------------
    timeline = iteration0 + after_list
    position = {n: i for i, n in enumerate(iteration0)}
    loop_end = len(iteration0)
    position.update({n: loop_end + 1 + i for i, n in enumerate(after_list)})
    last: dict[str, float] = {}
    for name in timeline:
        for _, target in inputs(name):
            if target not in bound.passes or target in stacked or target in accumulated:
                continue
            use = position[name]
            if not bound.passes[target].per_layer and bound.passes[name].per_layer and layered:
                use = max(use, loop_end)  # read again at every later layer
            last[target] = max(last.get(target, -1), use)
    for name in readback:
        if name in bound.passes and name not in stacked:
            last[name] = float("inf")
    free: dict[tuple, list[Slot]] = {}
    count: dict[tuple, int] = {}
    slots: dict[str, Slot] = {}
    scratch: dict[str, Slot] = {}
    free_after: dict[str, list[str]] = {}

    def take(space: str, fmt: str, scale: float) -> Slot:
        key = (space, fmt, round(scale, 9))
        if free.get(key):
            return free[key].pop()
        count[key] = count.get(key, 0) + 1
        return Slot(space, fmt, scale, count[key] - 1)

    def give(slot: Slot) -> None:
        free.setdefault((slot.space, slot.format, round(slot.scale, 9)), []).append(slot)

    for index, name in enumerate(accumulated):
        p = bound.passes[name]
        slots[name] = Slot("A", p.format, p.scale, index)
    for name in timeline:
        p = bound.passes[name]
        space = "L" if p.per_layer else "F"
        if p.kind == "separable":
            scratch[name] = take(space, SCRATCH_FORMAT, p.scale)
        if name not in stacked and name not in accumulated:
            slots[name] = take(space, p.format, p.scale)
        if name in scratch:
            give(scratch[name])
        done = [t for t, use in last.items() if use == position[name] and t in slots]
        for target in done:
            give(slots[target])
            del last[target]
        if name in slots and name not in last and name not in accumulated:
            give(slots[name])  # nobody reads it (cannot happen for live passes, kept for safety)
        free_after[name] = done
        if name == (iteration0[-1] if iteration0 else None):
            ended = [t for t, use in last.items() if use == loop_end and t in slots]
            for target in ended:
                give(slots[target])
                del last[target]

    return Plan(
        bound=bound,
        output=output,
        aliases=aliases,
        passes=passes,
        iteration0=iteration0,
        per_layer=per_layer,
        after=after_list,
        stacked=stacked,
        slots=slots,
        scratch=scratch,
        attributes=attributes,
        images=images,
        readback=readback,
        peel=any(bound.attributes[n].parts is None for n in attributes),
        needs_model=bool(attributes),
        layered=layered,
        free_after=free_after,
        parts=parts,
        accumulated=accumulated,
    )
