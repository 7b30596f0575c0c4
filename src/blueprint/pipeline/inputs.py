"""What goes onto the GPU and comes back: image inputs (files, videos' frames, arrays) sized
to the run, arrays uploaded in a target format, and targets read back as arrays."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.gpu.targets import FORMATS
from blueprint.pipeline.schema import Bound

_DTYPES = {"f1": np.uint8, "f2": np.float16, "f4": np.float32, "i4": np.int32}


class ImageInputs:
    """The image inputs of pipelines on ``pool``'s textures, each uploaded again only when its
    file (or array) changes."""

    def __init__(self, pool) -> None:
        self.pool = pool
        self._held: dict[str, tuple[tuple | None, object]] = {}

    def clear(self) -> None:
        self._held.clear()

    def texture(self, name: str):
        return self._held[name][1]

    def put(self, name: str, texture) -> None:
        """Hold ``texture`` as the input ``name`` (single operations' arrays)."""
        self._held[name] = (None, texture)

    def upload(self, bound: Bound, name: str, given, size) -> None:
        from blueprint.pipeline.media import read_image, to_format

        spec = bound.images[name]
        fmt = spec.format
        if isinstance(given, np.ndarray):
            if given.ndim == 2:
                given = np.repeat(given[..., None], 3, axis=2)
            data = given
            if data.shape[:2] != (size[1], size[0]):
                from PIL import Image

                data = np.asarray(
                    Image.fromarray(np.ascontiguousarray(data)).resize(size, Image.Resampling.BILINEAR)
                )
            data = to_format(np.ascontiguousarray(data, np.uint8), fmt)
            key = None
        else:
            path = Path(given) if given is not None else spec.file
            if path is None:
                raise InputError(
                    f"{bound.source}: images.{name}: no file given (set file, or give one when running)"
                )
            if spec.video:
                raise InputError(
                    f"{bound.source}: images.{name}: {path} is a video: "
                    "run it frame by frame (blueprint.api.files.run_pipeline)"
                )
            try:
                stamp = path.stat().st_mtime_ns
            except OSError:
                raise InputError(f"{path}: no such image file") from None
            key = (str(path), stamp, fmt, size)
            held = self._held.get(name)
            if held is not None and held[0] == key:
                return
            data = read_image(path, fmt, size)
        tex = self.pool.texture(f"pipeline.image.{name}", size, fmt)
        tex.write(np.ascontiguousarray(data[::-1]).tobytes())
        self._held[name] = (key, tex)


def output_size(bound: Bound, image_names, size, images: dict, max_texture: int) -> tuple[int, int]:
    """A run's output size: ``size``, else the file's, else the first image input's, else 1024²."""
    if size is not None:
        return check_size(size, 1, max_texture)
    if bound.size is not None:
        return bound.size
    from blueprint.pipeline.media import image_size

    for name in image_names:
        spec = bound.images[name]
        given = images.get(name)
        if isinstance(given, np.ndarray):
            return round(given.shape[1] / spec.scale), round(given.shape[0] / spec.scale)
        path = given if given is not None else spec.file
        if path is not None:
            iw, ih = image_size(path)
            return round(iw / spec.scale), round(ih / spec.scale)
    return 1024, 1024


def read_texture(tex, fmt: str) -> np.ndarray:
    """(H, W, C) of a target, row 0 at the top; uint8 for 8-bit formats, float32 or int32."""
    return _received(tex.read_into, tuple(tex.size[:2]), fmt)


def _received(read_into, size: tuple[int, int], fmt: str) -> np.ndarray:
    """What ``read_into`` fills with a target's pixels (rows bottom up, as the GL gives them),
    row 0 at the top: a view of the rows read, not a flipped copy (at 2048² a second copy of
    every frame's picture)."""
    w, h = size
    components, dtype = (1, np.float32) if fmt == "depth" else (FORMATS[fmt][0], _DTYPES[FORMATS[fmt][1]])
    array = np.empty((h, w, components), dtype)
    read_into(array)
    if array.dtype == np.float16:
        array = array.astype(np.float32)
    return array[::-1]


# compared by identity, never by value: no generated equality to build when the module loads
@dataclass(eq=False)
class PendingRead:
    """A target copied into a pixel buffer on the GPU, not yet brought back: ``collect`` waits
    only for that copy, so frames issued after it overlap the transfer."""

    buffer: object
    size: tuple[int, int]
    fmt: str
    nbytes: int

    def collect(self) -> np.ndarray:
        return _received(lambda array: self.buffer.read_into(array, size=self.nbytes), self.size, self.fmt)


def texture_bytes(tex) -> int:
    """Bytes of a 2D texture's pixels as ``read`` returns them."""
    return tex.size[0] * tex.size[1] * tex.components * int(tex.dtype[1:])


def read_texture_later(tex, fmt: str, buffer) -> PendingRead:
    """Start bringing ``tex`` back through ``buffer`` (at least ``texture_bytes(tex)`` long)."""
    tex.read_into(buffer)
    return PendingRead(buffer, tuple(tex.size[:2]), fmt, texture_bytes(tex))


def upload_array(pool, name: str, array: np.ndarray, fmt: str):
    """``array`` (H, W, C) in texture row order as the pool's texture ``name`` in ``fmt``."""
    h, w = array.shape[:2]
    if fmt == "depth":
        tex = pool.depth(name, (w, h))
        tex.write(np.ascontiguousarray(array, np.float32).tobytes())
        return tex
    components, dtype = FORMATS[fmt]
    tex = pool.texture(name, (w, h), fmt)
    tex.write(np.ascontiguousarray(np.asarray(array).reshape(h, w, components), _DTYPES[dtype]).tobytes())
    return tex


def default_format(array: np.ndarray) -> str:
    c = array.shape[2] if array.ndim == 3 else 1
    if array.dtype == np.uint8:
        return {1: "r8", 4: "rgba8"}[c]
    if np.issubdtype(array.dtype, np.integer):
        return {1: "r32i", 2: "rg32i"}[c]
    return {1: "r32f", 2: "rg32f", 4: "rgba32f"}[c]
