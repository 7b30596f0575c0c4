"""GPU state: the context factory, the render-target pool and shader loading."""

from blueprint.gpu.context import create_context, gl_info
from blueprint.gpu.queries import Queries, QuerySet
from blueprint.gpu.shaders import build_compute, build_program, preprocess
from blueprint.gpu.targets import FORMATS, TargetPool

__all__ = [
    "FORMATS",
    "Queries",
    "QuerySet",
    "TargetPool",
    "build_compute",
    "build_program",
    "create_context",
    "gl_info",
    "preprocess",
]
