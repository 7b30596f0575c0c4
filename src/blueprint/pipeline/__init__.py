"""Declared image-space pipelines (paper 004, the G²-buffer): attributes and passes in a TOML
file, validated as a graph before any GPU work, run on the renderer's context and targets."""

from blueprint.pipeline.blueprint import render_blueprint
from blueprint.pipeline.executor import Executor, executor_for
from blueprint.pipeline.graph import Plan, plan
from blueprint.pipeline.spec import ATTRIBUTES, PipelineSpec, load_pipeline, parse, preset_names
from blueprint.pipeline.state import Result

__all__ = [
    "ATTRIBUTES",
    "Executor",
    "PipelineSpec",
    "Plan",
    "Result",
    "executor_for",
    "load_pipeline",
    "parse",
    "plan",
    "preset_names",
    "render_blueprint",
]
