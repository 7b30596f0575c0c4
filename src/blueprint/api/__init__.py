"""The Python API: frames (``render``, ``peel``: ``blueprint.api.frames``) and the file
workflows (a model, image or video file in, a picture, drawing, video or data file out:
``blueprint.api.files``), drawn with a renderer shared by every call that is given none; their
options as one checked value, ``DrawOptions`` (``blueprint.api.options``)."""

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


def default_renderer() -> Renderer:
    """The renderer ``render``, ``peel`` and the file workflows use when none is given (created
    on first use)."""
    global _renderer
    if _renderer is None:
        _renderer = Renderer()
    return _renderer
