"""Images and video in and out of pipelines: Pillow for images, imageio-ffmpeg for video.

Arrays are (H, W, C) with row 0 at the top of the picture. Video files are written atomically
(a temporary file in the same folder, renamed when the last frame is in); imageio-ffmpeg is
imported only when a video is read or written, so it is needed only then.
"""

from __future__ import annotations

import contextlib
import os
import warnings
from collections.abc import Iterable, Iterator
from pathlib import Path

import numpy as np

from blueprint.errors import InputError
from blueprint.export.files import temporary
from blueprint.export.writers import Kind, Writers
from blueprint.gpu.targets import FORMATS
from blueprint.settings import IMAGE_FILE_LIMIT, IMAGE_PIXEL_LIMIT, check_file

VIDEO_FORMATS = {".mp4": "mp4", ".mov": "mov", ".mkv": "matroska", ".avi": "avi", ".m4v": "mp4"}


def _ffmpeg():
    try:
        import imageio_ffmpeg
    except ImportError:
        raise InputError("video needs imageio-ffmpeg: pip install imageio-ffmpeg") from None
    return imageio_ffmpeg


def to_format(rgba: np.ndarray, fmt: str) -> np.ndarray:
    """(H, W, 3 or 4) uint8 to the components and dtype of target format ``fmt``."""
    if rgba.shape[-1] == 3:
        rgba = np.concatenate([rgba, np.full(rgba.shape[:2] + (1,), 255, np.uint8)], axis=-1)
    components, dtype = FORMATS[fmt]
    if components == 1:
        data = (rgba[..., :3].astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32))[..., None]
        data = np.clip(np.round(data), 0, 255).astype(np.uint8) if dtype == "f1" else data / 255.0
    else:
        data = rgba if dtype == "f1" else rgba.astype(np.float32) / 255.0
    return np.ascontiguousarray(data.astype({"f1": np.uint8, "f2": np.float16, "f4": np.float32}[dtype]))


def _check_image(path: Path) -> None:
    """Pillow opens the path itself: a FIFO would block it, so refuse one first."""
    if not os.path.exists(path):
        raise InputError(f"{path}: no such image file")
    check_file(path, IMAGE_FILE_LIMIT, "an image file")


def _check_video(path: Path) -> None:
    """ffmpeg opens the path itself: a FIFO would block it. No size limit: frames are streamed."""
    if not os.path.exists(path):
        raise InputError(f"{path}: no such video file")
    check_file(path, None)


def _check_pixels(path: Path, size: tuple[int, int]) -> None:
    """The header's size, read before any pixel is decoded: a small file may declare an image
    far larger than memory."""
    if size[0] * size[1] > IMAGE_PIXEL_LIMIT:
        raise InputError(
            f"{path}: the image declares {size[0]} x {size[1]} pixels, over the limit of {IMAGE_PIXEL_LIMIT}"
        )


@contextlib.contextmanager
def _opened(path: Path):
    """Pillow's image of ``path`` (checked first), its errors and those of reading its pixels
    in the ``with`` body as one-line ``InputError``s."""
    from PIL import Image, UnidentifiedImageError

    _check_image(path)
    try:
        # the header's size is checked here, against our limit: Pillow's warning would be a second line
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            picture = Image.open(path)
        with picture:
            yield picture
    except FileNotFoundError:
        raise InputError(f"{path}: no such image file") from None
    except Image.DecompressionBombError:
        raise InputError(f"{path}: the image declares more than {IMAGE_PIXEL_LIMIT} pixels") from None
    except UnidentifiedImageError:
        raise InputError(f"{path}: not an image in a format Pillow reads") from None
    except (OSError, ValueError, SyntaxError):  # Pillow's messages name its internals
        raise InputError(f"{path}: cannot read the image (it is damaged or cut short)") from None


def read_image(path: Path, fmt: str, size: tuple[int, int] | None = None) -> np.ndarray:
    """An image file as (H, W, C) in target format ``fmt``, resized to ``size`` if given."""
    from PIL import Image

    with _opened(path) as picture:
        _check_pixels(path, picture.size)
        picture = picture.convert("RGBA")
        if size is not None and picture.size != tuple(size):
            picture = picture.resize(tuple(size), Image.Resampling.BILINEAR)
        rgba = np.asarray(picture)
    return to_format(rgba, fmt)


def image_size(path: Path) -> tuple[int, int]:
    """(width, height) of an image or of a video's frames."""
    if path.suffix.lower() in VIDEO_FORMATS or path.suffix.lower() in (".webm", ".gif"):
        return video_info(path)[0]
    with _opened(path) as picture:
        return picture.size


def video_info(path: Path) -> tuple[tuple[int, int], float, int]:
    """(size, frames per second, frame count) of a video file."""
    ffmpeg = _ffmpeg()
    _check_video(path)
    try:
        reader = ffmpeg.read_frames(str(path))
        meta = next(reader)
        reader.close()
        frames, _ = ffmpeg.count_frames_and_secs(str(path))
    except (RuntimeError, OSError, StopIteration):  # ffmpeg's messages run to many lines
        raise InputError(f"{path}: cannot read the video (not a video ffmpeg reads, or damaged)") from None
    return tuple(meta["size"]), float(meta.get("fps") or 25.0), int(frames)


def read_video(path: Path) -> Iterator[np.ndarray]:
    """The frames of a video, each (H, W, 3) uint8."""
    ffmpeg = _ffmpeg()
    _check_video(path)
    try:
        reader = ffmpeg.read_frames(str(path))
        meta = next(reader)
    except (RuntimeError, OSError, StopIteration):
        raise InputError(f"{path}: cannot read the video (not a video ffmpeg reads, or damaged)") from None
    w, h = meta["size"]
    try:
        for raw in reader:
            yield np.frombuffer(raw, np.uint8).reshape(h, w, 3)
    finally:
        reader.close()


class VideoWriter:
    """Writes frames to a video file atomically: ``with VideoWriter(path, size, fps) as v:
    v.write(frame)``; the file appears, complete, when the block ends without an error."""

    def __init__(self, path: Path, size: tuple[int, int], fps: float = 25.0, crf: int = 18) -> None:
        self.path = Path(path)
        suffix = self.path.suffix.lower()
        if suffix not in VIDEO_FORMATS:
            raise InputError(f"{path}: a video must end in {', '.join(VIDEO_FORMATS)}")
        self.size = tuple(int(v) for v in size)
        self.fps = fps
        self.crf = crf
        self.frames = 0
        self._container = VIDEO_FORMATS[suffix]
        self._tmp: str | None = None
        self._gen = None

    def __enter__(self) -> VideoWriter:
        ffmpeg = _ffmpeg()
        self._stack = contextlib.ExitStack()
        try:
            self._tmp = str(self._stack.enter_context(temporary(self.path)))
        except OSError as error:
            raise InputError(f"{self.path}: cannot write ({error.strerror or error})") from None
        w, h = self.size
        # 4:2:0 (what players expect) needs even sizes; odd ones keep full chroma
        pix_fmt = "yuv420p" if w % 2 == 0 and h % 2 == 0 else "yuv444p"
        self._gen = ffmpeg.write_frames(
            self._tmp,
            self.size,
            fps=self.fps,
            codec="libx264",
            pix_fmt_out=pix_fmt,
            quality=None,
            macro_block_size=1,
            ffmpeg_log_level="error",
            output_params=["-crf", str(self.crf), "-f", self._container],
        )
        self._gen.send(None)
        return self

    def write(self, frame: np.ndarray) -> None:
        """Add an (H, W, 1, 3 or 4) uint8 frame, row 0 at the top (alpha is dropped)."""
        if frame.ndim == 2:
            frame = frame[..., None]
        if frame.shape[:2] != (self.size[1], self.size[0]):
            raise ValueError(
                f"frame is {frame.shape[1]}x{frame.shape[0]}, video is {self.size[0]}x{self.size[1]}"
            )
        if frame.shape[2] == 1:
            frame = np.repeat(frame, 3, axis=2)
        self._gen.send(np.ascontiguousarray(frame[..., :3], dtype=np.uint8))
        self.frames += 1

    def __exit__(self, kind, exc, tb) -> None:
        try:
            if self._gen is not None:
                with contextlib.suppress(StopIteration):
                    self._gen.close()
            if kind is None and self.frames == 0:
                raise InputError(f"{self.path}: no frames to write")
        except BaseException as error:
            self._stack.__exit__(type(error), error, error.__traceback__)
            raise
        try:
            # published only where the block ended without an error
            self._stack.__exit__(kind, exc, tb)
        except OSError as error:
            raise InputError(f"{self.path}: cannot write ({error.strerror or error})") from None


def register_writers(writers: Writers) -> None:
    """Add the video writer, one per container suffix, to ``writers``
    (``blueprint.export.writers.PROVIDERS`` names this function)."""
    for suffix in VIDEO_FORMATS:
        writers.add(suffix, Kind.VIDEO, write_video)


def write_video(path: str | Path, frames: Iterable[np.ndarray], *, fps: float = 30.0, crf: int = 18) -> Path:
    """Encode (H, W, 3 or 4) uint8 frames of one size as H.264 in the container the suffix
    names, written atomically; returns the path.

    Odd widths and heights are padded by one pixel (players expect 4:2:0 chroma, which needs
    even sizes) with the colour of the frame's edge.
    """

    def even(frame: np.ndarray) -> np.ndarray:
        h, w = frame.shape[:2]
        return np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")

    frames = iter(frames)
    first = next(frames, None)
    if first is None:
        raise InputError(f"{path}: no frames to write")
    first = even(first)
    with VideoWriter(Path(path), (first.shape[1], first.shape[0]), fps, crf) as video:
        video.write(first)
        for frame in frames:
            video.write(even(frame))
    return Path(path)
