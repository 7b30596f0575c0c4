"""The viewer and its drawing loop: every picture comes from the same ``Renderer.render`` as
``blueprint render``, drawn only when something changed.

While the view moves (drag, wheel, turntable) each frame is drawn at the richest quality of a
ladder (``pacing``) that keeps the frame rate asked for, by what the last frames measured;
once the view rests for ``REFINE_DELAY`` seconds, the full drawing follows, once.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from blueprint.compose.lookup import get_style
from blueprint.errors import BlueprintError
from blueprint.gpu.device import check_size
from blueprint.scene.model import Model
from blueprint.viewer.controls import Controls
from blueprint.viewer.lod import coarse_model
from blueprint.viewer.pacing import COARSE_ABOVE, FrameRate, Pacer, Step
from blueprint.viewer.present import Presenter, hud_lines
from blueprint.viewer.snapshots import FrameDump, save_screenshot
from blueprint.viewer.state import Options, ViewState
from blueprint.viewer.window import Window

# Seconds the view rests before the full drawing follows the moving frames.
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
        self.dump = FrameDump(Path(dump)) if dump else None
        self.window = Window(size, f"blueprint view - {self.model_path.name}")
        try:
            check_size(size, self.options.supersample, self.window.renderer.max_texture)
        except BlueprintError:
            self.window.close()
            raise
        self.presenter = Presenter(self.window)
        self.controls = Controls(self)
        # kept from the resize callback: asking the window every frame waits on the display
        self._size = self.window.size()
        self.window.listen(
            key=self.controls.on_key,
            button=self.controls.on_button,
            cursor=self.controls.on_cursor,
            scroll=self.controls.on_scroll,
            resize=self._resized,
            refresh=lambda *_: self.repaint(),
        )
        self._drawing: np.ndarray | None = None  # the last full drawing (RGBA), read back
        self._last: dict = {}  # how the last frame was drawn
        self._status = ""
        self._status_time = 0.0
        self.pacer = Pacer(
            self.options.moving_fps,
            fixed_scale=self.options.interactive_scale,
            coarse=model.triangle_count > COARSE_ABOVE,
        )
        self._coarse: Model | None = None
        self._drawn: set[int] = set()  # the models drawn once (their first frame uploads them)
        self._drawn_as: tuple | None = None  # how the last frame was drawn: model, size, supersample, layers
        self._rate = FrameRate()
        self._shown_ms = (0.0, -RATE_SECONDS)  # (the frame time shown, when it was taken)
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
        """The full drawing once the view has rested for ``REFINE_DELAY``."""
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
            self._render(moving=False, present=False)
        if self._drawing is None:  # minimised: nothing drawn
            return
        self._status = save_screenshot(self.model_path, self._drawing)
        self._status_time = time.perf_counter()
        self.repaint()

    def _resized(self, window, width: int, height: int) -> None:
        self._size = (int(width), int(height))
        self.invalidate()

    # -- loop ----------------------------------------------------------------------------------
    def run(self, frames: int = 0, still_frames: int | None = None) -> dict | None:
        """Show the window until Esc or close. With ``frames`` > 0: spin the turntable for that
        many frames (after a warm-up), then draw ``still_frames`` (default ``frames``) full
        drawings of the view it stopped at, close, and return both frame rates."""
        glfw, handle = self.window.glfw, self.window.handle
        if frames > 0:
            self.state.turntable = True
        result = None
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
                    moving = self._moving(now)
                    self._render(moving)
                    self._refine_at = time.perf_counter() + REFINE_DELAY if moving else None
                elif self._refine_at is not None and now >= self._refine_at:
                    self._render(moving=False)
                    self._refine_at = None
                elif self._needs_present:
                    self._present()
                if frames > 0:
                    self._rate.tick(self._last.get("frame_ms", 0.0), self._last.get("step", ""))
                    if self._rate.done(frames):
                        result = self._measured(frames if still_frames is None else still_frames)
                        break
        finally:
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

    def _measured(self, still_frames: int) -> dict:
        """The turntable's frame rate, then that of ``still_frames`` full drawings."""
        moving = self._rate.report()
        self.state.turntable = False
        still = FrameRate()
        while not still.done(still_frames):
            self._render(moving=False)
            still.tick(self._last.get("frame_ms", 0.0), self._last.get("step", ""))
        about = {
            "model": self.model_path.name,
            "triangles": self.model.triangle_count,
            "renderer": self.window.renderer_name,
            "size": list(self._size),
            "moving_fps": self.options.moving_fps,
        }
        return {**about, **moving, "still": still.report()}

    # -- drawing -------------------------------------------------------------------------------
    def _model_for(self, step: Step) -> Model:
        """The model, or its coarse mesh (made when first asked for) where ``step`` draws that."""
        if not step.coarse:
            return self.model
        if self._coarse is None:
            self._coarse = coarse_model(self.model)
        return self._coarse

    def _render(self, moving: bool, present: bool = True) -> None:
        """A frame: the full drawing, or while ``moving`` the pacer's step; shown (and its time
        from the render call to the swap measured for the pacer) unless ``present`` is False."""
        w, h = self._size
        if w < 1 or h < 1:  # minimised
            self._needs_render = False
            return
        state, opts, pacer = self.state, self.options, self.pacer
        pacer.settle((w, h, opts.supersample, state.max_layers), opts.supersample, state.max_layers)
        index = pacer.next_step() if moving else pacer.full_index
        step = pacer.steps[index] if moving else pacer.full
        model = self._model_for(step)
        rw, rh = max(1, round(w * step.scale)), max(1, round(h * step.scale))
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
            model,
            camera,
            style=style,
            highlight=highlight,
            reveal=reveal,
            size=(rw, rh),
            max_layers=step.layers,
            min_fraction=opts.min_fraction,
            crease_angle=opts.crease_angle,
            line_width=opts.line_width,
            supersample=step.supersample,
            smooth_contours=opts.smooth_contours and not moving,
            # shown from the GPU; a screenshot (not presented at once) reads its drawing back
            on_gpu=present,
        )
        self._drawing = None if moving else frame.image
        if frame.texture is not None:
            self.presenter.show_texture(frame.texture, opaque)
        else:
            self.presenter.show(frame.image, opaque)
        ms = (time.perf_counter() - t0) * 1e3
        self._last = {
            "quality": "moving" if moving else "full",
            "step": step.label if moving else "full",
            "size": [w, h],
            "render_size": [rw, rh],
            "scale": step.scale,
            "supersample": step.supersample,
            "layers": frame.layers,
            "coarse": step.coarse,
            "triangles": model.triangle_count,
            "revealed": frame.revealed,
            "ms": ms,
            "frame_ms": ms,
        }
        self._needs_render = False
        before, self._drawn_as = self._drawn_as, (id(model), rw, rh, step.supersample, step.layers)
        # a model's first frame prepares and uploads it: not what its frames cost
        first = id(model) not in self._drawn
        self._drawn.add(id(model))
        if not present:
            self._needs_present = True
            return
        dumping = self._present()
        frame_ms = (time.perf_counter() - t0 - dumping) * 1e3
        self._last["frame_ms"] = frame_ms
        if not first and index is not None:
            pacer.record(index, frame_ms, cold=self._drawn_as != before)
        done = time.perf_counter()
        if done - self._shown_ms[1] >= RATE_SECONDS or not moving:
            self._shown_ms = (frame_ms, done)

    def _present(self) -> float:
        """The drawing, scaled to the window, the heads-up lines over it; dumped where asked; swap.
        Returns the seconds the dump took."""
        self._needs_present = False
        if not self.presenter.has_picture:
            self._needs_render = True
            return 0.0
        size = self._size
        if size[0] < 1 or size[1] < 1:
            return 0.0
        fresh = self._status and time.perf_counter() - self._status_time < STATUS_SECONDS
        status = self._status if fresh else ""
        last = {**self._last, "ms": self._shown_ms[0]}
        lines = hud_lines(self.state, self.model, last, self.window.renderer_name, status)
        self.presenter.draw(size, lines, self.state.help)
        dumping = 0.0
        if self.dump is not None:
            start = time.perf_counter()
            self.dump.write(
                self.presenter.read(size),
                lines,
                last=self._last,
                state=self.state,
                model=self.model,
                renderer_name=self.window.renderer_name,
            )
            dumping = time.perf_counter() - start
        self.window.swap()
        return dumping
