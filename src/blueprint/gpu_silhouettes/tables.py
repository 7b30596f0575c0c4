"""What the silhouette pass reads besides the ID buffer: per-face corner positions, or the ID
lists of a topology, as GPU tables of 4096 entries a row (moderngl has no buffer textures)."""

from __future__ import annotations

import numpy as np

from blueprint.errors import InputError
from blueprint.silhouette.idlist import IdLists

TABLE_WIDTH = 4096


def _rows(entries: int) -> int:
    return max(1, -(-entries // TABLE_WIDTH))


def _check_rows(ctx, entries: int, what: str) -> None:
    limit = int(ctx.info["GL_MAX_TEXTURE_SIZE"])
    if _rows(entries) > limit:
        raise InputError(
            f"{what}: {entries} entries need {_rows(entries)} rows of {TABLE_WIDTH}, this GPU allows {limit}"
        )


def _table(ctx, values: np.ndarray, dtype: str):
    """(N, C) values as a (4096, rows) texture of C components, entry i at (i % 4096, i / 4096)."""
    values = values.reshape(len(values), -1)
    _check_rows(ctx, len(values), "too many triangles for the adjacency tables")
    padded = np.zeros((_rows(len(values)) * TABLE_WIDTH, values.shape[1]), values.dtype)
    padded[: len(values)] = values
    tex = ctx.texture((TABLE_WIDTH, _rows(len(values))), values.shape[1], padded.tobytes(), dtype=dtype)
    tex.filter = (ctx.NEAREST, ctx.NEAREST)
    return tex


def diagonal(points: np.ndarray) -> float:
    """Length of the bounding-box diagonal of (..., 3) points; 1 where there is none, so that a
    tolerance relative to it stays usable."""
    if len(points) == 0:
        return 1.0
    return float(np.linalg.norm(np.ptp(points.reshape(-1, 3).astype(np.float64), axis=0))) or 1.0


class Corners:
    """Corner positions of F faces in one GPU buffer: corner k of face f at entry 3f + k, three
    float32 each, padded to whole rows of 4096 entries so the buffer is also a texture image."""

    def __init__(self, ctx, faces: int) -> None:
        _check_rows(ctx, 3 * faces, "too many triangles for the vertex table")
        self.ctx, self.faces = ctx, faces
        self.rows = _rows(3 * faces)
        self.buffer = ctx.buffer(reserve=self.rows * TABLE_WIDTH * 12)
        self.texture = None
        self._stale = True

    def write(self, corners: np.ndarray) -> None:
        data = np.ascontiguousarray(corners, dtype=np.float32)
        if data.size != 9 * self.faces:
            raise InputError(f"expected corners of {self.faces} triangles, (F, 3, 3), got shape {data.shape}")
        self.buffer.write(data)
        self._stale = True

    def as_texture(self):
        """The buffer as an RGB32F texture (fragment path), copied on the GPU when it changed."""
        if self.texture is None:
            self.texture = self.ctx.texture((TABLE_WIDTH, self.rows), 3, dtype="f4")
            self.texture.filter = (self.ctx.NEAREST, self.ctx.NEAREST)
        if self._stale:
            self.texture.write(self.buffer)
            self._stale = False
        return self.texture

    def release(self) -> None:
        self.buffer.release()
        if self.texture is not None:
            self.texture.release()


class ListTextures:
    """The ID lists of a topology as three integer textures."""

    def __init__(self, ctx, lists: IdLists) -> None:
        self.lists = lists
        self.textures = (
            _table(ctx, lists.face_vertices, "i4"),
            _table(ctx, lists.pointers, "i4"),
            _table(ctx, lists.lists if len(lists.lists) else np.zeros(1, np.int32), "i4"),
        )

    def release(self) -> None:
        for tex in self.textures:
            tex.release()
