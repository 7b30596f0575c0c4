"""Presenting: the drawing, uploaded once as a texture, drawn to the window over the backdrop
(scaled up where it is smaller: a moving frame), with the overlay (help box and heads-up lines,
drawn on the CPU) as a second texture over it. An opaque drawing of the window's size hides the
backdrop: it is copied to the window instead, and the overlay drawn over the rows it covers
alone, as a copy costs a software rasteriser less than a full-screen pass."""

from __future__ import annotations

import numpy as np

from blueprint.scene.model import Model
from blueprint.viewer.overlay import BACKDROP, LINE_HEIGHT, band_overlay, help_overlay
from blueprint.viewer.state import ViewState
from blueprint.viewer.window import Window

PRESENT_FRAG = "blueprint.viewer:glsl/present.frag"
OVERLAY_FRAG = "blueprint.viewer:glsl/overlay.frag"


def hud_lines(state: ViewState, model: Model, last: dict, renderer_name: str, status: str) -> list[str]:
    """The heads-up lines: frame rate, layers, model, renderer, style and view; then the picked
    part and `status` (a passing message), where there are any. `last` describes the last
    frame drawn (its ``ms``, ``layers``, ``quality`` and ladder ``step`` while moving, and
    ``revealed``)."""
    ms = last.get("ms", 0.0)
    fps = 1000.0 / ms if ms > 0 else 0.0
    limit = "all" if state.max_layers is None else str(state.max_layers)
    view = state.view if state.at_fit() else f"{state.view} (orbited)"
    quality = f" | moving: {last.get('step', 'full')}" if last.get("quality") == "moving" else ""
    lines = [
        f"{fps:.1f} fps | {last.get('layers', 0)} layers (max {limit}) | "
        f"{model.triangle_count:,} triangles | {renderer_name} | {state.style} | "
        f"{view} {'ortho' if state.ortho else 'persp'}{quality} | H: help"
    ]
    extra = []
    if state.part is not None:
        # of a model kept as instances from its instances, never its flattened arrays
        count = int(model.part_triangle_counts()[state.part])
        line = f"part {state.part}: {model.part_names[state.part]} ({count:,} triangles)"
        revealed = last.get("revealed")
        if state.mask and revealed is not None:
            line += f" | depth mask: {revealed:.0%} shown"
        extra.append(line)
    if status:
        extra.append(status)
    if extra:
        lines.append("   ".join(extra))
    return lines


class Presenter:
    """The window's textures (the picture, the overlay) and the pass that shows them."""

    def __init__(self, window: Window) -> None:
        self.window = window
        self._textures: dict[str, object] = {}
        self._fbos: dict[int, object] = {}  # a framebuffer over each texture, by its GL name
        self._overlay_key: tuple | None = None
        self._overlay_base: np.ndarray | None = None
        self._band_rows = 0
        self._band_lines: list[str] | None = None  # the lines the band holds now
        self._premultiplied = False  # how the picture's colours hold its alpha
        self._opaque = False  # whether the picture covers the backdrop everywhere

    @property
    def has_picture(self) -> bool:
        return "picture" in self._textures

    def show(self, image: np.ndarray, opaque: bool = False) -> None:
        """Make ``image``, (H, W, 4) uint8, row 0 at the top, the picture presented from now on;
        presenting again (heads-up lines, exposure) reuses the upload. ``opaque``: its alpha
        is 1 everywhere (drawn on paper)."""
        self._upload("picture", image)
        self._premultiplied, self._opaque = False, opaque

    def show_texture(self, texture, opaque: bool = False) -> None:
        """Make the renderer's picture ``texture`` (``Frame.texture``: premultiplied RGBA, on
        the GPU) the picture presented from now on: copied on the GPU, never read back."""
        ctx = self.window.renderer.ctx
        picture = self._texture("picture", texture.size)
        ctx.copy_framebuffer(self._fbos[picture.glo], self.window.renderer.pool.framebuffer((texture,)))
        self._premultiplied, self._opaque = True, opaque

    def draw(self, size: tuple[int, int], lines: list[str], show_help: bool) -> None:
        """The picture over the backdrop, scaled to the window's `size`, the heads-up `lines` and
        (with `show_help`) the help box over it, into the back buffer."""
        w, h = size
        renderer = self.window.renderer
        ctx = renderer.ctx
        overlay = self._overlay(size, lines, show_help)
        picture = self._textures["picture"]
        same_size = tuple(picture.size) == (w, h)
        ctx.screen.use()
        ctx.viewport = (0, 0, w, h)
        ctx.disable(ctx.DEPTH_TEST | ctx.BLEND)
        if same_size and self._opaque:
            ctx.copy_framebuffer(ctx.screen, self._fbos[picture.glo])
            self._draw_overlay(overlay, h if show_help else min(h, self._band_rows))
            return
        prog, vao = renderer.fullscreen(PRESENT_FRAG, {"SAME_SIZE": same_size})
        picture.use(0)
        overlay.use(1)
        prog["u_picture"].value = 0
        prog["u_overlay"].value = 1
        if not same_size:
            prog["u_window"].value = (float(w), float(h))
        prog["u_backdrop"].value = tuple(c / 255.0 for c in BACKDROP)
        prog["u_premultiplied"].value = self._premultiplied
        vao.render(vertices=3)

    def _draw_overlay(self, overlay, rows: int) -> None:
        """The overlay's top ``rows`` blended over what the window holds."""
        if rows <= 0:
            return
        renderer = self.window.renderer
        ctx = renderer.ctx
        w, h = overlay.size
        prog, vao = renderer.fullscreen(OVERLAY_FRAG)
        overlay.use(1)
        prog["u_overlay"].value = 1
        ctx.scissor = (0, h - rows, w, rows)
        ctx.enable(ctx.BLEND)
        ctx.blend_func = ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA
        vao.render(vertices=3)
        ctx.disable(ctx.BLEND)
        ctx.scissor = None

    def read(self, size: tuple[int, int]) -> np.ndarray:
        """What the back buffer shows, (H, W, 3) uint8, row 0 at the top; read it before the
        swap, which leaves the back buffer undefined."""
        w, h = size
        ctx = self.window.renderer.ctx
        shown = np.frombuffer(ctx.screen.read((0, 0, w, h), components=3, alignment=1), np.uint8)
        return shown.reshape(h, w, 3)[::-1]

    def _overlay(self, size: tuple[int, int], lines: list[str], show_help: bool):
        """The overlay texture: the help box redrawn when it or the window changes, the band of
        heads-up lines where they changed (rows written down to the lower of this band and the
        last), since drawing them all every frame cost the viewer time."""
        w, h = size
        key = (w, h, show_help)
        if self._overlay_key != key:
            self._overlay_base = help_overlay(size, show_help)
            self._upload("overlay", self._overlay_base)
            self._overlay_key, self._band_rows, self._band_lines = key, 0, None
        texture = self._textures["overlay"]
        if lines == self._band_lines:
            return texture
        self._band_lines = list(lines)
        rows = min(h, max(self._band_rows, LINE_HEIGHT * len(lines)))
        if rows:
            top = band_overlay(self._overlay_base[:rows], lines)
            texture.write(np.ascontiguousarray(top[::-1]).tobytes(), viewport=(0, h - rows, w, rows))
        self._band_rows = LINE_HEIGHT * len(lines)
        return texture

    def _upload(self, name: str, image: np.ndarray):
        """``image`` (H, W, 4) uint8, row 0 at the top, in the texture ``name``."""
        h, w = image.shape[:2]
        texture = self._texture(name, (w, h))
        texture.write(np.ascontiguousarray(image[::-1]).tobytes())
        return texture

    def _texture(self, name: str, size: tuple[int, int]):
        """The texture ``name``, kept between frames, remade when the size changes."""
        ctx = self.window.renderer.ctx
        texture = self._textures.get(name)
        if texture is None or texture.size != tuple(size):
            if texture is not None:
                self._fbos.pop(texture.glo).release()
                texture.release()
            texture = self._textures[name] = ctx.texture(tuple(size), 4, alignment=1)
            # smaller drawings are scaled up bilinearly; a full-size picture lands on texel centres
            texture.filter = (ctx.LINEAR, ctx.LINEAR)
            texture.repeat_x = texture.repeat_y = False
            self._fbos[texture.glo] = ctx.framebuffer(color_attachments=[texture])
        return texture

    def release(self) -> None:
        for fbo in self._fbos.values():
            fbo.release()
        for texture in self._textures.values():
            texture.release()
        self._fbos.clear()
        self._textures.clear()
