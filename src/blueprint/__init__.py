"""blueprint: drawings of the visible and hidden edges of 3D models, computed on the GPU.

Names are imported when first used (PEP 562), so that ``import blueprint`` and the command
line start fast: the GPU, trimesh and the vector packages load only for what draws.
"""

from __future__ import annotations

import sys
import types
from typing import TYPE_CHECKING

from blueprint.lazy import lazy_names

__version__ = "0.1.0"

# public name -> the module that defines it
_EXPORTS = {
    "default_renderer": "blueprint.api",
    "peel": "blueprint.api",
    "render": "blueprint.api",
    "render_frame": "blueprint.api",
    "Drawing": "blueprint.api.draw",
    "draw": "blueprint.api.draw",
    "batch": "blueprint.api.batch",
    "DrawOptions": "blueprint.api.options",
    "Renderer": "blueprint.api.renderer",
    "Glyphs": "blueprint.compose.glyphs",
    "draw_glyphs": "blueprint.compose.glyphs",
    "load_glyphs": "blueprint.compose.glyphs",
    "render_with_glyphs": "blueprint.compose.glyphs",
    "STYLES": "blueprint.compose.style",
    "Style": "blueprint.compose.style",
    "load_raster_style": "blueprint.compose.linestyle",
    "BlueprintError": "blueprint.errors",
    "GLUnavailableError": "blueprint.errors",
    "InputError": "blueprint.errors",
    "ShaderError": "blueprint.errors",
    "Frame": "blueprint.render.renderer",
    "Layers": "blueprint.render.renderer",
    "VIEWS": "blueprint.scene.camera",
    "Camera": "blueprint.scene.camera",
    "load_model": "blueprint.scene.loader",
    "Model": "blueprint.scene.model",
    "choose_parts": "blueprint.scene.environment",
    "environment_parts": "blueprint.scene.environment",
    "guess_up": "blueprint.scene.up",
    "Cut": "blueprint.scene.section",
    "SectionPlane": "blueprint.scene.section",
    "cut_model": "blueprint.scene.section",
    "parse_section": "blueprint.scene.section",
    "Marks": "blueprint.scene.sheet",
    "KINDS": "blueprint.vector.linework",
    "Lines": "blueprint.vector.linework",
    "edge_numbers": "blueprint.vector.lines",
    "anchor_glyphs": "blueprint.vector.anchors",
    "lay_out_sheet": "blueprint.scene.sheet",
}

__all__ = [
    "BlueprintError",
    "Camera",
    "Cut",
    "DrawOptions",
    "Drawing",
    "Frame",
    "GLUnavailableError",
    "Glyphs",
    "InputError",
    "KINDS",
    "Layers",
    "Lines",
    "Marks",
    "Model",
    "Renderer",
    "STYLES",
    "SectionPlane",
    "ShaderError",
    "Style",
    "VIEWS",
    "anchor_glyphs",
    "batch",
    "choose_parts",
    "cut_model",
    "default_renderer",
    "draw",
    "draw_glyphs",
    "edge_numbers",
    "environment_parts",
    "guess_up",
    "lay_out_sheet",
    "load_glyphs",
    "load_model",
    "load_raster_style",
    "parse_section",
    "peel",
    "render",
    "render_frame",
    "render_with_glyphs",
]

if TYPE_CHECKING:
    from blueprint.api import default_renderer, peel, render, render_frame
    from blueprint.api.batch import batch
    from blueprint.api.draw import Drawing, draw
    from blueprint.api.options import DrawOptions
    from blueprint.api.renderer import Renderer
    from blueprint.compose.glyphs import Glyphs, draw_glyphs, load_glyphs, render_with_glyphs
    from blueprint.compose.style import STYLES, Style
    from blueprint.errors import BlueprintError, GLUnavailableError, InputError, ShaderError
    from blueprint.render.renderer import Frame, Layers
    from blueprint.scene.camera import VIEWS, Camera
    from blueprint.scene.environment import choose_parts, environment_parts
    from blueprint.scene.loader import load_model
    from blueprint.scene.model import Model
    from blueprint.scene.section import Cut, SectionPlane, cut_model, parse_section
    from blueprint.scene.sheet import Marks, lay_out_sheet
    from blueprint.scene.up import guess_up
    from blueprint.vector.anchors import anchor_glyphs
    from blueprint.vector.lines import edge_numbers
    from blueprint.vector.linework import KINDS, Lines


class _Package(types.ModuleType):
    def __setattr__(self, name: str, value) -> None:
        # Importing a subpackage sets the package's attribute of its name to it; the subpackage
        # blueprint.render must not hide the function blueprint.render (a name of _EXPORTS).
        if isinstance(value, types.ModuleType) and name in _EXPORTS:
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


__getattr__, __dir__ = lazy_names(__name__, _EXPORTS, globals())
