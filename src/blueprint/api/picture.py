"""The blueprint frame of checked ``DrawOptions``: what ``render_frame``, its plan sheets and
sections draw each view with."""

from __future__ import annotations

from blueprint.api import stages
from blueprint.api.options import DrawOptions
from blueprint.render.renderer import Frame, LayerRenderer
from blueprint.scene.camera import Camera, fit_camera
from blueprint.scene.model import Model


def smooth_contours_wanted(model: Model, options: DrawOptions) -> bool:
    """Whether a picture of ``model`` with ``options`` draws smooth contour lines: as
    ``smooth_contours`` says, or where it is None, where ``model`` is one mesh (a model kept as
    instances draws its meshes' own outlines). A dense mesh's lines are found on the GPU, or
    where the renderer cannot, not at all (``blueprint.vector.contour_ink``)."""
    if options.smooth_contours is not None:
        return options.smooth_contours
    return model.instances is None


def blueprint_frame(renderer, model: Model, camera: Camera | None, options: DrawOptions, **extra) -> Frame:
    """The blueprint preset's frame of ``model`` from ``camera`` (None: fitted from the view)
    with ``options``, checked already (``blueprint.pipeline.blueprint.render_blueprint``, which
    takes ``extra`` too), with the smooth contour lines ``smooth_contours`` asks for (None, a
    renderer's frame: none)."""
    # the pipeline is for pictures: vector drawings and depth layers start without it
    from blueprint.pipeline.blueprint import render_blueprint

    keywords = options.frame_keywords(model)
    if options.smooth_contours:
        with stages.timed("contours"):
            camera, keywords["contours"] = frame_contours(renderer, model, camera, keywords)
    return render_blueprint(renderer, model, camera, profile=options.profile, **keywords, **extra)


def frame_contours(renderer: LayerRenderer, model: Model, camera: Camera | None, keywords: dict):
    """(camera, contour lines) of a frame of ``keywords`` (``DrawOptions.frame_keywords``): the
    camera fitted as the frame would fit it where None, since its lines are found for it
    before the frame is drawn (``blueprint.vector.contour_ink``; None for a model kept as
    instances, whose meshes' outlines are drawn as they are, without a smooth face, or dense
    where the renderer cannot find them on the GPU)."""
    # the vector drawings' lines load with the frames that draw them
    from blueprint.vector.contour_ink import contour_ink

    size = keywords["size"]
    camera = camera or fit_camera(model, size, keywords["view"])
    crease_angle, max_layers = keywords["crease_angle"], keywords["max_layers"]
    lines = contour_ink(renderer, model, camera, size, crease_angle=crease_angle, max_layers=max_layers)
    return camera, lines
