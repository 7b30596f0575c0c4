"""Frame pacing: how frames are drawn while the view moves, and the frame-rate measurement of
``blueprint view --frames N``.

While the view moves, each frame is drawn at one step of a ladder of qualities, from the full
drawing down to less work: supersample 1, fewer layers, a smaller drawing scaled up to the
window, a coarse mesh. ``Pacer`` measures what each step costs (the last frames drawn at it,
from the render call to the swap) and ``choose_step`` picks the richest step that keeps the
frame rate asked for (``moving_fps``, 10 by default), with hysteresis: a step is left for a
cheaper one once it is slower than the budget, and taken again only once it measured well
inside it, so the quality does not flicker between two steps.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

# The frame rate kept while the view moves, unless the viewer is told another.
MOVING_FPS = 10.0
# A richer step is taken again once it measured within this share of the frame budget.
UP_SHARE = 0.8
# A richer step not measured lately is tried when the current one takes less than this share
# of the budget (a step does about half the work of the one above it, or less).
PROBE_SHARE = 0.4
# What a step costs: the median of its last few frames, forgotten after some seconds (the
# view, and with it the cost, changes).
SAMPLES = 3
FORGET_SECONDS = 10.0
# A frame drawn unlike the one before it makes its targets anew, which can cost it half its
# time again: one slower than the budget by less than this share is measured once more.
COLD_SHARE = 2.0
# The steps below the full drawing cap the layers at this many (the first hidden ones), then 1.
FEW_LAYERS = 2
# Models above this many triangles get coarse-mesh steps at the end of the ladder.
COARSE_ABOVE = 200_000
WARMUP_FRAMES = 2


@dataclass(frozen=True)
class Step:
    """One quality of the ladder.

    Attributes
    ----------
    scale : float
        The drawing's size as a fraction of the window's (scaled up with linear filtering).
    supersample : int
        The supersampling of the drawing.
    layers : int or None
        Depth layers to peel at most (None: every one).
    coarse : bool
        Drawn from the coarse mesh (``viewer.lod``) instead of the model.
    label : str
        What the heads-up line says of it: ``full``, or how it differs from the full drawing
        (``1/2 size, 2 layers``).
    """

    scale: float
    supersample: int
    layers: int | None
    coarse: bool = False
    label: str = "full"


def _cap(layers: int | None, most: int) -> int:
    return most if layers is None else min(layers, most)


def _label(step: tuple, supersample: int, layers: int | None) -> str:
    scale, step_supersample, step_layers, coarse = step
    parts = ["coarse mesh"] if coarse else []
    if scale < 1:
        fraction = Fraction(scale)
        small = fraction.denominator <= 16
        parts.append(f"{fraction.numerator}/{fraction.denominator} size" if small else f"{scale:g} size")
    if step_layers != layers:
        parts.append(f"{step_layers} layer{'s' if step_layers != 1 else ''}")
    if not parts and step_supersample != supersample:
        parts.append(f"supersample {step_supersample}")
    return ", ".join(parts) or "full"


def ladder(
    supersample: int, layers: int | None, *, fixed_scale: float = 0.0, coarse: bool = False
) -> tuple[Step, ...]:
    """The qualities tried while the view moves, richest first, each doing less work than the
    one before it.

    Parameters
    ----------
    supersample, layers : int, int or None
        The full drawing's supersampling and layer limit (None: every layer).
    fixed_scale : float
        Where > 0, the one quality of moving frames: this fraction of the window, supersample 1,
        the full drawing's layers (``--interactive-scale``).
    coarse : bool
        End with steps drawn from a coarse mesh (a big model).
    """
    if fixed_scale:
        steps = [(fixed_scale, 1, layers, False)]
    else:
        few, one = _cap(layers, FEW_LAYERS), _cap(layers, 1)
        steps = [
            (1.0, supersample, layers, False),
            (1.0, 1, layers, False),
            (1.0, 1, few, False),
            (0.5, 1, few, False),
            (0.5, 1, one, False),
            (0.25, 1, one, False),
        ]
        if coarse:
            steps += [(0.5, 1, few, True), (0.25, 1, one, True)]
    unique = list(dict.fromkeys(steps))
    return tuple(Step(*step, label=_label(step, supersample, layers)) for step in unique)


def choose_step(current: int, costs: Sequence[float | None], budget_ms: float) -> int:
    """The ladder step for the next moving frame.

    Parameters
    ----------
    current : int
        The step of the last moving frame.
    costs : sequence of float or None
        Each step's measured milliseconds a frame (None: not measured lately), richest first.
    budget_ms : float
        The time a frame may take.

    Returns
    -------
    int
        The current step while it keeps within the budget and no richer one measured within
        ``UP_SHARE`` of it; once it is slower, the next cheaper step measured within the budget,
        or not measured lately and within it at half the cost a step down (a big model's first
        moving frame, seconds over, goes down the ladder at once, not a slow frame a step); the
        richest step above it that measured within ``UP_SHARE`` of the budget (one step not
        measured lately is tried where the current takes less than ``PROBE_SHARE`` of it).
    """
    last = len(costs) - 1
    cost = costs[current]
    if cost is None:
        return current
    if cost > budget_ms:
        for step in range(current + 1, last + 1):
            known = costs[step]
            if (known if known is not None else cost / 2 ** (step - current)) <= budget_ms:
                return step
        return last
    chosen = current
    while chosen > 0:
        richer = costs[chosen - 1]
        if richer is None:
            below = costs[chosen]
            return chosen - 1 if below is not None and below <= PROBE_SHARE * budget_ms else chosen
        if richer > UP_SHARE * budget_ms:
            return chosen
        chosen -= 1
    return chosen


class Pacer:
    """The ladder of a viewer, what its steps cost, and the step of the next moving frame.

    ``fps``: the frame rate to keep while moving; ``fixed_scale`` > 0: one quality only (see
    ``ladder``); ``coarse``: the ladder ends with coarse-mesh steps. ``steps`` is the ladder,
    ``full`` the still frame's quality, ``full_index`` its place in the ladder (None: none).
    """

    def __init__(self, fps: float = MOVING_FPS, *, fixed_scale: float = 0.0, coarse: bool = False) -> None:
        self.budget_ms = 1000.0 / fps
        self.fixed_scale = fixed_scale
        self.coarse = coarse
        self.steps: tuple[Step, ...] = ()
        self.full = Step(1.0, 1, None)
        self.full_index: int | None = 0
        self.current = 0
        self._key: tuple | None = None
        self._samples: list[list[tuple[float, float]]] = []  # (when, ms) a step

    def settle(self, key: tuple, supersample: int, layers: int | None) -> None:
        """The ladder for a full drawing of ``supersample`` and ``layers``; ``key`` names all
        that its costs depend on (with these, the window's size): a new key starts a new
        ladder with nothing measured, its moving frames from the step of the same place (the
        cost of the full drawing alone changes most when a layer more or less is asked for)."""
        if key == self._key:
            return
        self._key = key
        self.steps = ladder(supersample, layers, fixed_scale=self.fixed_scale, coarse=self.coarse)
        self.full = Step(1.0, supersample, layers)
        # a still frame's cost is that of the ladder's first step, unless the ladder is one fixed step
        self.full_index = 0 if self.steps[0] == self.full else None
        self.current = min(self.current, len(self.steps) - 1)
        self._samples = [[] for _ in self.steps]

    def costs(self, now: float | None = None) -> list[float | None]:
        """Each step's median milliseconds over its last ``SAMPLES`` frames of the last
        ``FORGET_SECONDS``; None where there are none."""
        now = time.perf_counter() if now is None else now
        return [
            float(np.median([ms for when, ms in samples[-SAMPLES:]]))
            if samples and now - samples[-1][0] <= FORGET_SECONDS
            else None
            for samples in self._samples
        ]

    def next_step(self, now: float | None = None) -> int:
        """The step of the next moving frame (see ``choose_step``), kept as the current one."""
        self.current = choose_step(self.current, self.costs(now), self.budget_ms)
        return self.current

    def record(self, step: int, ms: float, now: float | None = None, *, cold: bool = False) -> None:
        """A frame drawn at ``step`` took ``ms``; samples older than ``FORGET_SECONDS`` go.

        ``cold``: the frame before it was drawn otherwise (another size, supersampling, layers
        or mesh), and this one paid for making its targets: over the budget by less than
        ``COLD_SHARE``, it says nothing of the step, which the next frame measures again."""
        if cold and self.budget_ms < ms <= COLD_SHARE * self.budget_ms:
            return
        now = time.perf_counter() if now is None else now
        samples = self._samples[step]
        samples[:] = [s for s in samples[-SAMPLES:] if now - s[0] <= FORGET_SECONDS]
        samples.append((now, ms))


class FrameRate:
    """Frames, timed, for a frame rate after ``WARMUP_FRAMES`` of warm-up."""

    def __init__(self) -> None:
        self._samples: list[tuple[float, float, str]] = []  # (when, draw ms, step label)

    def tick(self, ms: float, step: str, now: float | None = None) -> None:
        """One frame done (at ``now``), drawn at the ladder step labelled `step` in `ms`."""
        self._samples.append((time.perf_counter() if now is None else now, ms, step))

    def done(self, frames: int) -> bool:
        return len(self._samples) >= frames + WARMUP_FRAMES

    def report(self) -> dict:
        """Frames, fps, mean and median ms and how many frames each step drew; the last frame's
        step and the frame rate of the frames at it since the step last changed (the ladder
        settled); only the frame count where fewer than two frames were timed."""
        timed = self._samples[WARMUP_FRAMES:]
        if len(timed) < 2:
            return {"frames": len(timed)}
        start = self._samples[WARMUP_FRAMES - 1][0]
        wall = timed[-1][0] - start
        steps: dict[str, int] = {}
        for _, _, step in timed:
            steps[step] = steps.get(step, 0) + 1
        last = timed[-1][2]
        tail = next((k for k, sample in enumerate(reversed(timed)) if sample[2] != last), len(timed))
        tail_start = self._samples[len(self._samples) - tail - 1][0]
        return {
            "frames": len(timed),
            "fps": round(len(timed) / wall, 2),
            "ms": round(wall * 1e3 / len(timed), 2),
            "draw_ms_median": round(float(np.median([ms for _, ms, _ in timed])), 2),
            "steps": steps,
            "step": last,
            "step_frames": tail,
            "step_fps": round(tail / (timed[-1][0] - tail_start), 2),
        }
