"""Glyphs: boxes, arrows, paths and text labels in model coordinates, drawn into a blueprint
with the same depth test as its edges, so that what lies behind a surface is drawn as a hidden
line (dimmed or dashed) or left out.

A glyph file is TOML or JSON (chosen by extension)::

    [hidden]                      # how glyph pieces behind a surface are drawn
    mode = "dim"                  # "dim" (lower opacity), "dashed" or "none"
    opacity = 0.35                # dim mode
    dash = [4, 3]                 # dashed mode: on, off lengths in pixels

    [[box]]
    min = [-7, 14, -26]
    max = [7, 66, 26]
    color = "#ff8800"             # optional, every glyph; default DEFAULT_COLOR
    width = 2                     # optional: line width in pixels
    label = "gear"                # optional: text at the box's top corner on screen

    [[arrow]]
    from = [-45, 90, 40]
    to = [-45, 52, 0]
    head = 0.1                    # head length, fraction of the arrow's length

    [[path]]
    points = [[0, 0, 0], [1, 0, 0], [1, 1, 0]]
    closed = false
    dash = [6, 4]                 # optional for box, arrow and path: on, off in pixels

    [[label]]
    at = [0, 80, 0]
    text = "gear"
    size = 14                     # pixels
    anchor = "left"               # which side of the text sits at the point

    [[dimension]]                 # after ISO 129, drawn over everything
    from = [-45, 0, 0]
    to = [45, 0, 0]
    text = "90 h7"                # optional: default the distance in mm (see units)
    offset = 12                   # optional, model units, left of from -> to on screen

    [[dimension]]                 # the model's edge 118 (blueprint.edge_numbers), end to end
    edge = 118                    # or edges = [118, 240]: the distance between two edges

``load_glyphs`` reads a file and ``Glyphs.from_dict`` validates plain data (both raise
``InputError`` with one line naming the file and the entry); dimensions given by edges get
their points from a model (``blueprint.vector.anchors.anchor_glyphs``, which ``render`` and
``draw`` call); ``draw_glyphs`` draws them over an
image, given the camera and the blueprint's front depth layer; ``render_with_glyphs`` peels
that layer itself. No GPU here except through ``render_with_glyphs``.

The modules, in the order a drawing goes through them: ``values`` (the glyph types),
``parse`` (``Glyphs``, a whole file of them, from files and plain data), ``projection`` (to the
screen, clipping, the depth test), ``strokes`` (line glyphs into screen pieces), ``raster``
(pieces and texts into pixels), ``draw`` (the two entries above).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from blueprint.lazy import lazy_names

# Names load on first use (PEP 562): a module of the package (``raster`` for label anchors)
# loads without the others, which a drawing without glyphs never runs.
_EXPORTS = {
    **dict.fromkeys(("draw_glyphs", "render_with_glyphs"), "blueprint.compose.glyphs.draw"),
    **dict.fromkeys(("Glyphs", "load_glyphs"), "blueprint.compose.glyphs.parse"),
    **dict.fromkeys(
        ("ANCHORS", "HIDDEN_MODES", "Arrow", "Box", "Dimension", "Hidden", "Label", "Path3D"),
        "blueprint.compose.glyphs.values",
    ),
}

__all__ = [
    "ANCHORS",
    "HIDDEN_MODES",
    "Arrow",
    "Box",
    "Dimension",
    "Glyphs",
    "Hidden",
    "Label",
    "Path3D",
    "draw_glyphs",
    "load_glyphs",
    "render_with_glyphs",
]

if TYPE_CHECKING:
    from blueprint.compose.glyphs.draw import draw_glyphs, render_with_glyphs
    from blueprint.compose.glyphs.parse import Glyphs, load_glyphs
    from blueprint.compose.glyphs.values import (
        ANCHORS,
        HIDDEN_MODES,
        Arrow,
        Box,
        Dimension,
        Hidden,
        Label,
        Path3D,
    )


__getattr__, __dir__ = lazy_names(__name__, _EXPORTS, globals())
