"""blueprint: drawings of the visible and hidden edges of 3D models, computed on the GPU."""

from blueprint.api import default_renderer, peel, render, render_frame
from blueprint.api.draw import Drawing, draw
from blueprint.api.renderer import Renderer
from blueprint.compose.glyphs import Glyphs, draw_glyphs, load_glyphs, render_with_glyphs
from blueprint.compose.style import STYLES, Style
from blueprint.errors import BlueprintError, GLUnavailableError, InputError, ShaderError
from blueprint.render.renderer import Frame, Layers
from blueprint.scene.camera import VIEWS, Camera
from blueprint.scene.loader import load_model
from blueprint.scene.model import Model

__version__ = "0.1.0"

__all__ = [
    "STYLES",
    "VIEWS",
    "BlueprintError",
    "Camera",
    "Drawing",
    "Frame",
    "GLUnavailableError",
    "Glyphs",
    "InputError",
    "Layers",
    "Model",
    "Renderer",
    "ShaderError",
    "Style",
    "default_renderer",
    "draw",
    "draw_glyphs",
    "load_glyphs",
    "load_model",
    "peel",
    "render",
    "render_frame",
    "render_with_glyphs",
]
