"""Section views as the API draws them: the model cut on the CPU (``blueprint.scene.section``),
drawn by the usual frame, then hatched where the first layer shows a cut face
(``blueprint.compose.hatch``)."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from blueprint.api.options import DrawOptions
from blueprint.api.picture import blueprint_frame
from blueprint.api.renderer import Renderer
from blueprint.compose.hatch import hatch_overlay
from blueprint.compose.style import Style
from blueprint.render.renderer import Frame
from blueprint.scene.camera import Camera
from blueprint.scene.model import Model
from blueprint.scene.parts import designated_parts
from blueprint.scene.section import Cut, SectionPlane, cut_model

__all__ = ["Section", "render_section", "section_of"]


@dataclass(frozen=True)
class Section:
    """A section the user asked for: the plane, and the parts drawn whole ((P,) bool)."""

    plane: SectionPlane
    keep: np.ndarray

    def cut(self, model: Model, camera: Camera) -> Cut:
        """``model`` cut as ``camera`` sees it: an axis cut removes the side facing it."""
        return cut_model(model, self.plane.facing(camera.eye, camera.target), self.keep)


def section_of(model: Model, options: DrawOptions) -> Section | None:
    """The ``Section`` of ``options`` (its plane and the parts of ``model`` it keeps whole),
    None when no plane is given."""
    if options.plane is None:
        return None
    keep = np.zeros(len(model.part_names), bool)
    if options.section_keep is not None:
        keep = designated_parts(model, options.section_keep)
    return Section(options.plane, keep)


def render_section(renderer: Renderer, cut: Cut, camera: Camera, options: DrawOptions) -> Frame:
    """Draw the model ``cut`` left with ``options`` (resolved: its ``style`` a ``Style``) and
    hatch its cut faces where the first layer of the parts cut shows them: parts kept whole,
    in front of the plane, do not hide the hatching (as in the vector drawing)."""
    frame = blueprint_frame(renderer, cut.model, camera, options)
    t0 = time.perf_counter()
    style: Style = options.style
    size, s = options.size, options.supersample
    model, cap = cut.model, cut.cap
    if cut.keep is not None and cut.keep.any():
        cut_faces = ~cut.keep[model.face_part]
        model = Model(
            model.positions, model.faces[cut_faces], model.face_part[cut_faces], model.part_names, model.up
        )
        cap = cap[cut_faces]
    front = renderer.peel(model, camera, size=(size[0] * s, size[1] * s), max_layers=1, normals=False)
    image = hatch_overlay(
        frame.image,
        front.triangle[0],
        model.face_part,
        cap,
        style.ink,
        supersample=s,
        line_width=float(options.line_width),
    )
    spent = (time.perf_counter() - t0) * 1e3
    return replace(frame, image=image, ms=frame.ms + spent, stages={**frame.stages, "section": spent})
