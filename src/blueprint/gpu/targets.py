"""One owner of every render target: textures and framebuffers by (name, size, format)."""

from __future__ import annotations

import contextlib

from blueprint.errors import InputError

# (components, dtype) per format name; the G-buffer and the ops agree through these names
FORMATS: dict[str, tuple[int, str]] = {
    "r8": (1, "f1"),
    "rgba8": (4, "f1"),
    "r32f": (1, "f4"),
    "rg32f": (2, "f4"),
    "rgba16f": (4, "f2"),
    "rgba32f": (4, "f4"),
    "r32i": (1, "i4"),
    "rg32i": (2, "i4"),
}
# formats of the renderer's own targets, not offered to pipelines (k-buffer surfaces, A-buffer
# list heads)
INTERNAL_FORMATS: dict[str, tuple[int, str]] = {
    "rgba32ui": (4, "u4"),
    "rg32ui": (2, "u4"),
    "r32ui": (1, "u4"),
    "rg8": (2, "f1"),
}


# GL enums the slices of a viewed array (``SlicedArray``) are made with
_TEXTURE_2D, _TEXTURE_2D_ARRAY, _TEXTURE0 = 0x0DE1, 0x8C1A, 0x84C0
_NEAREST, _MIN_FILTER, _MAG_FILTER, _IMMUTABLE_FORMAT = 0x2600, 0x2801, 0x2800, 0x912F
_INTERNAL_FORMATS = {"rgba32ui": 0x8D70}


def _gl_entry_points():
    """The GL's own entry points of the current context (GLVND's libOpenGL), or None."""
    import ctypes

    try:
        gl = ctypes.CDLL("libOpenGL.so.0")
    except OSError:
        return None
    gl.glIsTexture.restype = ctypes.c_ubyte  # a GLboolean: one byte of the return register
    return gl


class SlicedArray:
    """A 2D texture array whose slices are also 2D textures (texture views, OpenGL 4.3): render
    targets a slice each (``slices``: moderngl attaches whole 2D textures alone), read by one
    sampler (``use``) where a sampler array indexed in a loop costs a software rasteriser a
    branch a fetch. Made through the GL's own entry points ``gl``: moderngl makes no views."""

    def __init__(self, ctx, gl, size: tuple[int, int], layers: int, fmt: str) -> None:
        import ctypes

        self.gl, self.size, self.layers = gl, tuple(size), layers
        internal, (components, dtype) = _INTERNAL_FORMATS[fmt], INTERNAL_FORMATS[fmt]
        name = ctypes.c_uint(0)
        gl.glGenTextures(1, ctypes.byref(name))
        self.glo = name.value
        gl.glBindTexture(_TEXTURE_2D_ARRAY, self.glo)
        gl.glTexStorage3D(_TEXTURE_2D_ARRAY, 1, internal, size[0], size[1], layers)
        gl.glTexParameteri(_TEXTURE_2D_ARRAY, _MIN_FILTER, _NEAREST)
        gl.glTexParameteri(_TEXTURE_2D_ARRAY, _MAG_FILTER, _NEAREST)
        # storage refused leaves the format mutable, a view refused leaves its name no texture:
        # asked so, not through the GL's error, which may hold another call's
        stored = ctypes.c_int(0)
        gl.glGetTexParameteriv(_TEXTURE_2D_ARRAY, _IMMUTABLE_FORMAT, ctypes.byref(stored))
        gl.glBindTexture(_TEXTURE_2D_ARRAY, 0)
        self.slices = ()
        for k in range(layers if stored.value else 0):
            view = ctypes.c_uint(0)
            gl.glGenTextures(1, ctypes.byref(view))
            gl.glTextureView(view.value, _TEXTURE_2D, self.glo, internal, 0, 1, k, 1)
            if not gl.glIsTexture(view.value):
                gl.glDeleteTextures(1, ctypes.byref(view))
                break
            tex = ctx.external_texture(view.value, tuple(size), components, 0, dtype)
            tex.filter = (ctx.NEAREST, ctx.NEAREST)
            self.slices += (tex,)
        if len(self.slices) < layers:  # (``_allocating`` says so)
            self.release()
            raise MemoryError

    def use(self, unit: int) -> None:
        """Bind the array to texture unit ``unit``."""
        self.gl.glActiveTexture(_TEXTURE0 + unit)
        self.gl.glBindTexture(_TEXTURE_2D_ARRAY, self.glo)

    def release(self) -> None:
        import ctypes

        # moderngl lets go of a texture it did not make without deleting it
        names = [tex.glo for tex in self.slices] + [self.glo]
        for tex in self.slices:
            tex.release()
        self.gl.glDeleteTextures(len(names), (ctypes.c_uint * len(names))(*names))
        self.slices = ()


class TargetPool:
    """Creates textures lazily, keeps them while their size and format stay, drops them on
    change. Passes borrow targets by name; only the pool releases them."""

    def __init__(self, ctx) -> None:
        self.ctx = ctx
        # name -> ((size, format), texture); a plain tuple: a frame looks up dozens
        self._textures: dict[str, tuple[tuple, object]] = {}
        self._framebuffers: dict[tuple, object] = {}
        # name -> (bytes, buffer): a buffer's own size is a call into the driver's wrapper
        self._buffers: dict[str, tuple[int, object]] = {}
        # objects made of the pool's targets (``held``), dropped with any target
        self._held: dict[tuple, object] = {}
        # the GL's own entry points, where the context makes texture views (``sliced``)
        self._gl = _gl_entry_points() if ctx.version_code >= 430 else None

    @property
    def slices_viewed(self) -> bool:
        """Whether ``sliced`` makes arrays whose slices are render targets."""
        return self._gl is not None

    def sliced(self, name: str, size: tuple[int, int], fmt: str, layers: int) -> SlicedArray:
        """The ``SlicedArray`` called ``name``, (re)created at ``size`` with ``layers`` slices of
        format ``fmt`` (``rgba32ui``); framebuffers over its ``slices`` as over textures."""
        key = ((*size, layers), fmt, "sliced")
        held = self._textures[name] if name in self._textures else None
        if held is not None and held[0] == key:
            return held[1]
        if held is not None:
            self._drop(name)
        with _allocating(size):
            array = SlicedArray(self.ctx, self._gl, size, layers, fmt)
        self._textures[name] = (key, array)
        return array

    def texture(self, name: str, size: tuple[int, int], fmt: str, layers: int = 0):
        """The texture called ``name``, (re)created at ``size`` in format ``fmt``; with
        ``layers`` > 0 a 2D texture array of that many slices."""
        key = ((*size, layers) if layers else (*size,), fmt)
        held = self._textures[name] if name in self._textures else None
        if held is not None and held[0] == key:
            return held[1]
        spec = FORMATS.get(fmt) or INTERNAL_FORMATS.get(fmt)
        if spec is None:
            raise ValueError(f"unknown target format {fmt!r} (choose {', '.join(FORMATS)})")
        if held is not None:
            self._drop(name)
        components, dtype = spec
        with _allocating(size):
            if layers:
                tex = self.ctx.texture_array((*size, layers), components, dtype=dtype)
            else:
                tex = self.ctx.texture(tuple(size), components, dtype=dtype)
        tex.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        tex.repeat_x = tex.repeat_y = False
        self._textures[name] = (key, tex)
        return tex

    def depth(self, name: str, size: tuple[int, int]):
        """A depth texture, readable by shaders (comparison off) as window depth in [0, 1]."""
        key = (tuple(size), "depth")
        held = self._textures.get(name)
        if held is not None and held[0] == key:
            return held[1]
        if held is not None:
            self._drop(name)
        with _allocating(size):
            tex = self.ctx.depth_texture(tuple(size))
        tex.compare_func = ""
        tex.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        tex.repeat_x = tex.repeat_y = False
        self._textures[name] = (key, tex)
        return tex

    def held_bytes(self) -> dict[str, int]:
        """Bytes of every texture and buffer the pool holds, by name (depth textures four a
        texel)."""
        out = {name: nbytes for name, (nbytes, _) in self._buffers.items()}
        for name, (key, _) in self._textures.items():
            texels = 1
            for side in key[0]:
                texels *= side
            if key[1] == "depth":
                out[name] = 4 * texels
            else:
                components, dtype = FORMATS.get(key[1]) or INTERNAL_FORMATS[key[1]]
                out[name] = components * int(dtype[1:]) * texels
        return out

    def framebuffer(self, colors: tuple, depth=None):
        """A framebuffer over pool textures, cached while its attachments live."""
        key = (tuple(map(id, colors)), id(depth) if depth is not None else None)
        fbo = self._framebuffers[key] if key in self._framebuffers else None
        if fbo is None:
            size = (colors[0] if colors else depth).size
            with _allocating(size):
                fbo = self.ctx.framebuffer(color_attachments=list(colors), depth_attachment=depth)
            self._framebuffers[key] = (fbo, colors, depth)
            return fbo
        return fbo[0]

    def held(self, key: tuple, make):
        """What ``make()`` returns, kept under ``key`` until the pool drops or replaces any of
        its targets (a frame's G-buffer: a dozen look-ups a frame otherwise). ``key`` must name
        everything ``make`` depends on but the pool's targets."""
        if key in self._held:
            return self._held[key]
        value = self._held[key] = make()
        return value

    def _drop(self, name: str) -> None:
        self._held.clear()
        old = self._textures.pop(name)[1]
        parts = (old, *getattr(old, "slices", ()))
        for key, (fbo, colors, depth) in list(self._framebuffers.items()):
            if any(c is part for c in colors for part in parts) or depth is old:
                self._unbind(fbo)
                fbo.release()
                del self._framebuffers[key]
        old.release()

    def buffer(self, name: str, nbytes: int):
        """The storage buffer called ``name`` holding at least ``nbytes``: kept while it is big
        enough, replaced by one of the size asked for when it is not."""
        if name in self._buffers:
            size, held = self._buffers[name]
            if size >= nbytes:
                return held
            self._held.clear()
            held.release()
            del self._buffers[name]
        try:
            buf = self.ctx.buffer(reserve=max(int(nbytes), 4))
        except Exception:
            raise InputError(
                f"{name}: {nbytes / 2**20:.0f} MiB of GPU memory could not be allocated (try a smaller size)"
            ) from None
        self._buffers[name] = (buf.size, buf)
        return buf

    def _unbind(self, fbo) -> None:
        # moderngl re-binds its idea of the current framebuffer: never leave it a deleted one
        if self.ctx.fbo is fbo:
            self.ctx.detect_framebuffer(0).use()

    def release(self) -> None:
        self._held.clear()
        for fbo, _, _ in self._framebuffers.values():
            self._unbind(fbo)
            fbo.release()
        for _, tex in self._textures.values():
            tex.release()
        for _, buf in self._buffers.values():
            buf.release()
        self._framebuffers.clear()
        self._textures.clear()
        self._buffers.clear()


@contextlib.contextmanager
def _allocating(size):
    """Turn a driver's refusal to allocate (out of memory, incomplete framebuffer) into a
    user error naming the size."""
    try:
        yield
    except (MemoryError, Exception) as exc:
        if isinstance(exc, InputError | ValueError):
            raise
        w, h = size[0], size[1]
        raise InputError(
            f"size {w}x{h}: its render targets need more memory than the GPU has (try a smaller size)"
        ) from None
