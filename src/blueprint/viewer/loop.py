"""The viewer and its drawing loop: every picture comes from the same ``Renderer.render`` as
``blueprint render``, drawn only when something changed.

While the view moves (drag, wheel, turntable) frames are drafts: supersample 1 and, when that
is slower than 30 fps, a lower resolution scaled up; once the view rests for ``REFINE_DELAY``
seconds one full-quality frame follows.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from blueprint.compose.lookup import get_style
from blueprint.errors import BlueprintError, InputError
from blueprint.gpu.device import check_size
from blueprint.scene.model import Model
from blueprint.viewer.controls import Controls
from blueprint.viewer.pacing import Drafts, FrameRate
from blueprint.viewer.present import Presenter, hud_lines
from blueprint.viewer.snapshots import FrameDump, save_screenshot
from blueprint.viewer.state import Options, ViewState
from blueprint.viewer.window import Window

# Seconds the view rests before a full-quality frame follows the drafts.
REFINE_DELAY = 0.2
# Depth masking (M): peel until this fraction of the selected part's pixels shows.
REVEAL = 0.95
# How long a message (screenshot saved) stays in the heads-up lines.
STATUS_SECONDS = 5.0
# The frame rate in the heads-up lines changes at most this often: readable while the view
# moves, and the lines are drawn again only when they change.
RATE_SECONDS = 0.5


class Viewer:
    """One window on one model. ``run()`` returns when the window closes."""

    def __init__(
        self,
        model: Model,
        model_path: Path,
        state: ViewState,
        *,
        size: tuple[int, int] = (800, 600),
        options: Options | None = None,
        dump: str | os.PathLike | None = None,
    ) -> None:
        self.model = model
        self.model_path = Path(model_path)
        self.state = state
        self.options = options or Options()
        check_size(size, self.options.supersample, 16384)
        if self.options.interactive_scale and not 0.05 <= self.options.interactive_scale <= 1.0:
            scale = self.options.interactive_scale
            raise InputError(f"interactive-scale must be 0 (automatic) or in [0.05, 1], got {scale}")
        self.dump = FrameDump(Path(dump)) if dump else None
        self.window = Window(size, f"blueprint view - {self.model_path.name}")
        try:
            check_size(size, self.options.supersample, self.window.renderer.max_texture)
        except BlueprintError:
            self.window.close()
            raise
        self.presenter = Presenter(self.window)
        self.controls = Controls(self)
        self.window.listen(
            key=self.controls.on_key,
            button=self.controls.on_button,
            cursor=self.controls.on_cursor,
            scroll=self.controls.on_scroll,
            resize=lambda *_: self.invalidate(),
            refresh=lambda *_: self.repaint(),
        )
        self._drawing: np.ndarray | None = None  # the last full-quality drawing (RGBA)
        self._last: dict = {}  # how the last frame was drawn
        self._status = ""
        self._status_time = 0.0
        self._drafts = Drafts(self.options.interactive_scale)
        self._rate = FrameRate()
        self._shown_ms = (0.0, -RATE_SECONDS)  # (the draw time shown, when it was taken)
        # what needs doing
        self._needs_render = True
        self._needs_present = False
        self._refine_at: float | None = None
        self._last_spin = time.perf_counter()

    def close(self) -> None:
        """Release the GL objects, the window and GLFW."""
        if self.window.renderer is not None:
            self.presenter.release()
        self.window.close()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- what the controls ask for ---------------------------------------------------------------
    def invalidate(self) -> None:
        self._needs_render = True

    def repaint(self) -> None:
        self._needs_present = True

    def refine_later(self) -> None:
        """A full-quality frame once the view has rested for ``REFINE_DELAY``."""
        self._refine_at = time.perf_counter() + REFINE_DELAY

    def toggle_turntable(self) -> None:
        self.state.turntable = not self.state.turntable
        self._last_spin = time.perf_counter()
        if not self.state.turntable:
            self.refine_later()

    @property
    def layers_drawn(self) -> int:
        return int(self._last.get("layers", 1) or 1)

    def screenshot(self) -> None:
        """Save the current drawing (full quality, no heads-up lines) as NAME-N.png beside the model."""
        if self._drawing is None or self._needs_render:
            self._render(draft=False, present=False)
        if self._drawing is None:  # minimised: nothing drawn
            return
        self._status = save_screenshot(self.model_path, self._drawing)
        self._status_time = time.perf_counter()
        self.repaint()

    # -- loop ----------------------------------------------------------------------------------
    def run(self, frames: int = 0) -> dict | None:
        """Show the window until Esc or close. With ``frames`` > 0: spin the turntable for that
        many frames (after a warm-up), close, and return the measured timings."""
        glfw, handle = self.window.glfw, self.window.handle
        if frames > 0:
            self.state.turntable = True
        try:
            while not glfw.window_should_close(handle):
                self._wait()
                now = time.perf_counter()
                if self.state.turntable:
                    self.state.spin(min(0.1, now - self._last_spin))
                    self._last_spin = now
                    self._needs_render = True
                if glfw.window_should_close(handle):
                    break
                if self._needs_render:
                    draft = self._moving(now)
                    self._render(draft)
                    self._refine_at = time.perf_counter() + REFINE_DELAY if draft else None
                elif self._refine_at is not None and now >= self._refine_at:
                    self._render(draft=False)
                    self._refine_at = None
                elif self._needs_present:
                    self._present()
                if frames > 0:
                    self._rate.tick(self._last.get("ms", 0.0))
                    if self._rate.done(frames):
                        break
        finally:
            result = self._timings() if frames > 0 else None
            self.close()
        return result

    def _wait(self) -> None:
        glfw = self.window.glfw
        if self._needs_render or self._needs_present or self.state.turntable:
            glfw.poll_events()
        elif self._refine_at is not None:
            glfw.wait_events_timeout(max(0.0, min(0.5, self._refine_at - time.perf_counter())))
        else:
            # a timeout, not a plain wait, so Ctrl+C in the terminal is noticed
            glfw.wait_events_timeout(0.5)

    def _moving(self, now: float) -> bool:
        controls = self.controls
        return self.state.turntable or controls.moved or now - controls.last_scroll < REFINE_DELAY

    def _timings(self) -> dict:
        about = {
            "model": self.model_path.name,
            "triangles": self.model.triangle_count,
            "renderer": self.window.renderer_name,
        }
        return self._rate.report(about, self._last)

    # -- drawing -------------------------------------------------------------------------------
    def _render(self, draft: bool, present: bool = True) -> None:
        w, h = self.window.size()
        if w < 1 or h < 1:  # minimised
            self._needs_render = False
            return
        state, opts = self.state, self.options
        scale = self._drafts.scale() if draft else 1.0
        supersample = 1 if draft else opts.supersample
        rw, rh = max(1, round(w * scale)), max(1, round(h * scale))
        camera = state.camera(self.model, w / h)
        highlight = reveal = None
        if state.part is not None:
            # the renderer's own highlight: the part's whole outline over everything, in the
            # style's highlight ink; M adds depth masking (peel until the part shows)
            highlight = np.arange(len(self.model.part_names)) == state.part
            reveal = REVEAL if state.mask else None
        style = get_style(state.style, opts.grid)
        opaque = style.paper is not None and style.paper[3] >= 1.0
        t0 = time.perf_counter()
        frame = self.window.renderer.render(
            self.model,
            camera,
            style=style,
            highlight=highlight,
            reveal=reveal,
            size=(rw, rh),
            max_layers=state.max_layers,
            min_fraction=opts.min_fraction,
            crease_angle=opts.crease_angle,
            line_width=opts.line_width,
            supersample=supersample,
            # shown from the GPU; a screenshot (not presented at once) reads its drawing back
            on_gpu=present,
        )
        self._drawing = None if draft else frame.image
        if frame.texture is not None:
            self.presenter.show_texture(frame.texture, opaque)
        else:
            self.presenter.show(frame.image, opaque)
        done = time.perf_counter()
        ms = (done - t0) * 1e3
        if done - self._shown_ms[1] >= RATE_SECONDS or not draft:
            self._shown_ms = (ms, done)
        if draft:
            self._drafts.adapt(ms)
        self._last = {
            "quality": "draft" if draft else "full",
            "size": [w, h],
            "render_size": [rw, rh],
            "scale": scale,
            "supersample": supersample,
            "layers": frame.layers,
            "revealed": frame.revealed,
            "ms": ms,
        }
        self._needs_render = False
        if present:
            self._present()
        else:
            self._needs_present = True

    def _present(self) -> None:
        """The drawing, scaled to the window, the heads-up lines over it; dumped where asked; swap."""
        self._needs_present = False
        if not self.presenter.has_picture:
            self._needs_render = True
            return
        size = self.window.size()
        if size[0] < 1 or size[1] < 1:
            return
        fresh = self._status and time.perf_counter() - self._status_time < STATUS_SECONDS
        status = self._status if fresh else ""
        last = {**self._last, "ms": self._shown_ms[0]}
        lines = hud_lines(self.state, self.model, last, self.window.renderer_name, status)
        self.presenter.draw(size, lines, self.state.help)
        if self.dump is not None:
            self.dump.write(
                self.presenter.read(size),
                lines,
                last=self._last,
                state=self.state,
                model=self.model,
                renderer_name=self.window.renderer_name,
            )
        self.window.swap()
