"""The one place that creates OpenGL contexts, and the EGL devices they can be made on."""

from __future__ import annotations

import functools
import os
import re

from blueprint.errors import GLUnavailableError, InputError

MIN_GL = 330

#: Environment variable naming the EGL device index of contexts created without one.
DEVICE_VARIABLE = "BLUEPRINT_GL_DEVICE"

_INSTALL_HINT = (
    "install an OpenGL driver with EGL: on Debian/Ubuntu 'apt-get install libegl1 libgl1-mesa-dri' "
    "(Mesa, software llvmpipe), or the NVIDIA driver for a GPU"
)
_SOFTWARE = ("llvmpipe", "softpipe", "swrast")
_LIBGL, _LIBEGL = "libGL.so.1", "libEGL.so.1"


def _device_from_environment() -> int | None:
    value = os.environ.get(DEVICE_VARIABLE, "").strip()
    if not value:
        return None
    if not value.isdigit():
        raise InputError(f"{DEVICE_VARIABLE}={value!r}: give an EGL device index (0, 1, ...)")
    return int(value)


def create_context(backend: str | None = None, device: int | None = None):
    """Create a headless OpenGL >= 3.3 core context through EGL.

    Parameters
    ----------
    backend : str, optional
        A glcontext backend name (default ``egl``); ``BLUEPRINT_GL_BACKEND`` overrides it.
    device : int, optional
        The EGL device index (``egl_devices`` lists them); default ``BLUEPRINT_GL_DEVICE``,
        else the driver's choice: the GPU driver where there is one, Mesa's llvmpipe otherwise.

    Raises
    ------
    InputError
        ``device`` is not an EGL device of this machine (one line giving how many there are).
    GLUnavailableError
        With one line saying what to install.
    """
    import moderngl

    backend = os.environ.get("BLUEPRINT_GL_BACKEND", backend or "egl")
    if device is None:
        device = _device_from_environment()
    if device is not None:
        _check_device(device)
    extra = {} if device is None else {"device_index": int(device)}
    if backend == "egl":
        # the libraries by soname, which is what glcontext would find: its own lookup runs
        # ldconfig twice (ctypes.util.find_library) at every start
        # (GLCONTEXT_LINUX_LIBGL and GLCONTEXT_LINUX_LIBEGL still override these)
        extra.update(libgl=_LIBGL, libegl=_LIBEGL)
    reason = ""
    # Some drivers give exactly the version asked for: ask for 4.3 (compute shaders) first.
    for version in (430, MIN_GL):
        try:
            return moderngl.create_standalone_context(backend=backend, require=version, **extra)
        except Exception as exc:
            reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            found = re.search(r"requested device index \d+, but found (\d+) devices", reason)
            if found:
                raise InputError(_no_such_device(device, int(found.group(1)))) from None
    raise GLUnavailableError(f"no usable OpenGL 3.3 context ({reason}): {_INSTALL_HINT}")


def _no_such_device(device: int, count: int) -> str:
    have = {0: "no EGL devices", 1: "one EGL device, 0"}.get(count, f"EGL devices 0 to {count - 1}")
    return f"EGL device {device} does not exist: this machine has {have} (see 'blueprint info')"


def _check_device(device) -> None:
    if isinstance(device, bool) or not isinstance(device, int) or device < 0:
        raise InputError(f"EGL device index must be a whole number >= 0, got {device!r}")
    count = egl_device_count()
    if count is not None and device >= count:
        raise InputError(_no_such_device(device, count))


def egl_device_count() -> int | None:
    """The number of EGL devices (``eglQueryDevicesEXT``), or None where EGL cannot say."""
    # imported here: ctypes.util brings subprocess, tempfile and shutil into every drawing's
    # start, and only a device asked for by index needs it
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("EGL")
    if name is None:
        return None
    try:
        egl = ctypes.CDLL(name)
    except OSError:
        return None
    egl.eglGetProcAddress.restype = ctypes.c_void_p
    egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
    address = egl.eglGetProcAddress(b"eglQueryDevicesEXT")
    if not address:
        return None
    query = ctypes.CFUNCTYPE(ctypes.c_uint, ctypes.c_int, ctypes.c_void_p, ctypes.POINTER(ctypes.c_int))(
        address
    )
    count = ctypes.c_int(0)
    if not query(0, None, ctypes.byref(count)):
        return None
    return int(count.value)


def egl_devices() -> list[dict[str, object]]:
    """Every EGL device a context can be created on: ``index``, ``renderer`` (its
    ``GL_RENDERER``, or why no context could be made there) and ``gpu`` (False for software
    renderers such as llvmpipe). Creates and releases one context per device."""
    count = egl_device_count()
    devices = []
    for index in range(count if count is not None else 1):
        try:
            ctx = create_context(device=index if count is not None else None)
        except (InputError, GLUnavailableError) as exc:
            devices.append({"index": index, "renderer": f"unusable: {exc}", "gpu": False})
            continue
        renderer = ctx.info["GL_RENDERER"]
        ctx.release()
        software = any(name in renderer.lower() for name in _SOFTWARE)
        devices.append({"index": index, "renderer": renderer, "gpu": not software})
    return devices


def gl_info(ctx) -> dict[str, str]:
    """Renderer, vendor and version strings of a context."""
    info = ctx.info
    return {
        "renderer": info["GL_RENDERER"],
        "vendor": info["GL_VENDOR"],
        "version": info["GL_VERSION"],
        "max_texture_size": str(info["GL_MAX_TEXTURE_SIZE"]),
    }


@functools.cache
def _gl_flush():
    import ctypes

    try:
        return ctypes.CDLL(_LIBGL).glFlush
    except (OSError, AttributeError):
        return None


def gl_flush() -> None:
    """``glFlush`` on the current context, which moderngl does not offer: the driver starts on
    the commands given so far while the caller goes on, where a software rasteriser would
    otherwise start only once something waits for them. A hint (nothing where the GL library
    does not load): no result depends on it."""
    flush = _gl_flush()
    if flush is not None:
        flush()
