"""Passes drawn only over the tiles where a depth layer has something.

A software rasteriser shades every pixel a full-screen triangle covers, whatever the layer
holds there, so a pass over a layer that covers little of the screen costs nearly as much as
one over a layer that covers much of it. Where an operation's result can be non-zero only
near what its input holds (``Op.support`` and ``Op.reach``), the executor
reads the layer's coverage back (cheap where the GPU is the CPU), finds the tiles it touches,
widens them by the pass's reach and draws the pass as rectangles over those tiles alone; the
rest of its target is cleared. GPUs keep drawing full-screen passes (a read-back a layer would
stall them, and their passes cost little next to it).
"""

from __future__ import annotations

import numpy as np

from blueprint.render.abuffer import TILE


def covered_tiles(depth: np.ndarray) -> np.ndarray:
    """(ceil(H / TILE), ceil(W / TILE)) bool: the tiles of ``depth`` (H, W), 1.0 where the
    layer has nothing, that hold any covered pixel."""
    h, w = depth.shape
    rows = np.minimum.reduceat(depth, np.arange(0, h, TILE), axis=0)
    return np.minimum.reduceat(rows, np.arange(0, w, TILE), axis=1) < 1.0


def widen(tiles: np.ndarray, by: int) -> np.ndarray:
    """``tiles`` grown by ``by`` tiles in every direction (a square neighbourhood)."""
    if by <= 0 or not tiles.any():
        return tiles
    h, w = tiles.shape
    padded = np.zeros((h + 2 * by, w + 2 * by), bool)
    padded[by : by + h, by : by + w] = tiles
    rows = np.zeros((h, w + 2 * by), bool)
    for dy in range(2 * by + 1):
        rows |= padded[dy : dy + h]
    out = np.zeros((h, w), bool)
    for dx in range(2 * by + 1):
        out |= rows[:, dx : dx + w]
    return out


def rectangles(tiles: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Two triangles (six (x, y) vertices in clip space, float32) for each run of set tiles
    along a row of ``tiles`` over a target of ``size`` (W, H) pixels; row 0 is the bottom row of
    the target, as GL stores it."""
    w, h = size
    # (not np.pad, np.diff and np.argwhere, whose Python overhead counts in small frames: a tile
    # pass a layer calls this)
    rows, columns = tiles.shape
    padded = np.zeros((rows, columns + 2), np.int8)
    padded[:, 1:-1] = tiles
    edges = padded[:, 1:] - padded[:, :-1]
    start_rows, start_columns = np.nonzero(edges == 1)
    ends = np.nonzero(edges == -1)[1]
    y0 = start_rows * TILE
    y1 = np.minimum(y0 + TILE, h)
    x0 = start_columns * TILE
    x1 = np.minimum(ends * TILE, w)
    left, right = x0 / w * 2.0 - 1.0, x1 / w * 2.0 - 1.0
    bottom, top = y0 / h * 2.0 - 1.0, y1 / h * 2.0 - 1.0
    xs = np.stack([left, right, right, left, right, left], axis=1)
    ys = np.stack([bottom, bottom, top, bottom, top, top], axis=1)
    return np.stack([xs, ys], axis=2).astype(np.float32).reshape(-1, 2)


class Tiles:
    """The coverage of the layer being drawn, in tiles, and the vertex buffer the executor's
    tiled passes draw from (one per executor; vertex arrays per program)."""

    def __init__(self, ctx) -> None:
        self.ctx = ctx
        self.buffer = None
        self._vaos: dict[int, object] = {}
        self._scratch: np.ndarray | None = None
        self.covered: np.ndarray | None = None
        self.size: tuple[int, int] | None = None
        self._drawn: tuple | None = None
        self._vertices = 0
        # the covered tiles of every layer of the run so far (the composite draws over them)
        self.layers: dict[int, np.ndarray] = {}

    def release(self) -> None:
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
        if self.buffer is not None:
            self.buffer.release()
            self.buffer = None

    def look(self, depth_texture, layer: int) -> None:
        """Read layer ``layer``'s depth back and keep which tiles it covers."""
        w, h = depth_texture.size
        if self._scratch is None or self._scratch.shape != (h, w):
            self._scratch = np.empty((h, w), np.float32)
        depth_texture.read_into(self._scratch)
        self._keep(covered_tiles(self._scratch), layer, (w, h))

    def layer_of(self, tile_layers: np.ndarray, layer: int, size: tuple[int, int]) -> None:
        """Keep the tiles layer ``layer`` covers, from the layers of each tile (an A-buffer's
        count: ``Capture.tile_layers``) over a target of ``size``."""
        self._keep(tile_layers > layer, layer, size)

    def _keep(self, covered: np.ndarray, layer: int, size) -> None:
        self.covered, self.size, self._drawn = covered, tuple(size), None
        self.layers[layer] = covered

    def forget(self) -> None:
        self.covered = self.size = self._drawn = None
        self.layers = {}

    def draw(self, prog, reach: int) -> int:
        """Draw ``prog`` (built with ``compositor.TILES_VERT``) over the covered tiles widened by ``reach``
        pixels; returns the draw calls issued (0 where no tile is covered)."""
        return self._draw(prog, ("covered", reach), lambda: widen(self.covered, -(-reach // TILE)))

    def draw_layers(self, prog, first: int, count: int, reach: int) -> int:
        """Draw ``prog`` over the tiles any of layers ``first`` .. ``first + count - 1`` covers,
        widened by ``reach`` pixels of the layers' size and one tile more: a target of another
        size (the composite's, a supersample apart) has pixels straddling two tiles."""
        held = [self.layers[k] for k in range(first, first + count) if k in self.layers]

        def tiles() -> np.ndarray:
            union = np.logical_or.reduce(held) if held else np.zeros((1, 1), bool)
            return widen(union, -(-reach // TILE) + 1)

        return self._draw(prog, ("layers", first, count, reach, len(held)), tiles)

    def _draw(self, prog, key, tiles) -> int:
        if self._drawn != key:
            vertices = rectangles(tiles(), self.size)
            self._upload(vertices)
            self._drawn, self._vertices = key, len(vertices)
        if not self._vertices:
            return 0
        vao = self._vaos.get(prog.glo)
        if vao is None:
            vao = self._vaos[prog.glo] = self.ctx.vertex_array(prog, [(self.buffer, "2f", "in_position")])
        vao.render(vertices=self._vertices)
        return 1

    def _upload(self, vertices: np.ndarray) -> None:
        need = max(vertices.nbytes, 4096)
        if self.buffer is None or self.buffer.size < need:
            for vao in self._vaos.values():
                vao.release()
            self._vaos.clear()
            if self.buffer is not None:
                self.buffer.release()
            self.buffer = self.ctx.buffer(reserve=2 * need)
        if vertices.nbytes:
            self.buffer.write(vertices)
