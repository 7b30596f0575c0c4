"""Depth peeling on the GPU and the blueprint frame built on it."""

from blueprint.render.renderer import Frame, Layers, Renderer

__all__ = ["Frame", "Layers", "Renderer"]
