"""PNG images and NPZ layer stacks, written atomically; the checks an output path passes first."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from blueprint.errors import InputError


def check_output(path: str | os.PathLike, suffixes: tuple[str, ...], suffix: str | None = None) -> Path:
    """Fail early, before any rendering, on an output path that cannot be written: its suffix
    (or ``suffix``, the format it is to be written in whatever its name) not among
    ``suffixes``, a directory, or in a folder that is missing or read-only."""
    path = Path(path)
    if (suffix or path.suffix).lower() not in suffixes:
        raise InputError(f"{path}: output must end in {' or '.join(suffixes)}")
    if path.is_dir():
        raise InputError(f"{path}: is a directory")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise InputError(f"{path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise InputError(f"{path}: folder {folder} is not writable")
    if path.exists() and not os.access(path, os.W_OK):
        raise InputError(f"{path}: file is not writable")
    return path


def publish(tmp: str | os.PathLike, path: Path) -> None:
    """Rename a finished temporary file onto ``path``, with the permissions the file would have
    had if written directly: temporary files are private (0600), a drawing is not."""
    try:
        mode = os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    os.chmod(tmp, mode)
    os.replace(tmp, path)


@contextlib.contextmanager
def _temporary(path: Path) -> Iterator[Path]:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:64]}.", suffix=".tmp", dir=path.parent or ".")
    os.close(fd)
    try:
        yield Path(tmp)
        publish(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def atomic_write(path: str | os.PathLike, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp)`` then rename ``tmp`` onto ``path``: readers never see half a file."""
    path = Path(path)
    try:
        with _temporary(path) as tmp:
            write(tmp)
    except OSError as exc:
        raise InputError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return path


def save_png(path: str | os.PathLike, image: np.ndarray) -> Path:
    """Write an (H, W, 3 or 4) uint8 image as PNG."""
    from PIL import Image

    picture = Image.fromarray(np.ascontiguousarray(image))
    return atomic_write(path, lambda tmp: picture.save(tmp, format="PNG"))


def save_layers(path: str | os.PathLike, layers) -> Path:
    """Write peeled layers as NPZ: depth, triangle, part, normal, view, projection."""

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            np.savez_compressed(
                fh,
                depth=layers.depth.astype(np.float32),
                triangle=layers.triangle.astype(np.int32),
                part=layers.part.astype(np.int32),
                normal=layers.normal.astype(np.float16),
                view=layers.view.astype(np.float64),
                projection=layers.projection.astype(np.float64),
            )

    return atomic_write(path, write)
