"""Plan sheets as pictures: the style's paper (and grid) over the whole sheet, each view's picture
laid over it where the sheet layout (``blueprint.scene.sheet.lay_out_sheet``) puts it, the marks
(border, title block, labels, dimensions) drawn on top. No GPU here: the views come drawn."""

from __future__ import annotations

import numpy as np

from blueprint.compose.style import Style

__all__ = ["over", "paper_image"]


def paper_image(style: Style, size: tuple[int, int]) -> np.ndarray:
    """(H, W, 4) uint8: the style's paper with its drafting grid (minor lines every
    ``style.grid`` pixels, major every fifth), as the compositor draws it; transparent where the
    style has no paper."""
    w, h = size
    if style.paper is None:
        return np.zeros((h, w, 4), np.uint8)
    color = np.broadcast_to(np.asarray(style.paper, np.float64), (h, w, 4)).copy()
    if style.grid > 0:

        def line(spacing: float) -> np.ndarray:
            # the compositor's grid_line at pixel centres (the fragment's coordinates: y up)
            y, x = np.mgrid[0:h, 0:w].astype(np.float64) + 0.5
            y = h - y
            dx = np.abs(np.mod(x - 0.5 + spacing * 0.5, spacing) - spacing * 0.5)
            dy = np.abs(np.mod(y - 0.5 + spacing * 0.5, spacing) - spacing * 0.5)
            return 1.0 - np.clip(np.minimum(dx, dy), 0.0, 1.0)

        amount = np.maximum(0.45 * line(style.grid), line(style.grid * 5.0)) * style.grid_color[3]
        grid = np.asarray(style.grid_color[:3], np.float64)
        color[..., :3] = color[..., :3] * (1 - amount[..., None]) + grid * amount[..., None]
    return np.round(np.clip(color, 0.0, 1.0) * 255.0).astype(np.uint8)


def over(canvas: np.ndarray, picture: np.ndarray, x: int, y: int) -> None:
    """Lay the straight-alpha RGBA ``picture`` over ``canvas`` (both uint8) with its top-left
    pixel at ``(x, y)``, in place; what falls off the canvas is left out."""
    h, w = canvas.shape[:2]
    ph, pw = picture.shape[:2]
    x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + pw, w), min(y + ph, h)
    if x1 <= x0 or y1 <= y0:
        return
    src = picture[y0 - y : y1 - y, x0 - x : x1 - x].astype(np.float64) / 255.0
    dst = canvas[y0:y1, x0:x1].astype(np.float64) / 255.0
    a_s, a_d = src[..., 3:4], dst[..., 3:4]
    a_o = a_s + a_d * (1.0 - a_s)
    rgb = src[..., :3] * a_s + dst[..., :3] * a_d * (1.0 - a_s)
    rgb = np.divide(rgb, a_o, out=np.zeros_like(rgb), where=a_o > 0)
    out = np.concatenate([rgb, a_o], axis=-1)
    canvas[y0:y1, x0:x1] = np.round(np.clip(out, 0.0, 1.0) * 255.0).astype(np.uint8)
