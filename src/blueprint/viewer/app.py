"""The interactive window: GLFW opens it and delivers the events; every picture comes from the
same ``Renderer.render`` as ``blueprint render``, uploaded as a texture and drawn to the window
over the backdrop, scaled up where it is a draft, with the heads-up lines (drawn on the CPU) as
a second texture over it.

Frames are drawn only when something changed. While the view moves (drag, wheel, turntable)
frames are drafts: supersample 1 and, when that is slower than 30 fps, a lower resolution
scaled up; once the view rests for ``REFINE_DELAY`` seconds one full-quality frame follows.
``BLUEPRINT_VIEWER_DUMP=FOLDER`` writes every presented frame as a PNG (read back from the
window: what is shown) plus one JSON line of state to ``FOLDER/frames.jsonl`` (for tests and bug
reports).
"""

from __future__ import annotations

import json
import logging
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from blueprint.api.renderer import Renderer
from blueprint.compose.style import get_style
from blueprint.errors import BlueprintError, InputError
from blueprint.export.files import save_png
from blueprint.gpu.device import check_size
from blueprint.scene.model import Model
from blueprint.viewer.overlay import BACKDROP, LINE_HEIGHT, band_overlay, help_overlay, screenshot_path
from blueprint.viewer.state import VIEW_KEYS, ViewState

log = logging.getLogger("blueprint")

DUMP_ENV = "BLUEPRINT_VIEWER_DUMP"
PRESENT_FRAG = "blueprint.viewer:glsl/present.frag"
SUGGESTION = "draw to a file with 'blueprint render MODEL -o drawing.png' instead"
# Draft resolutions tried while the view moves, as fractions of the window.
DRAFT_SCALES = (1.0, 0.75, 0.5)
TARGET_MS = 1000.0 / 30.0
REFINE_DELAY = 0.2
# A press that moves less than this (pixels) before release is a click, not a drag.
CLICK_SLOP = 3.0
WARMUP_FRAMES = 2
# Layers searched for the parts behind a clicked spot (clicking it again).
PICK_DEPTH = 12
# Depth masking (M): peel until this fraction of the selected part's pixels shows.
REVEAL = 0.95
# How long a message (screenshot saved) stays in the heads-up lines.
STATUS_SECONDS = 5.0


class NoDisplayError(BlueprintError):
    """No window can be opened here (no display, no windowing library, no OpenGL 3.3)."""


@dataclass
class Options:
    """Rendering options passed through to ``Renderer.render`` (see there)."""

    grid: float | None = None
    min_fraction: float = 0.0
    crease_angle: float = 30.0
    line_width: float = 1.0
    supersample: int = 2
    interactive_scale: float = 0.0  # 0: automatic; otherwise a fixed fraction of the window


def _has_display() -> bool:
    if sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def _import_glfw():
    if not _has_display():
        raise NoDisplayError(f"no display to open a window on (DISPLAY is not set): {SUGGESTION}")
    try:
        import glfw
    except Exception as exc:  # the wheel bundles libglfw; its X11 libraries may be missing
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise NoDisplayError(f"cannot load the windowing library glfw ({reason}): {SUGGESTION}") from None
    return glfw


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
        self.dump = Path(dump) if dump else None
        self.glfw = _import_glfw()
        self.window = None
        self.renderer: Renderer | None = None
        self._errors: list[str] = []
        self._open(size)
        try:
            check_size(size, self.options.supersample, self.renderer.max_texture)
        except BlueprintError:
            self.close()
            raise
        # what is on screen
        self._drawing: np.ndarray | None = None  # the last full-quality drawing (RGBA)
        self._textures: dict[str, object] = {}  # the drawing on screen, the overlay
        self._overlay_key: tuple | None = None
        self._overlay_base: np.ndarray | None = None
        self._band_rows = 0
        self._last: dict = {}
        self._status = ""
        self._status_time = 0.0
        self._scale_index = 0
        self._frames = 0
        # what needs doing
        self._needs_render = True
        self._needs_present = False
        self._refine_at: float | None = None
        self._press: tuple | None = None
        self._cursor = tuple(self.glfw.get_cursor_pos(self.window))
        self._pick_spot: tuple | None = None  # (x, y, camera, parts behind it or None)
        self._moved = False
        self._last_scroll = -1.0
        self._last_spin = time.perf_counter()
        self._measure: list[tuple[float, float]] = []

    # -- window --------------------------------------------------------------------------------
    def _open(self, size: tuple[int, int]) -> None:
        glfw = self.glfw
        glfw.set_error_callback(self._on_error)
        if not glfw.init():
            reason = self._errors[-1] if self._errors else "initialisation failed"
            raise NoDisplayError(f"cannot open a window ({reason}): {SUGGESTION}")
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        glfw.window_hint(glfw.DEPTH_BITS, 0)
        glfw.window_hint(glfw.STENCIL_BITS, 0)
        title = f"blueprint view - {self.model_path.name}"
        window = glfw.create_window(int(size[0]), int(size[1]), title, None, None)
        if not window:
            reason = self._errors[-1] if self._errors else "no OpenGL 3.3 core context"
            glfw.terminate()
            raise NoDisplayError(f"cannot open a window ({reason}): {SUGGESTION}")
        self.window = window
        glfw.make_context_current(window)
        glfw.swap_interval(1)
        try:
            import moderngl

            ctx = moderngl.create_context(require=330)
            self.renderer = Renderer(ctx=ctx)
        except Exception as exc:
            glfw.destroy_window(window)
            glfw.terminate()
            if isinstance(exc, BlueprintError):
                raise
            raise NoDisplayError(
                f"the window has no usable OpenGL 3.3 context ({exc}): {SUGGESTION}"
            ) from None
        glfw.set_key_callback(window, self._on_key)
        glfw.set_mouse_button_callback(window, self._on_button)
        glfw.set_cursor_pos_callback(window, self._on_cursor)
        glfw.set_scroll_callback(window, self._on_scroll)
        glfw.set_framebuffer_size_callback(window, lambda *_: self._invalidate())
        glfw.set_window_refresh_callback(window, lambda *_: self._repaint())

    def _on_error(self, code, text) -> None:
        self._errors.append(text.decode(errors="replace") if isinstance(text, bytes) else str(text))

    def close(self) -> None:
        """Release the GL objects, the window and GLFW."""
        glfw = self.glfw
        if self.renderer is not None:
            for texture in self._textures.values():
                texture.release()
            self._textures.clear()
            self.renderer.release()
            self.renderer = None
        if self.window is not None:
            glfw.destroy_window(self.window)
            self.window = None
            glfw.terminate()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- loop ----------------------------------------------------------------------------------
    def run(self, frames: int = 0) -> dict | None:
        """Show the window until Esc or close. With ``frames`` > 0: spin the turntable for that
        many frames (after a warm-up), close, and return the measured timings."""
        glfw = self.glfw
        if frames > 0:
            self.state.turntable = True
        try:
            while not glfw.window_should_close(self.window):
                self._wait()
                now = time.perf_counter()
                if self.state.turntable:
                    self.state.spin(min(0.1, now - self._last_spin))
                    self._last_spin = now
                    self._needs_render = True
                if glfw.window_should_close(self.window):
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
                    self._measure.append((time.perf_counter(), self._last.get("ms", 0.0)))
                    if len(self._measure) >= frames + WARMUP_FRAMES:
                        break
        finally:
            result = self._timings() if frames > 0 else None
            self.close()
        return result

    def _wait(self) -> None:
        glfw = self.glfw
        if self._needs_render or self._needs_present or self.state.turntable:
            glfw.poll_events()
        elif self._refine_at is not None:
            glfw.wait_events_timeout(max(0.0, min(0.5, self._refine_at - time.perf_counter())))
        else:
            # a timeout, not a plain wait, so Ctrl+C in the terminal is noticed
            glfw.wait_events_timeout(0.5)

    def _moving(self, now: float) -> bool:
        return self.state.turntable or self._moved or now - self._last_scroll < REFINE_DELAY

    def _timings(self) -> dict:
        timed = self._measure[WARMUP_FRAMES:]
        if len(timed) < 2:
            return {"frames": len(timed)}
        start = self._measure[WARMUP_FRAMES - 1][0]
        wall = timed[-1][0] - start
        return {
            "model": self.model_path.name,
            "triangles": self.model.triangle_count,
            "renderer": self.renderer_name,
            "frames": len(timed),
            "fps": round(len(timed) / wall, 2),
            "ms": round(wall * 1e3 / len(timed), 2),
            "draw_ms_median": round(float(np.median([ms for _, ms in timed])), 2),
            "size": self._last.get("size"),
            "render_size": self._last.get("render_size"),
            "supersample": self._last.get("supersample"),
            "layers": self._last.get("layers"),
        }

    @property
    def renderer_name(self) -> str:
        return self.renderer.info["renderer"] if self.renderer is not None else "?"

    # -- events --------------------------------------------------------------------------------
    def _invalidate(self) -> None:
        self._needs_render = True

    def _repaint(self) -> None:
        self._needs_present = True

    def _on_key(self, window, key, scancode, action, mods) -> None:
        glfw = self.glfw
        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        state = self.state
        repeatable = {glfw.KEY_D}
        if action == glfw.REPEAT and key not in repeatable:
            return
        drawn = int(self._last.get("layers", 1) or 1)
        views = {getattr(glfw, f"KEY_{i + 1}"): name for i, name in enumerate(VIEW_KEYS)}
        views.update({getattr(glfw, f"KEY_KP_{i + 1}"): name for i, name in enumerate(VIEW_KEYS)})
        if key == glfw.KEY_ESCAPE:
            glfw.set_window_should_close(window, True)
        elif key == glfw.KEY_D:
            if mods & glfw.MOD_SHIFT:
                state.fewer_layers(drawn)
            else:
                state.more_layers(drawn)
            self._invalidate()
        elif key == glfw.KEY_A:
            state.all_layers()
            self._invalidate()
        elif key == glfw.KEY_S:
            state.next_style()
            self._invalidate()
        elif key in views:
            state.set_view(views[key])
            self._invalidate()
        elif key == glfw.KEY_M:
            state.toggle_mask()
            self._invalidate()
        elif key == glfw.KEY_O:
            state.toggle_ortho()
            self._invalidate()
        elif key == glfw.KEY_T:
            state.turntable = not state.turntable
            self._last_spin = time.perf_counter()
            if not state.turntable:
                self._refine_at = time.perf_counter() + REFINE_DELAY
        elif key == glfw.KEY_H:
            state.help = not state.help
            self._repaint()
        elif key == glfw.KEY_P:
            self._screenshot()

    def _on_button(self, window, button, action, mods) -> None:
        glfw = self.glfw
        # where the last motion event put the pointer: querying the pointer now would give
        # where it is after events still in the queue
        x, y = self._cursor
        if action == glfw.PRESS and self._press is None:
            self._press = (button, mods, x, y, x, y)
            self._moved = False
        elif action == glfw.RELEASE and self._press is not None and self._press[0] == button:
            clicked = button == glfw.MOUSE_BUTTON_LEFT and not self._moved
            if self._moved:
                self._refine_at = time.perf_counter() + REFINE_DELAY
            self._press = None
            self._moved = False
            if clicked:
                self._pick(x, y)

    def _on_cursor(self, window, x, y) -> None:
        self._cursor = (x, y)
        if self._press is None:
            return
        glfw = self.glfw
        button, mods, x0, y0, last_x, last_y = self._press
        if not self._moved and max(abs(x - x0), abs(y - y0)) < CLICK_SLOP:
            return
        self._moved = True
        dx, dy = x - last_x, y - last_y
        self._press = (button, mods, x0, y0, x, y)
        if button == glfw.MOUSE_BUTTON_LEFT and not mods & glfw.MOD_SHIFT:
            self.state.orbit(dx, dy)
        else:
            self.state.pan_by(dx, dy, glfw.get_window_size(window)[1])
        self._invalidate()

    def _on_scroll(self, window, dx, dy) -> None:
        self.state.zoom_by(dy)
        self._last_scroll = time.perf_counter()
        self._invalidate()

    # -- actions -------------------------------------------------------------------------------
    def _size(self) -> tuple[int, int]:
        return tuple(int(v) for v in self.glfw.get_framebuffer_size(self.window))

    def _parts_at(self, camera, size: tuple[int, int], px: int, py: int, layers: int) -> list[int]:
        """Distinct part indices at pixel (px, py) in the first ``layers`` depth layers, front first."""
        peeled = self.renderer.peel(
            self.model,
            camera,
            size=size,
            max_layers=layers,
            crease_angle=self.options.crease_angle,
        )
        found: list[int] = []
        for part in peeled.part[:, py, px].tolist():
            if part >= 0 and part not in found:
                found.append(part)
        return found

    def _pick(self, x: float, y: float) -> None:
        """Select the part under window point (x, y) from layer 0's part-ID buffer; a click on
        the same spot again selects the next part behind it (from deeper layers), round."""
        w, h = self._size()
        ww, wh = self.glfw.get_window_size(self.window)
        if w < 1 or h < 1:
            return
        px = min(w - 1, max(0, int(x * w / max(1, ww))))
        py = min(h - 1, max(0, int(y * h / max(1, wh))))
        camera = self.state.camera(self.model, w / h)
        spot = self._pick_spot
        again = (
            spot is not None
            and self.state.part is not None
            and spot[2] == camera
            and max(abs(px - spot[0]), abs(py - spot[1])) <= CLICK_SLOP
        )
        if not again:
            self._pick_spot = (px, py, camera, None)
            found = self._parts_at(camera, (w, h), px, py, 1)
            part = found[0] if found else None
        else:
            stack = spot[3]
            if stack is None:
                stack = self._parts_at(camera, (w, h), px, py, PICK_DEPTH)
                self._pick_spot = (*spot[:3], stack)
            i = stack.index(self.state.part) + 1 if self.state.part in stack else 0
            part = stack[i % len(stack)] if stack else None
        self.state.part = part
        self._invalidate()

    def _screenshot(self) -> None:
        """Save the current drawing (full quality, no heads-up lines) as NAME-N.png beside the model."""
        if self._drawing is None or self._needs_render:
            self._render(draft=False, present=False)
        if self._drawing is None:  # minimised: nothing drawn
            return
        path = screenshot_path(self.model_path)
        try:
            save_png(path, self._drawing)
        except BlueprintError as exc:
            self._status = f"screenshot failed: {exc}"
            log.warning(str(exc))
        else:
            self._status = f"saved {path.name}"
            h, w = self._drawing.shape[:2]
            print(f"{path}: screenshot {w}x{h}", flush=True)
        self._status_time = time.perf_counter()
        self._repaint()

    # -- drawing -------------------------------------------------------------------------------
    def _draft_scale(self) -> float:
        fixed = self.options.interactive_scale
        return fixed if fixed else DRAFT_SCALES[self._scale_index]

    def _adapt(self, ms: float) -> None:
        """Pick the next draft resolution so drafts come near 30 fps."""
        if self.options.interactive_scale:
            return
        if ms > TARGET_MS * 1.2 and self._scale_index < len(DRAFT_SCALES) - 1:
            self._scale_index += 1
        elif ms < TARGET_MS * 0.45 and self._scale_index > 0:
            self._scale_index -= 1

    def _render(self, draft: bool, present: bool = True) -> None:
        w, h = self._size()
        if w < 1 or h < 1:  # minimised
            self._needs_render = False
            return
        state, opts = self.state, self.options
        scale = self._draft_scale() if draft else 1.0
        supersample = 1 if draft else opts.supersample
        rw, rh = max(1, round(w * scale)), max(1, round(h * scale))
        camera = state.camera(self.model, w / h)
        common = dict(
            size=(rw, rh),
            max_layers=state.max_layers,
            min_fraction=opts.min_fraction,
            crease_angle=opts.crease_angle,
            line_width=opts.line_width,
            supersample=supersample,
        )
        highlight = reveal = None
        if state.part is not None:
            # the renderer's own highlight: the part's whole outline over everything, in the
            # style's highlight ink; M adds depth masking (peel until the part shows)
            highlight = np.arange(len(self.model.part_names)) == state.part
            reveal = REVEAL if state.mask else None
        t0 = time.perf_counter()
        frame = self.renderer.render(
            self.model,
            camera,
            style=get_style(state.style, opts.grid),
            highlight=highlight,
            reveal=reveal,
            **common,
        )
        drawing = frame.image
        self._drawing = None if draft else drawing
        # uploaded once a drawing; presenting again (heads-up lines, exposure) reuses it
        self._upload("picture", drawing)
        ms = (time.perf_counter() - t0) * 1e3
        if draft:
            self._adapt(ms)
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

    def _hud_lines(self) -> list[str]:
        state, last = self.state, self._last
        ms = last.get("ms", 0.0)
        fps = 1000.0 / ms if ms > 0 else 0.0
        limit = "all" if state.max_layers is None else str(state.max_layers)
        view = state.view if state.at_fit() else f"{state.view} (orbited)"
        quality = "" if last.get("quality") == "full" else f" | draft {last.get('scale', 1):g}"
        lines = [
            f"{fps:.1f} fps | {last.get('layers', 0)} layers (max {limit}) | "
            f"{self.model.triangle_count:,} triangles | {self.renderer_name} | {state.style} | "
            f"{view} {'ortho' if state.ortho else 'persp'}{quality} | H: help"
        ]
        extra = []
        if state.part is not None:
            count = int(np.count_nonzero(self.model.face_part == state.part))
            line = f"part {state.part}: {self.model.part_names[state.part]} ({count:,} triangles)"
            revealed = last.get("revealed")
            if state.mask and revealed is not None:
                line += f" | depth mask: {revealed:.0%} shown"
            extra.append(line)
        if self._status and time.perf_counter() - self._status_time < STATUS_SECONDS:
            extra.append(self._status)
        if extra:
            lines.append("   ".join(extra))
        return lines

    def _present(self) -> None:
        """The drawing over the backdrop, scaled to the window, the heads-up lines over it; swap."""
        self._needs_present = False
        picture = self._textures.get("picture")
        if picture is None:
            self._needs_render = True
            return
        w, h = self._size()
        if w < 1 or h < 1:
            return
        lines = self._hud_lines()
        ctx = self.renderer.ctx
        overlay = self._overlay((w, h), lines)
        prog, vao = self.renderer.fullscreen(PRESENT_FRAG)
        ctx.screen.use()
        ctx.viewport = (0, 0, w, h)
        ctx.disable(ctx.DEPTH_TEST | ctx.BLEND)
        picture.use(0)
        overlay.use(1)
        prog["u_picture"].value = 0
        prog["u_overlay"].value = 1
        prog["u_window"].value = (float(w), float(h))
        prog["u_backdrop"].value = tuple(c / 255.0 for c in BACKDROP)
        vao.render(vertices=3)
        self._frames += 1
        if self.dump is not None:  # read before the swap leaves the back buffer undefined
            shown = np.frombuffer(ctx.screen.read((0, 0, w, h), components=3, alignment=1), np.uint8)
            self._dump(shown.reshape(h, w, 3)[::-1], lines)
        self.glfw.swap_buffers(self.window)

    def _overlay(self, size: tuple[int, int], lines: list[str]):
        """The overlay texture: the help box redrawn when it or the window changes, the band of
        heads-up lines every frame (rows written down to the lower of this band and the last)."""
        w, h = size
        key = (w, h, self.state.help)
        if self._overlay_key != key:
            self._overlay_base = help_overlay(size, self.state.help)
            self._upload("overlay", self._overlay_base)
            self._overlay_key, self._band_rows = key, 0
        rows = min(h, max(self._band_rows, LINE_HEIGHT * len(lines)))
        texture = self._textures["overlay"]
        if rows:
            top = band_overlay(self._overlay_base[:rows], lines)
            texture.write(np.ascontiguousarray(top[::-1]).tobytes(), viewport=(0, h - rows, w, rows))
        self._band_rows = LINE_HEIGHT * len(lines)
        return texture

    def _upload(self, name: str, image: np.ndarray):
        """``image`` (H, W, 4) uint8, row 0 at the top, in the texture ``name`` (kept between
        frames, remade when the size changes)."""
        h, w = image.shape[:2]
        ctx = self.renderer.ctx
        texture = self._textures.get(name)
        if texture is None or texture.size != (w, h):
            if texture is not None:
                texture.release()
            texture = self._textures[name] = ctx.texture((w, h), 4, alignment=1)
            # drafts are scaled up bilinearly; a full-size picture lands on texel centres
            texture.filter = (ctx.LINEAR, ctx.LINEAR)
            texture.repeat_x = texture.repeat_y = False
        texture.write(np.ascontiguousarray(image[::-1]).tobytes())
        return texture

    def _dump(self, image: np.ndarray, lines: list[str]) -> None:
        self.dump.mkdir(parents=True, exist_ok=True)
        name = f"frame-{self._frames:05d}.png"
        save_png(self.dump / name, image)
        state = self.state
        record = {
            "n": self._frames,
            "file": name,
            **self._last,
            "max_layers": state.max_layers,
            "style": state.style,
            "view": state.view,
            "azimuth": state.azimuth,
            "elevation": state.elevation,
            "zoom": state.zoom,
            "pan": list(state.pan),
            "ortho": state.ortho,
            "turntable": state.turntable,
            "help": state.help,
            "mask": state.mask,
            "part": None if state.part is None else self.model.part_names[state.part],
            "part_index": state.part,
            "hud": lines,
            "hud_height": LINE_HEIGHT * len(lines),
            "renderer": self.renderer_name,
        }
        with open(self.dump / "frames.jsonl", "a", encoding="utf-8") as fh:
            fh.write(json.dumps(record) + "\n")


def run_viewer(
    model_path: str | os.PathLike,
    *,
    size: tuple[int, int] = (800, 600),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    up: str | None = None,
    style: str = "blueprint",
    styles: tuple[str, ...] = ("blueprint", "paper", "transparent", "wireframe"),
    max_layers: int | None = 5,
    options: Options | None = None,
    frames: int = 0,
) -> dict | None:
    """Open the viewer on a model file; returns when the window closes (see ``Viewer.run``)."""
    from blueprint.scene.loader import load_model

    _import_glfw()  # no display: say so before loading anything
    state = ViewState.start(styles, style, view, azimuth, elevation, fov, ortho, max_layers)
    options = options or Options()
    get_style(style, options.grid)
    model = load_model(model_path, up=up)
    viewer = Viewer(model, Path(model_path), state, size=size, options=options, dump=os.environ.get(DUMP_ENV))
    return viewer.run(frames=frames)
