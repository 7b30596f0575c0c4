"""PNG images and NPZ layer stacks, written atomically; the checks an output path passes first.

Every output is written to a temporary file and put in place whole. Where the file system
allows (Linux's ``O_TMPFILE``: ext4, XFS, Btrfs, tmpfs), the temporary file has no name until
it is linked into place, so a process killed mid-write leaves nothing behind: the kernel frees
the unnamed file with the process. Elsewhere it is named ``.NAME.bpPID.XXXX.tmp`` beside the
output, and every later write into that folder removes such files whose process has died.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import stat
import struct
import time
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from blueprint import parallel, settings
from blueprint.errors import InputError

__all__ = [
    "atomic_write",
    "check_output",
    "png_bytes",
    "save_layers",
    "save_png",
    "sweep_temporaries",
    "temporary",
]

# what our named temporary files are called: the output's name, our process id, a token
_NAMED = re.compile(r"^\..*\.bp(\d+)\.[0-9A-Za-z_]+\.tmp$")
# a named temporary file of a dead process is left alone this long after its last write: the
# process id may be of another machine or container writing into a shared folder
STALE_SECONDS = 60.0
# errors that say the file system has no O_TMPFILE (the folder's, or the kernel's)
_NO_TMPFILE = (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL, errno.ENOENT)


def _folder(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")


def _stat(path: Path) -> os.stat_result | None:
    """``path``'s stat, None where there is no such file; any other failure (a name too long
    for the file system, a path through a file) is one line."""
    try:
        return os.stat(path)
    except (FileNotFoundError, NotADirectoryError):  # the folder's check says which
        return None
    except OSError as exc:
        raise InputError(f"{path}: cannot write ({exc.strerror or exc})") from None


def check_output(path: str | os.PathLike, suffixes: tuple[str, ...], suffix: str | None = None) -> Path:
    """Fail early, before any rendering, on an output path that cannot be written: its suffix
    (or ``suffix``, the format it is to be written in whatever its name) not among
    ``suffixes``, a directory, a name too long, or in a folder that is missing, read-only or
    takes no new files (``/proc``): a temporary file is made there, and removed, to know."""
    path = Path(path)
    if (suffix or path.suffix).lower() not in suffixes:
        raise InputError(f"{path}: output must end in {' or '.join(suffixes)}")
    info = _stat(path)
    if info is not None and stat.S_ISDIR(info.st_mode):
        raise InputError(f"{path}: is a directory")
    folder = _folder(path)
    if not os.path.isdir(folder):
        raise InputError(f"{path}: folder {folder} does not exist")
    if not os.access(folder, os.W_OK):
        raise InputError(f"{path}: folder {folder} is not writable")
    if info is not None and not os.access(path, os.W_OK):
        raise InputError(f"{path}: file is not writable")
    try:
        with _open_temporary(path):
            pass
    except OSError as exc:
        raise InputError(f"{path}: folder {folder} takes no new files ({exc.strerror or exc})") from None
    return path


def _mode(path: Path) -> int:
    """The permissions ``path`` would have had if written directly: temporary files are
    private (0600), a drawing is not."""
    try:
        return os.stat(path).st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def _named(path: Path) -> str:
    return f".{path.name[:64]}.bp{os.getpid()}.{os.urandom(4).hex()}.tmp"


class _Temporary:
    """A temporary file for ``path``: unnamed (``fd`` set) or named (``name`` set). ``path``
    is what writers open: ``/proc/PID/fd/N`` for an unnamed one, which other processes
    (ffmpeg) can open too."""

    def __init__(self, target: Path) -> None:
        self.target = target
        self.fd: int | None = None
        self.name: Path | None = None
        folder = _folder(target)
        try:
            self.fd = os.open(folder, os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, 0o600)
        except AttributeError:  # not Linux
            pass
        except OSError as exc:
            if exc.errno not in _NO_TMPFILE:
                raise
        if self.fd is not None:
            self.path = Path(f"/proc/{os.getpid()}/fd/{self.fd}")
        else:
            import tempfile

            prefix = f".{target.name[:64]}.bp{os.getpid()}."
            fd, name = tempfile.mkstemp(prefix=prefix, suffix=".tmp", dir=folder)
            os.close(fd)
            self.name = self.path = Path(name)

    def publish(self) -> None:
        """Put the finished file in place of the target, whole."""
        mode = _mode(self.target)
        if self.name is not None:
            os.chmod(self.name, mode)
            os.replace(self.name, self.target)
            self.name = None
            return
        os.fchmod(self.fd, mode)
        folder = os.open(_folder(self.target), os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        try:
            # a name for the file, then the rename over the target: link(2) cannot replace
            name = _named(self.target)
            os.link(f"/proc/self/fd/{self.fd}", name, dst_dir_fd=folder, follow_symlinks=True)
            try:
                os.replace(name, self.target.name, src_dir_fd=folder, dst_dir_fd=folder)
            except OSError:
                with contextlib.suppress(OSError):
                    os.unlink(name, dir_fd=folder)
                raise
        finally:
            os.close(folder)

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None
        if self.name is not None:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(self.name)
            self.name = None


@contextlib.contextmanager
def _open_temporary(path: Path) -> Iterator[_Temporary]:
    tmp = _Temporary(path)
    try:
        yield tmp
    finally:
        tmp.close()


@contextlib.contextmanager
def temporary(path: str | os.PathLike) -> Iterator[Path]:
    """A path to write ``path``'s contents to, put in place of ``path`` when the block ends
    without an error, and gone otherwise, or if the process is killed (see the module's
    docstring). Stale temporary files of dead processes in the folder are removed first."""
    path = Path(path)
    sweep_temporaries(_folder(path))
    with _open_temporary(path) as tmp:
        yield tmp.path
        tmp.publish()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, of another user
        return True
    return True


def sweep_temporaries(folder: str | os.PathLike) -> list[str]:
    """Remove the named temporary files that processes of ours, now dead, left in ``folder``
    (killed mid-write where the file system has no unnamed files), untouched for
    ``STALE_SECONDS``; returns their names. Files of living processes, and any other file,
    are left alone."""
    removed = []
    now = time.time()
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        match = _NAMED.match(entry.name)
        if not match or int(match.group(1)) == os.getpid() or _alive(int(match.group(1))):
            continue
        try:
            if not entry.is_file(follow_symlinks=False) or now - entry.stat().st_mtime < STALE_SECONDS:
                continue
            os.unlink(entry.path)
        except OSError:
            continue
        removed.append(entry.name)
    return removed


def atomic_write(path: str | os.PathLike, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp)`` then put ``tmp`` in place of ``path``: readers never see half a file,
    and a failed or killed write leaves none."""
    path = Path(path)
    try:
        with temporary(path) as tmp:
            write(tmp)
    except OSError as exc:
        raise InputError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return path


# PNG's colour type by channels: grey, grey and alpha, RGB, RGBA
_PNG_COLOUR = {1: 0, 2: 4, 3: 2, 4: 6}
# bytes of a PNG's rows deflated at a time, side by side, where they are more than four such
_PNG_PIECE = 1 << 21
# a zlib stream's header: deflate, a 32 KiB window, the default level
_ZLIB_HEADER = b"\x78\x9c"


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png_bytes(image: np.ndarray) -> bytes:
    """An (H, W) or (H, W, 1 to 4) uint8 image (grey, grey and alpha, RGB, RGBA), row 0 at the
    top, as the bytes of a PNG file.

    Encoded here with zlib rather than by Pillow: importing Pillow cost a small drawing's
    process more than the whole encoding, and rows left unfiltered compress drawings (flat
    paper, thin lines) smaller than Pillow's adaptive filters at its default level.
    """
    image = np.asarray(image)
    channels = 1 if image.ndim == 2 else (image.shape[2] if image.ndim == 3 else 0)
    if image.dtype != np.uint8 or channels not in _PNG_COLOUR or 0 in image.shape:
        raise ValueError(f"a PNG image is (H, W) or (H, W, 1-4) uint8, got {image.shape} {image.dtype}")
    height, width = image.shape[:2]
    rows = np.empty((height, 1 + width * channels), np.uint8)
    rows[:, 0] = 0  # filter type None on every row
    rows[:, 1:] = image.reshape(height, width * channels)
    header = struct.pack(">IIBBBBB", width, height, 8, _PNG_COLOUR[channels], 0, 0, 0)
    return b"".join(
        (
            b"\x89PNG\r\n\x1a\n",
            _png_chunk(b"IHDR", header),
            _png_chunk(b"IDAT", _deflated(memoryview(rows.reshape(-1)))),
            _png_chunk(b"IEND", b""),
        )
    )


def _deflated(raw: memoryview) -> bytes:
    """``zlib.compress(raw, 6)``'s stream, for rows of more than four ``_PNG_PIECE`` bytes made
    of pieces of that many deflated side by side on the pool (zlib lets go of the GIL): each
    piece but the last ends on a byte with a sync flush, so that the pieces follow one another
    as one stream's blocks; the checksum is the whole's."""
    if len(raw) <= 4 * _PNG_PIECE or settings.THREADS == 1:
        return zlib.compress(raw, 6)

    def deflate(start: int) -> bytes:
        stop = min(start + _PNG_PIECE, len(raw))
        piece = zlib.compressobj(6, zlib.DEFLATED, -15)
        return piece.compress(raw[start:stop]) + piece.flush(
            zlib.Z_FINISH if stop == len(raw) else zlib.Z_SYNC_FLUSH
        )

    pieces = parallel.each(deflate, list(range(0, len(raw), _PNG_PIECE)))
    return b"".join((_ZLIB_HEADER, *pieces, struct.pack(">I", zlib.adler32(raw))))


def save_png(path: str | os.PathLike, image: np.ndarray) -> Path:
    """Write an (H, W) or (H, W, 1 to 4) uint8 image as PNG (``png_bytes``), atomically."""
    data = png_bytes(image)
    return atomic_write(path, lambda tmp: tmp.write_bytes(data))


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
