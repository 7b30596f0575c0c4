"""GPU-free scene data: models, their loading and normals, cameras."""

from blueprint.scene.camera import VIEWS, Camera
from blueprint.scene.loader import load_model, supported_formats
from blueprint.scene.model import Model
from blueprint.scene.normals import corner_normals

__all__ = ["VIEWS", "Camera", "Model", "corner_normals", "load_model", "supported_formats"]
