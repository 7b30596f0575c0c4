"""Depth peeling on the GPU and the blueprint frame built on it."""

from blueprint.render.renderer import Capturer, Frame, LayerRenderer, Layers

__all__ = ["Capturer", "Frame", "LayerRenderer", "Layers"]
