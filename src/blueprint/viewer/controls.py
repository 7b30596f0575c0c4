"""Keys and mouse: keys change the view state, a left drag orbits, a right or Shift+left drag pans,
the wheel zooms, and a click picks the part under the pointer (again on the same spot: the part
behind it). Every change asks the viewer for a new frame or a repaint."""

from __future__ import annotations

import time
from typing import Protocol

from blueprint.scene.model import Model
from blueprint.viewer.state import VIEW_KEYS, Options, ViewState
from blueprint.viewer.window import Window

# A press that moves less than this (pixels) before release is a click, not a drag.
CLICK_SLOP = 3.0
# Layers searched for the parts behind a clicked spot (clicking it again).
PICK_DEPTH = 12


class Steered(Protocol):
    """What the controls steer: the viewer (``viewer.loop.Viewer``), as they see it."""

    window: Window
    state: ViewState
    model: Model
    options: Options

    @property
    def layers_drawn(self) -> int: ...

    def invalidate(self) -> None: ...

    def repaint(self) -> None: ...

    def refine_later(self) -> None: ...

    def toggle_turntable(self) -> None: ...

    def screenshot(self) -> None: ...


class Controls:
    """The viewer's input: GLFW's key, button, cursor and scroll callbacks.

    Attributes
    ----------
    moved : bool
        A button is held and has dragged past ``CLICK_SLOP``.
    last_scroll : float
        ``time.perf_counter()`` of the last wheel event.
    """

    def __init__(self, viewer: Steered) -> None:
        self.viewer = viewer
        self.glfw = viewer.window.glfw
        self.moved = False
        self.last_scroll = -1.0
        self._press: tuple | None = None
        self._cursor = tuple(self.glfw.get_cursor_pos(viewer.window.handle))
        self._pick_spot: tuple | None = None  # (x, y, camera, parts behind it or None)

    def on_key(self, window, key, scancode, action, mods) -> None:
        glfw, viewer = self.glfw, self.viewer
        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        state = viewer.state
        repeatable = {glfw.KEY_D}
        if action == glfw.REPEAT and key not in repeatable:
            return
        drawn = viewer.layers_drawn
        views = {getattr(glfw, f"KEY_{i + 1}"): name for i, name in enumerate(VIEW_KEYS)}
        views.update({getattr(glfw, f"KEY_KP_{i + 1}"): name for i, name in enumerate(VIEW_KEYS)})
        if key == glfw.KEY_ESCAPE:
            glfw.set_window_should_close(window, True)
        elif key == glfw.KEY_D:
            if mods & glfw.MOD_SHIFT:
                state.fewer_layers(drawn)
            else:
                state.more_layers(drawn)
            viewer.invalidate()
        elif key == glfw.KEY_A:
            state.all_layers()
            viewer.invalidate()
        elif key == glfw.KEY_S:
            state.next_style()
            viewer.invalidate()
        elif key in views:
            state.set_view(views[key])
            viewer.invalidate()
        elif key == glfw.KEY_M:
            state.toggle_mask()
            viewer.invalidate()
        elif key == glfw.KEY_O:
            state.toggle_ortho()
            viewer.invalidate()
        elif key == glfw.KEY_T:
            viewer.toggle_turntable()
        elif key == glfw.KEY_H:
            state.help = not state.help
            viewer.repaint()
        elif key == glfw.KEY_P:
            viewer.screenshot()

    def on_button(self, window, button, action, mods) -> None:
        glfw = self.glfw
        # where the last motion event put the pointer: querying the pointer now would give
        # where it is after events still in the queue
        x, y = self._cursor
        if action == glfw.PRESS and self._press is None:
            self._press = (button, mods, x, y, x, y)
            self.moved = False
        elif action == glfw.RELEASE and self._press is not None and self._press[0] == button:
            clicked = button == glfw.MOUSE_BUTTON_LEFT and not self.moved
            if self.moved:
                self.viewer.refine_later()
            self._press = None
            self.moved = False
            if clicked:
                self._pick(x, y)

    def on_cursor(self, window, x, y) -> None:
        self._cursor = (x, y)
        if self._press is None:
            return
        glfw = self.glfw
        button, mods, x0, y0, last_x, last_y = self._press
        if not self.moved and max(abs(x - x0), abs(y - y0)) < CLICK_SLOP:
            return
        self.moved = True
        dx, dy = x - last_x, y - last_y
        self._press = (button, mods, x0, y0, x, y)
        if button == glfw.MOUSE_BUTTON_LEFT and not mods & glfw.MOD_SHIFT:
            self.viewer.state.orbit(dx, dy)
        else:
            self.viewer.state.pan_by(dx, dy, glfw.get_window_size(window)[1])
        self.viewer.invalidate()

    def on_scroll(self, window, dx, dy) -> None:
        self.viewer.state.zoom_by(dy)
        self.last_scroll = time.perf_counter()
        self.viewer.invalidate()

    # -- picking -------------------------------------------------------------------------------
    def _parts_at(self, camera, size: tuple[int, int], px: int, py: int, layers: int) -> list[int]:
        """Distinct part indices at pixel (px, py) in the first ``layers`` depth layers, front first."""
        viewer = self.viewer
        peeled = viewer.window.renderer.peel(
            viewer.model,
            camera,
            size=size,
            max_layers=layers,
            crease_angle=viewer.options.crease_angle,
        )
        found: list[int] = []
        for part in peeled.part[:, py, px].tolist():
            if part >= 0 and part not in found:
                found.append(part)
        return found

    def _pick(self, x: float, y: float) -> None:
        """Select the part under window point (x, y) from layer 0's part-ID buffer; a click on
        the same spot again selects the next part behind it (from deeper layers), round."""
        viewer = self.viewer
        w, h = viewer.window.size()
        ww, wh = self.glfw.get_window_size(viewer.window.handle)
        if w < 1 or h < 1:
            return
        px = min(w - 1, max(0, int(x * w / max(1, ww))))
        py = min(h - 1, max(0, int(y * h / max(1, wh))))
        camera = viewer.state.camera(viewer.model, w / h)
        spot = self._pick_spot
        again = (
            spot is not None
            and viewer.state.part is not None
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
            i = stack.index(viewer.state.part) + 1 if viewer.state.part in stack else 0
            part = stack[i % len(stack)] if stack else None
        viewer.state.part = part
        viewer.invalidate()
