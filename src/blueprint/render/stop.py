"""When peeling stops: small rules that the one loop drawing layers asks
(``blueprint.render.capture.layer_loop``).

A rule may cap the layers (``limit``), end the peel once it has seen the occlusion counts of
the layers drawn so far (``done``), and say how many of the peeled layers count (``count``).
Counts are read only when the loop looks, so a rule that must look after every layer
(``every_layer``, depth masking) makes the CPU wait for the GPU once a layer; the others are
looked at once a chunk of layers, or once a frame when the layers are capped.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from blueprint.errors import InputError

# The most layers any peel draws: also the cap where no rule sets one.
HARD_MAX_LAYERS = 256


class StopRule:
    every_layer = False

    def limit(self) -> int | None:
        return None

    def done(self, counts: Sequence[int]) -> bool:
        return False

    def count(self, counts: Sequence[int]) -> int:
        return len(counts)


class EmptyLayer(StopRule):
    """A pass that draws nothing ends the peel; it and the layers after it do not count."""

    def done(self, counts: Sequence[int]) -> bool:
        return bool(counts) and counts[-1] == 0

    def count(self, counts: Sequence[int]) -> int:
        return next((i for i, c in enumerate(counts) if c == 0), len(counts))


class MaxLayers(StopRule):
    def __init__(self, layers: int) -> None:
        if not 1 <= int(layers) <= HARD_MAX_LAYERS:
            raise InputError(f"max-layers must be between 1 and {HARD_MAX_LAYERS}, got {layers}")
        self.layers = int(layers)

    def limit(self) -> int:
        return self.layers


class MinFraction(StopRule):
    """A layer covering fewer than ``fraction`` of layer 0's samples ends the peel."""

    def __init__(self, fraction: float) -> None:
        if not 0.0 <= fraction <= 1.0:
            raise InputError(f"min-fraction must be in [0, 1], got {fraction}")
        self.fraction = float(fraction)

    def count(self, counts: Sequence[int]) -> int:
        return next((i for i, c in enumerate(counts) if i > 0 and c < self.fraction * counts[0]), len(counts))

    def done(self, counts: Sequence[int]) -> bool:
        return self.fraction > 0 and self.count(counts) < len(counts)


class Reveal(StopRule):
    """Depth masking: stop as soon as ``fraction`` of the designated parts' pixels is uncovered.

    ``revealed(layer)`` counts (on the GPU, read back) the designated pixels whose surface is
    among the layers peeled up to ``layer``; ``wanted`` is all of them.
    """

    every_layer = True

    def __init__(self, fraction: float, wanted: int, revealed: Callable[[int], int]) -> None:
        if not 0.0 < fraction <= 1.0:
            raise InputError(f"reveal must be in (0, 1], got {fraction}")
        self.fraction, self.wanted, self._revealed = float(fraction), wanted, revealed
        self.shown = 1.0

    def done(self, counts: Sequence[int]) -> bool:
        if not counts:
            return False
        shown = self._revealed(len(counts) - 1)
        self.shown = shown / self.wanted if self.wanted else 1.0
        return self.shown >= self.fraction


def standard_rules(max_layers: int | None, min_fraction: float) -> list[StopRule]:
    """The rules every peel has: an empty pass ends it; then ``max_layers`` (None: no cap
    but ``HARD_MAX_LAYERS``; depth masking passes None, as it peels as deep as it needs) and
    ``min_fraction``."""
    rules: list[StopRule] = [EmptyLayer(), MinFraction(min_fraction)]
    if max_layers is not None:
        rules.append(MaxLayers(max_layers))
    return rules
