"""Waiting for the GPU a draw behind: fence syncs (OpenGL 3.2) through the GL's own entry
points, which moderngl does not make."""

from __future__ import annotations

import ctypes
import functools

_SYNC_GPU_COMMANDS_COMPLETE = 0x9117
_SYNC_FLUSH_COMMANDS_BIT = 0x1
_TIMEOUT_EXPIRED, _WAIT_FAILED = 0x911B, 0x911D
# nanoseconds a wait lasts before it is taken again, so that Ctrl-C is seen between waits
_WAIT_NS = 100_000_000


@functools.cache
def _entry_points():
    """libOpenGL's fence entry points (GLVND), or None where it has none."""
    try:
        gl = ctypes.CDLL("libOpenGL.so.0")
        gl.glFenceSync.restype = ctypes.c_void_p
        gl.glFenceSync.argtypes = [ctypes.c_uint, ctypes.c_uint]
        gl.glClientWaitSync.restype = ctypes.c_uint
        gl.glClientWaitSync.argtypes = [ctypes.c_void_p, ctypes.c_uint, ctypes.c_uint64]
        gl.glDeleteSync.argtypes = [ctypes.c_void_p]
    except (OSError, AttributeError):
        return None
    return gl


class OneAhead:
    """Draws given while the one before is drawn: ``drawn()`` after a draw fences it, sends it
    to the GPU and waits until the draw before it is done, so a driver that holds a draw's
    triangles until it has drawn them (llvmpipe) holds two draws' at most, and sets up the
    next while it rasterises the last. ``close()`` after the last draw waits for nothing more.
    Where the GL has no fence entry points, each draw is waited for (``ctx.finish``)."""

    def __init__(self, ctx) -> None:
        self.ctx, self.gl, self.fence = ctx, _entry_points(), None

    def drawn(self) -> None:
        if self.gl is None:
            self.ctx.finish()
            return
        fence = self.gl.glFenceSync(_SYNC_GPU_COMMANDS_COMPLETE, 0)
        self.gl.glFlush()
        self._wait()
        self.fence = fence
        if not fence:
            self.ctx.finish()

    def _wait(self) -> None:
        if not self.fence:
            return
        fence, self.fence = self.fence, None
        wait = self.gl.glClientWaitSync
        try:
            while (done := wait(fence, _SYNC_FLUSH_COMMANDS_BIT, _WAIT_NS)) == _TIMEOUT_EXPIRED:
                pass
        finally:
            self.gl.glDeleteSync(fence)
        if done == _WAIT_FAILED:
            self.ctx.finish()

    def close(self) -> None:
        if self.fence:
            self.gl.glDeleteSync(self.fence)
            self.fence = None
