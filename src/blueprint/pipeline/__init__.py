"""Declared image-space pipelines (paper 004, the G²-buffer): attributes and passes in a TOML
file, validated as a graph before any GPU work, run on the renderer's context and targets.

Names are imported when first used (PEP 562): a module of the package (``media`` for videos)
loads without the executor, which a vector drawing or a depth peel never runs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from blueprint.lazy import lazy_names

# public name -> the module that defines it
_EXPORTS = {
    "render_blueprint": "blueprint.pipeline.blueprint",
    "Executor": "blueprint.pipeline.executor",
    "Plan": "blueprint.pipeline.graph",
    "plan": "blueprint.pipeline.graph",
    "ATTRIBUTES": "blueprint.pipeline.schema",
    "PipelineSpec": "blueprint.pipeline.spec",
    "load_pipeline": "blueprint.pipeline.spec",
    "parse": "blueprint.pipeline.spec",
    "preset_names": "blueprint.pipeline.spec",
    "Result": "blueprint.pipeline.state",
}

__all__ = [
    "ATTRIBUTES",
    "Executor",
    "PipelineSpec",
    "Plan",
    "Result",
    "load_pipeline",
    "parse",
    "plan",
    "preset_names",
    "render_blueprint",
]

if TYPE_CHECKING:
    from blueprint.pipeline.blueprint import render_blueprint
    from blueprint.pipeline.executor import Executor
    from blueprint.pipeline.graph import Plan, plan
    from blueprint.pipeline.schema import ATTRIBUTES
    from blueprint.pipeline.spec import PipelineSpec, load_pipeline, parse, preset_names
    from blueprint.pipeline.state import Result


__getattr__, __dir__ = lazy_names(__name__, _EXPORTS, globals())
