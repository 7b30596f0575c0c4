"""The Python API: frames (``render``, ``peel``: ``blueprint.api.frames``) and the file
workflows (a model, image or video file in, a picture, drawing, video or data file out:
``blueprint.api.files``), drawn with a renderer shared by every call that is given none; their
options as one checked value, ``DrawOptions`` (``blueprint.api.options``)."""

import threading

from blueprint.api.frames import PLAN, peel, render, render_frame
from blueprint.api.options import DrawOptions
from blueprint.api.renderer import Renderer
from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.render.renderer import Frame, Layers
from blueprint.scene.camera import SHEET_CELLS, Camera, sheet_cameras
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model
from blueprint.scene.parts import designated_parts

__all__ = [
    "PLAN",
    "SHEET_CELLS",
    "Camera",
    "DrawOptions",
    "Frame",
    "Glyphs",
    "InputError",
    "Layers",
    "Model",
    "Renderer",
    "check_size",
    "default_renderer",
    "designated_parts",
    "load_glyphs",
    "load_model",
    "open_default_renderer",
    "peel",
    "render",
    "render_frame",
    "render_with_glyphs",
    "sheet_cameras",
]

_GLYPHS = ("Glyphs", "load_glyphs", "render_with_glyphs")


def __getattr__(name: str):
    # the glyph names load their package when first asked for: a plain drawing needs none of it
    if name in _GLYPHS:
        from blueprint.compose import glyphs

        return getattr(glyphs, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# Here, in the package, so that callers (the tests) can swap it: blueprint.api._renderer = r.
_renderer: Renderer | None = None
# (thread, what it made: {"renderer": ...} or {"error": ...}) of ``open_default_renderer``
_opening: tuple[threading.Thread, dict] | None = None


def default_renderer() -> Renderer:
    """The renderer ``render``, ``peel`` and the file workflows use when none is given (created
    on first use, or taken from ``open_default_renderer``'s thread, raising what it raised)."""
    global _renderer, _opening
    if _renderer is None:
        if _opening is None:
            _renderer = Renderer()
        else:
            thread, made = _opening
            _opening = None
            thread.join()
            if "error" in made:
                raise made["error"]
            _renderer = made["renderer"]
    return _renderer


def open_default_renderer() -> None:
    """Start making the default renderer on a thread of its own, beside what the caller does
    next (reading a model: a GPU driver takes a good part of a second to start), for
    ``default_renderer`` to take. Its context is left current in no thread, so that the thread
    that draws takes it (``Device.make_current``)."""
    global _opening
    if _renderer is not None or _opening is not None:
        return
    made: dict = {}

    def make() -> None:
        try:
            renderer = Renderer()
            renderer.ctx.__exit__(None, None, None)
            made["renderer"] = renderer
        except BaseException as exc:  # raised again where the renderer is taken
            made["error"] = exc

    # not a daemon: a process ending before the renderer is taken waits for its driver's start
    # rather than tearing the driver down under it
    thread = threading.Thread(target=make, name="blueprint-renderer")
    thread.start()
    _opening = (thread, made)
