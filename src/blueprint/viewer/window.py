"""The window and its OpenGL context: GLFW, loaded only when a window is opened; a window with an
OpenGL 3.3 core context; the ``Renderer`` that draws with that context. Whatever stops a window
from opening is a ``NoDisplayError`` that suggests drawing to a file instead."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable

from blueprint.api.renderer import Renderer
from blueprint.errors import BlueprintError

SUGGESTION = "draw to a file with 'blueprint render MODEL -o drawing.png' instead"


class NoDisplayError(BlueprintError):
    """No window can be opened here (no display, no windowing library, no OpenGL 3.3)."""


def _has_display() -> bool:
    if sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def import_glfw():
    """The glfw module, or a ``NoDisplayError`` saying why there is none to use."""
    if not _has_display():
        raise NoDisplayError(f"no display to open a window on (DISPLAY is not set): {SUGGESTION}")
    try:
        import glfw
    except Exception as exc:  # the wheel bundles libglfw; its X11 libraries may be missing
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise NoDisplayError(f"cannot load the windowing library glfw ({reason}): {SUGGESTION}") from None
    return glfw


class Window:
    """A GLFW window whose OpenGL 3.3 core context is current, and the renderer drawing with it.

    Attributes
    ----------
    glfw : module
        The windowing library, for its constants and event calls.
    handle
        The GLFW window; None once closed.
    renderer : Renderer or None
        Draws with the window's context; None once closed.
    """

    def __init__(self, size: tuple[int, int], title: str) -> None:
        self.glfw = import_glfw()
        self.handle = None
        self.renderer: Renderer | None = None
        self._errors: list[str] = []
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
        handle = glfw.create_window(int(size[0]), int(size[1]), title, None, None)
        if not handle:
            reason = self._errors[-1] if self._errors else "no OpenGL 3.3 core context"
            glfw.terminate()
            raise NoDisplayError(f"cannot open a window ({reason}): {SUGGESTION}")
        self.handle = handle
        glfw.make_context_current(handle)
        glfw.swap_interval(1)
        try:
            import moderngl

            ctx = moderngl.create_context(require=330)
            self.renderer = Renderer(ctx=ctx)
        except Exception as exc:
            glfw.destroy_window(handle)
            glfw.terminate()
            if isinstance(exc, BlueprintError):
                raise
            raise NoDisplayError(
                f"the window has no usable OpenGL 3.3 context ({exc}): {SUGGESTION}"
            ) from None

    def _on_error(self, code, text) -> None:
        self._errors.append(text.decode(errors="replace") if isinstance(text, bytes) else str(text))

    def listen(
        self,
        *,
        key: Callable,
        button: Callable,
        cursor: Callable,
        scroll: Callable,
        resize: Callable,
        refresh: Callable,
    ) -> None:
        """Deliver the window's events to these callbacks (GLFW's signatures)."""
        glfw, handle = self.glfw, self.handle
        glfw.set_key_callback(handle, key)
        glfw.set_mouse_button_callback(handle, button)
        glfw.set_cursor_pos_callback(handle, cursor)
        glfw.set_scroll_callback(handle, scroll)
        glfw.set_framebuffer_size_callback(handle, resize)
        glfw.set_window_refresh_callback(handle, refresh)

    def size(self) -> tuple[int, int]:
        """The framebuffer's size in pixels (0 while minimised)."""
        return tuple(int(v) for v in self.glfw.get_framebuffer_size(self.handle))

    def swap(self) -> None:
        self.glfw.swap_buffers(self.handle)

    @property
    def renderer_name(self) -> str:
        return self.renderer.info["renderer"] if self.renderer is not None else "?"

    def close(self) -> None:
        """Release the renderer, the window and GLFW; safe to call again."""
        if self.renderer is not None:
            self.renderer.release()
            self.renderer = None
        if self.handle is not None:
            self.glfw.destroy_window(self.handle)
            self.handle = None
            self.glfw.terminate()
