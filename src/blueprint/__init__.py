"""blueprint: drawings of the visible and hidden edges of 3D models, computed on the GPU."""

from blueprint.api import default_renderer, peel, render, render_frame
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
from blueprint.scene.up import guess_up

__version__ = "0.1.0"

__all__ = [
    "STYLES",
    "VIEWS",
    "BlueprintError",
    "Camera",
    "Cut",
    "Frame",
    "GLUnavailableError",
    "Glyphs",
    "InputError",
    "Layers",
    "Model",
    "Renderer",
    "SectionPlane",
    "ShaderError",
    "Style",
    "cut_model",
    "choose_parts",
    "default_renderer",
    "draw_glyphs",
    "environment_parts",
    "guess_up",
    "load_glyphs",
    "load_model",
    "parse_section",
    "peel",
    "render",
    "render_frame",
    "render_with_glyphs",
]
