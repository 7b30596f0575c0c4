"""The one place that creates OpenGL contexts."""

from __future__ import annotations

import os

from blueprint.errors import GLUnavailableError

MIN_GL = 330

_INSTALL_HINT = (
    "install an OpenGL driver with EGL: on Debian/Ubuntu 'apt-get install libegl1 libgl1-mesa-dri' "
    "(Mesa, software llvmpipe), or the NVIDIA driver for a GPU"
)


def create_context(backend: str | None = None):
    """Create a headless OpenGL >= 3.3 core context through EGL.

    EGL picks the GPU driver where there is one and Mesa's llvmpipe otherwise.
    ``BLUEPRINT_GL_BACKEND`` overrides ``backend`` (glcontext backend names, e.g. ``egl``).

    Raises
    ------
    GLUnavailableError
        With one line saying what to install.
    """
    import moderngl

    backend = os.environ.get("BLUEPRINT_GL_BACKEND", backend or "egl")
    reason = ""
    # Some drivers give exactly the version asked for: ask for 4.3 (compute shaders) first.
    for version in (430, MIN_GL):
        try:
            return moderngl.create_standalone_context(backend=backend, require=version)
        except Exception as exc:
            reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    raise GLUnavailableError(f"no usable OpenGL 3.3 context ({reason}): {_INSTALL_HINT}")


def gl_info(ctx) -> dict[str, str]:
    """Renderer, vendor and version strings of a context."""
    info = ctx.info
    return {
        "renderer": info["GL_RENDERER"],
        "vendor": info["GL_VENDOR"],
        "version": info["GL_VERSION"],
        "max_texture_size": str(info["GL_MAX_TEXTURE_SIZE"]),
    }
