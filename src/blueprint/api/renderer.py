"""The renderer of the API: a layer renderer that also draws blueprint frames."""

from __future__ import annotations

from blueprint.api.options import DrawOptions, takes_options
from blueprint.gpu.device import current
from blueprint.render.renderer import Frame, LayerRenderer
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model

# The options of a blueprint frame (``Renderer.render``): the preset's, and how it is profiled.
FRAME_KEYWORDS = (
    "size", "view", "style", "max_layers", "min_fraction", "crease_angle", "line_width", "supersample",
    "depth_threshold", "part_edges", "id_silhouettes", "highlight", "reveal", "shade", "shade_opacity",
    "profile",
)  # fmt: skip


class Renderer(LayerRenderer):
    """Owns one OpenGL context, its targets, programs, queries and uploaded meshes; draws
    blueprints (``render``) and peels depth layers (``peel``, ``triangles_at``).

    Use as a context manager or call ``release()``. Models, cameras and styles stay GPU-free;
    the renderer uploads a model once per (model, crease angle).
    """

    @current
    @takes_options(*FRAME_KEYWORDS)
    def render(
        self,
        model: Model,
        camera: Camera | None = None,
        options: DrawOptions | None = None,
        *,
        on_gpu: bool = False,
    ) -> Frame:
        """Render a blueprint of ``model``: the ``blueprint`` pipeline preset.

        Parameters
        ----------
        model : Model
        camera : Camera, optional
            Defaults to ``Camera.fit`` from ``view`` at the image's aspect.
        options : DrawOptions, optional
            The frame's options, each of these fields a keyword too, over ``options`` where both
            are given (see ``blueprint.api.options.DrawOptions``): ``size``, ``view``, ``style``,
            ``max_layers``, ``min_fraction``, ``crease_angle``, ``line_width``, ``supersample``,
            ``depth_threshold``, ``part_edges``, ``id_silhouettes`` (triangle-ID silhouettes,
            paper 002), ``highlight`` (their whole outline drawn over everything in the style's
            highlight ink and width), ``reveal`` (depth masking: stop peeling as soon as this
            fraction of the highlighted parts' pixels is uncovered), ``shade`` (parts shaded
            inside the blueprint, in depth order), ``shade_opacity`` and ``profile``
            (synchronise after each stage to fill ``Frame.stages``).
        on_gpu : bool
            Leave the picture on the GPU (``Frame.texture``), unread: for a window of this
            renderer's context to show it (``Frame.image`` is None then). Nothing is read
            back then: ``Frame.layers_left`` is not counted (0).
        """
        # the pipeline is for pictures: vector drawings and depth layers start without it
        from blueprint.pipeline.blueprint import render_blueprint

        keywords = options.frame_keywords(model)
        return render_blueprint(self, model, camera, profile=options.profile, on_gpu=on_gpu, **keywords)
