"""The renderer of the API: a layer renderer that also draws blueprint frames."""

from __future__ import annotations

import numpy as np

from blueprint.compose.style import Style
from blueprint.gpu.device import current
from blueprint.render.renderer import Frame, LayerRenderer
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model


class Renderer(LayerRenderer):
    """Owns one OpenGL context, its targets, programs, queries and uploaded meshes; draws
    blueprints (``render``) and peels depth layers (``peel``, ``triangles_at``).

    Use as a context manager or call ``release()``. Models, cameras and styles stay GPU-free;
    the renderer uploads a model once per (model, crease angle).
    """

    @current
    def render(
        self,
        model: Model,
        camera: Camera | None = None,
        *,
        size: tuple[int, int] = (1024, 1024),
        view: str = "iso",
        style: str | Style = "blueprint",
        max_layers: int | None = 8,
        min_fraction: float = 0.0,
        crease_angle: float = 30.0,
        line_width: float = 1.0,
        supersample: int = 2,
        depth_threshold: float = 4.0,
        part_edges: bool = True,
        id_silhouettes: bool = False,
        highlight: np.ndarray | None = None,
        reveal: float | None = None,
        shade: np.ndarray | None = None,
        shade_opacity: float = 1.0,
        profile: bool = False,
        on_gpu: bool = False,
    ) -> Frame:
        """Render a blueprint of ``model``: the ``blueprint`` pipeline preset.

        Parameters
        ----------
        model : Model
        camera : Camera, optional
            Defaults to ``Camera.fit`` from ``view`` at the image's aspect.
        size : (int, int)
            Output width and height in pixels.
        style : str or Style
        max_layers : int or None
            Depth layers to peel at most; ``None`` peels until a pass draws nothing.
        min_fraction : float
            Stop once a layer covers fewer than this fraction of layer 0's pixels.
        crease_angle : float
            Degrees: normals are smoothed across smaller angles, larger ones draw creases.
        line_width : float
            Line width in output pixels.
        supersample : int
            G-buffer and edges are computed at this multiple of the size, then filtered down.
        id_silhouettes : bool
            Also draw triangle-ID silhouettes (neighbouring pixels whose triangles share no
            vertex, paper 002) in every layer's edge map.
        highlight : (P,) bool, optional
            Designated parts (see ``blueprint.scene.parts.select_parts``): their whole outline
            is drawn over everything in the style's highlight ink and width.
        reveal : float, optional
            Depth masking: stop peeling as soon as this fraction of the highlighted parts'
            pixels is uncovered, so the clutter behind them is not drawn. Needs ``highlight``.
        shade : (P,) bool, optional
            Parts drawn shaded (Lambert, headlight) inside the blueprint, in depth order: edges
            in front of them stay on top, the ones behind are hidden (``shade_opacity`` 1) or
            seen through them.
        shade_opacity : float
            Opacity of the shading, in (0, 1].
        profile : bool
            Synchronise after each stage to fill ``Frame.stages`` (slower).
        on_gpu : bool
            Leave the picture on the GPU (``Frame.texture``), unread: for a window of this
            renderer's context to show it (``Frame.image`` is None then). Nothing is read
            back then: ``Frame.layers_left`` is not counted (0).
        """
        # the pipeline is for pictures: vector drawings and depth layers start without it
        from blueprint.api.options import DrawOptions
        from blueprint.pipeline.blueprint import render_blueprint

        options = DrawOptions(
            size=size,
            view=view,
            style=style,
            max_layers=max_layers,
            min_fraction=min_fraction,
            crease_angle=crease_angle,
            line_width=line_width,
            supersample=supersample,
            depth_threshold=depth_threshold,
            part_edges=part_edges,
            id_silhouettes=id_silhouettes,
            highlight=highlight,
            reveal=reveal,
            shade=shade,
            shade_opacity=shade_opacity,
        )
        return render_blueprint(
            self, model, camera, profile=profile, on_gpu=on_gpu, **options.frame_keywords(model)
        )
