"""Depth peeling on the GPU and the blueprint frame built on it."""

from blueprint.render.renderer import Frame, LayerRenderer, Layers

__all__ = ["Frame", "LayerRenderer", "Layers"]
