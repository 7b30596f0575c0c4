"""Drawing styles: paper, inks, grid, and how hidden layers fade. No GPU here."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from blueprint.color import RGBA, hex_color
from blueprint.errors import InputError


@dataclass(frozen=True)
class Style:
    """How the edge layers become a picture.

    Layer 0 (visible edges) is drawn in ``ink`` at full strength; layer ``k >= 1`` (edges hidden
    behind ``k`` surfaces) in ``hidden_ink`` at ``hidden_opacity * fade ** (k - 1)``, unless
    ``level_inks`` lists the colour and opacity of the first layers (a line style file's
    levels: past the last, its opacity fades by ``fade`` a layer). Visible lines are ``width``
    times the frame's line width, hidden ones ``hidden_width`` times (ISO 128: hidden lines
    narrow, half the wide ones; a raster never draws them wider than the visible ones).
    ``paper`` is ``None`` for a transparent background; ``grid`` is the minor grid spacing in
    pixels (0: none). ``threshold`` draws binary edges (the paper's wire-frame variant).
    Highlighted parts are outlined in ``highlight`` ink, ``highlight_width`` times as wide.
    """

    name: str
    paper: RGBA | None
    ink: RGBA
    hidden_ink: RGBA
    hidden_opacity: float = 0.7
    fade: float = 0.8
    grid: float = 0.0
    grid_color: RGBA = (1.0, 1.0, 1.0, 0.12)
    threshold: bool = False
    highlight: RGBA = (1.0, 0.55, 0.1, 1.0)
    highlight_width: float = 2.0
    shade: RGBA = (0.86, 0.9, 0.95, 1.0)
    width: float = 1.0
    hidden_width: float = 0.5
    level_inks: tuple[RGBA, ...] = ()

    def __post_init__(self) -> None:
        for label, value in (("width", self.width), ("hidden_width", self.hidden_width)):
            if not 0.0 < value <= 16.0:
                raise InputError(f"style {self.name}: {label} must be in (0, 16], got {value}")
        for label, value in (("hidden_opacity", self.hidden_opacity), ("fade", self.fade)):
            if not 0.0 <= value <= 1.0:
                raise InputError(f"style {self.name}: {label} must be in [0, 1], got {value}")
        if not math.isfinite(self.grid) or self.grid < 0:
            raise InputError(f"style {self.name}: grid spacing must be >= 0, got {self.grid}")
        if not 1.0 <= self.highlight_width <= 8.0:
            raise InputError(
                f"style {self.name}: highlight_width must be in [1, 8], got {self.highlight_width}"
            )

    def layer_inks(self, count: int) -> np.ndarray:
        """(count, 4) float32: colour and opacity for each layer, front first."""
        inks = np.empty((count, 4), np.float32)
        listed = len(self.level_inks)
        for k in range(count):
            if listed:
                *rgb, opacity = self.level_inks[min(k, listed - 1)]
                inks[k] = (*rgb, opacity * self.fade ** max(0, k - listed + 1))
            elif k == 0:
                inks[k] = self.ink
            else:
                opacity = self.hidden_opacity * self.fade ** (k - 1)
                inks[k] = (*self.hidden_ink[:3], self.hidden_ink[3] * opacity)
        return inks

    def with_options(self, **changes) -> Style:
        return replace(self, **changes)


#: The raster styles by name: the one list that the API, the command line (``--style``), the
#: viewer's style cycle and vector drawings (``blueprint.vector.vector_style``) choose from. A new
#: style is one entry here; line style files (``blueprint.compose.linestyle``) stay files. The
#: composite op's ``style`` parameter (``blueprint.compose.compositor.COMPOSITE``) takes its names.
STYLES: dict[str, Style] = {
    "blueprint": Style(
        "blueprint",
        paper=hex_color("#12457a"),
        ink=hex_color("#ffffff"),
        hidden_ink=hex_color("#bfe0ff"),
        # hidden lines are half as wide, hence fainter already: stronger ink, gentler fading
        hidden_opacity=0.9,
        fade=0.85,
        grid=0.0,
    ),
    "paper": Style(
        "paper",
        paper=hex_color("#ffffff"),
        ink=hex_color("#0a1f44"),
        # a quiet slate: hidden lines read as hidden, not as saturated blue that draws the eye
        hidden_ink=hex_color("#4f5d75"),
        hidden_opacity=0.9,
        fade=0.85,
    ),
    "transparent": Style(
        "transparent",
        paper=None,
        ink=hex_color("#0a1f44"),
        hidden_ink=hex_color("#4f5d75"),
        hidden_opacity=0.9,
        fade=0.85,
    ),
    "wireframe": Style(
        "wireframe",
        paper=hex_color("#ffffff"),
        ink=hex_color("#000000"),
        hidden_ink=hex_color("#000000"),
        # binary lines still tell hidden from visible: half-strength grey, never the full ink;
        # as wide as the visible ones, since a thresholded sample cannot be half a line
        hidden_opacity=0.5,
        hidden_width=1.0,
        fade=1.0,
        threshold=True,
    ),
}


#: A style that ends in one of these is a line style file (``blueprint.compose.linestyle``), not
#: a name.
FILE_SUFFIXES = (".toml", ".json")
