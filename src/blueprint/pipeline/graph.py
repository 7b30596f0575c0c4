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

from blueprint.pipeline.schema import Bound, fail

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


# compared by identity, never by value: no generated equality to build when the module loads
@dataclass(eq=False)
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
    known = [*bound.attributes, *bound.images, *bound.passes]
    for name in dumps:
        if name not in known:
            raise fail(bound.source, "--dump", f"unknown name {name!r} (choose {', '.join(known)})")
    wires = _Wires(bound)
    output = wires.resolve(bound.output)
    readback = list(dict.fromkeys([output, *(wires.resolve(d) for d in dumps)]))
    passes = wires.live(readback)
    accumulated = [n for n in passes if bound.passes[n].accumulate]
    after = wires.after_peel(passes, accumulated)
    stacked = wires.stacked(passes, after, accumulated, readback)
    attributes = sorted(
        {t for n in passes for _, t in wires.inputs(n) if t in bound.attributes}
        | {n for n in readback if n in bound.attributes}
        | {name for stop in bound.stops for name in (stop.depth, "depth")}  # layers against parts
    )
    images = sorted(
        {t for n in passes for _, t in wires.inputs(n) if t in bound.images}
        | {n for n in readback if n in bound.images}
    )
    per_layer = [n for n in passes if bound.passes[n].per_layer]
    iteration0 = [n for n in passes if n not in after]
    after_list = [n for n in passes if n in after]
    slots = _Slots(wires, iteration0, after_list, stacked, accumulated, bool(per_layer))
    slots.allot(readback)
    return Plan(
        bound=bound,
        output=output,
        aliases=wires.aliases,
        passes=passes,
        iteration0=iteration0,
        per_layer=per_layer,
        after=after_list,
        stacked=stacked,
        slots=slots.slots,
        scratch=slots.scratch,
        attributes=attributes,
        images=images,
        readback=readback,
        peel=any(bound.attributes[n].parts is None for n in attributes),
        needs_model=bool(attributes),
        layered=bool(per_layer),
        free_after=slots.free_after,
        parts=[n for n in attributes if bound.attributes[n].parts is not None],
        accumulated=accumulated,
    )


class _Wires:
    """The passes of a bound pipeline as they read each other, identities (a pass that passes
    its input on unchanged) replaced by what they read."""

    def __init__(self, bound: Bound) -> None:
        self.bound = bound
        self.aliases: dict[str, str] = {}
        for name in bound.passes:  # bind settles them in dependency order
            if _identity(bound, name):
                (target,) = bound.passes[name].inputs.values()
                self.aliases[name] = target

    def resolve(self, name: str) -> str:
        while name in self.aliases:
            name = self.aliases[name]
        return name

    def inputs(self, name: str) -> list[tuple[str, str]]:
        return [(k, self.resolve(t)) for k, t in self.bound.passes[name].inputs.items()]

    def live(self, readback: list[str]) -> list[str]:
        """The passes the results read back need, in dependency order."""
        passes = self.bound.passes
        live: set[str] = set()
        stack = [n for n in readback if n in passes]
        while stack:
            name = stack.pop()
            if name in live:
                continue
            live.add(name)
            stack += [t for _, t in self.inputs(name) if t in passes]
        return [n for n in passes if n in live]

    def after_peel(self, passes: list[str], accumulated: list[str]) -> set[str]:
        """The once-passes that need every layer (a stack input, an accumulated target, or
        such a pass's result), which run after the peel; a per-layer pass cannot read them."""
        after: set[str] = set()
        for name in passes:
            p = self.bound.passes[name]
            inputs = self.inputs(name)
            needs_all = any(k in p.stacks for k, _ in inputs) or any(
                t in after or (t in accumulated and not p.per_layer) for _, t in inputs
            )
            if needs_all:
                if p.per_layer:
                    culprit = next(t for _, t in inputs if t in after)
                    raise fail(
                        self.bound.source,
                        f"passes.{name}.inputs",
                        f"{culprit!r} needs every depth layer, so it is ready only after the peel; "
                        "a per-layer pass cannot read it",
                    )
                after.add(name)
        return after

    def stacked(
        self, passes: list[str], after: set[str], accumulated: list[str], readback: list[str]
    ) -> set[str]:
        """The per-layer results kept a target a layer: every layer of a stack input, those
        read after the peel, and those read back."""
        bound = self.bound
        stacked: set[str] = set()
        for name in passes:
            p = bound.passes[name]
            for key, target in self.inputs(name):
                if key in p.stacks:
                    stacked.add(target)
                elif name in after:
                    if target in bound.attributes and bound.attributes[target].parts is None:
                        raise fail(
                            bound.source,
                            f"passes.{name}.inputs.{key}",
                            f"attribute {target!r} is gone once every layer is peeled, and this pass "
                            f"needs every layer; read {target!r} through a pass of its own "
                            "(without per_layer) instead",
                        )
                    if (
                        target in bound.passes
                        and bound.passes[target].per_layer
                        and target not in accumulated
                    ):
                        stacked.add(target)  # read as layer 0 after the peel
        for name in readback:
            if name in bound.passes and bound.passes[name].per_layer and name not in accumulated:
                stacked.add(name)
        return stacked


class _Slots:
    """The slots of the results neither stacked nor accumulated: a linear scan over the
    timeline (layer 0's passes, the loop's end, the passes after the peel), each result taking
    a slot of its (format, scale) when written and giving it back after its last reader."""

    def __init__(
        self,
        wires: _Wires,
        iteration0: list[str],
        after: list[str],
        stacked: set,
        accumulated: list,
        layered: bool,
    ) -> None:
        self.wires, self.bound = wires, wires.bound
        self.iteration0, self.timeline = iteration0, iteration0 + after
        self.stacked, self.accumulated, self.layered = stacked, accumulated, layered
        self.position = {n: i for i, n in enumerate(iteration0)}
        self.loop_end = len(iteration0)
        self.position.update({n: self.loop_end + 1 + i for i, n in enumerate(after)})
        self.free: dict[tuple, list[Slot]] = {}
        self.count: dict[tuple, int] = {}
        self.slots: dict[str, Slot] = {}
        self.scratch: dict[str, Slot] = {}
        self.free_after: dict[str, list[str]] = {}

    def last_uses(self, readback: list[str]) -> dict[str, float]:
        """Where on the timeline each slotted result is read for the last time (a once-result
        read by a per-layer pass: at the loop's end; a result read back: never given back)."""
        bound, passes = self.bound, self.bound.passes
        last: dict[str, float] = {}
        for name in self.timeline:
            for _, target in self.wires.inputs(name):
                if target not in passes or target in self.stacked or target in self.accumulated:
                    continue
                use = self.position[name]
                if not passes[target].per_layer and passes[name].per_layer and self.layered:
                    use = max(use, self.loop_end)  # read again at every later layer
                last[target] = max(last.get(target, -1), use)
        for name in readback:
            if name in bound.passes and name not in self.stacked:
                last[name] = float("inf")
        return last

    def take(self, space: str, fmt: str, scale: float) -> Slot:
        key = (space, fmt, round(scale, 9))
        if self.free.get(key):
            return self.free[key].pop()
        self.count[key] = self.count.get(key, 0) + 1
        return Slot(space, fmt, scale, self.count[key] - 1)

    def give(self, slot: Slot) -> None:
        self.free.setdefault((slot.space, slot.format, round(slot.scale, 9)), []).append(slot)

    def allot(self, readback: list[str]) -> None:
        last = self.last_uses(readback)
        slots, scratch = self.slots, self.scratch
        for index, name in enumerate(self.accumulated):
            p = self.bound.passes[name]
            slots[name] = Slot("A", p.format, p.scale, index)
        for name in self.timeline:
            p = self.bound.passes[name]
            space = "L" if p.per_layer else "F"
            if p.kind == "separable":
                scratch[name] = self.take(space, SCRATCH_FORMAT, p.scale)
            if name not in self.stacked and name not in self.accumulated:
                slots[name] = self.take(space, p.format, p.scale)
            if name in scratch:
                self.give(scratch[name])
            done = [t for t, use in last.items() if use == self.position[name] and t in slots]
            for target in done:
                self.give(slots[target])
                del last[target]
            if name in slots and name not in last and name not in self.accumulated:
                self.give(slots[name])  # nobody reads it (cannot happen for live passes, kept for safety)
            self.free_after[name] = done
            if name == (self.iteration0[-1] if self.iteration0 else None):
                ended = [t for t, use in last.items() if use == self.loop_end and t in slots]
                for target in ended:
                    self.give(slots[target])
                    del last[target]
