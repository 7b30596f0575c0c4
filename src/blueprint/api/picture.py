"""The blueprint frame of checked ``DrawOptions``: what ``render_frame``, its plan sheets and
sections draw each view with."""

from __future__ import annotations

from blueprint.api.options import DrawOptions
from blueprint.api.renderer import Renderer
from blueprint.render.renderer import Frame
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model


def blueprint_frame(renderer: Renderer, model: Model, camera: Camera, options: DrawOptions) -> Frame:
    """The blueprint preset's frame of ``model`` from ``camera`` with ``options``, checked
    already (``blueprint.pipeline.blueprint.render_blueprint``)."""
    # the pipeline is for pictures: vector drawings and depth layers start without it
    from blueprint.pipeline.blueprint import render_blueprint

    keywords = options.frame_keywords(model)
    return render_blueprint(renderer, model, camera, profile=options.profile, **keywords)
