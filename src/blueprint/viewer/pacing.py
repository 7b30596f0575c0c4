"""Frame pacing: the resolution of drafts, lowered while they are slower than 30 fps, and the
frame-rate measurement of ``blueprint view --frames N``."""

from __future__ import annotations

import time

import numpy as np

# Draft resolutions tried while the view moves, as fractions of the window.
DRAFT_SCALES = (1.0, 0.75, 0.5)
TARGET_MS = 1000.0 / 30.0
WARMUP_FRAMES = 2


class Drafts:
    """The resolution of the next draft: `fixed`, a fraction of the window, or where that is 0
    one of ``DRAFT_SCALES``, adapted to how long drafts take."""

    def __init__(self, fixed: float = 0.0) -> None:
        self.fixed = fixed
        self._index = 0

    def scale(self) -> float:
        return self.fixed if self.fixed else DRAFT_SCALES[self._index]

    def adapt(self, ms: float) -> None:
        """Pick the next draft resolution so drafts come near 30 fps."""
        if self.fixed:
            return
        if ms > TARGET_MS * 1.2 and self._index < len(DRAFT_SCALES) - 1:
            self._index += 1
        elif ms < TARGET_MS * 0.45 and self._index > 0:
            self._index -= 1


class FrameRate:
    """Loop iterations, timed, for a frame rate after ``WARMUP_FRAMES`` of warm-up."""

    def __init__(self) -> None:
        self._samples: list[tuple[float, float]] = []  # (when, draw ms)

    def tick(self, ms: float) -> None:
        """One iteration done, the last frame having taken `ms` to draw."""
        self._samples.append((time.perf_counter(), ms))

    def done(self, frames: int) -> bool:
        return len(self._samples) >= frames + WARMUP_FRAMES

    def report(self, about: dict, last: dict) -> dict:
        """`about` (model, renderer), then frames, fps, mean and median ms, and how the `last`
        frame was drawn; only the frame count where fewer than two frames were timed."""
        timed = self._samples[WARMUP_FRAMES:]
        if len(timed) < 2:
            return {"frames": len(timed)}
        start = self._samples[WARMUP_FRAMES - 1][0]
        wall = timed[-1][0] - start
        return {
            **about,
            "frames": len(timed),
            "fps": round(len(timed) / wall, 2),
            "ms": round(wall * 1e3 / len(timed), 2),
            "draw_ms_median": round(float(np.median([ms for _, ms in timed])), 2),
            "size": last.get("size"),
            "render_size": last.get("render_size"),
            "supersample": last.get("supersample"),
            "layers": last.get("layers"),
        }
