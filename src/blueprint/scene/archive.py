"""Compressed model files expanded with bounds: a zip archive (and the zip containers 3MF and
3DXML) is refused by the sizes its directory declares before any member is expanded, and a
``.gz``, ``.bz2`` or ``.xz`` stream is expanded a chunk at a time and stopped at the limit, so
that two kilobytes that expand to gigabytes cost a few megabytes of memory and one line.

Two limits, both named in the message: the expanded size of all members together
(``blueprint.settings.EXPANDED_LIMIT``, set from the machine's memory) and how many times the
compressed size they expand to (``EXPANSION_RATIO_LIMIT``; small archives are exempt, as a few
hundred bytes of text compress far better than models do).
"""

from __future__ import annotations

import io
import zlib
from pathlib import Path

from blueprint import settings
from blueprint.errors import InputError
from blueprint.settings import human_size, open_file, read_at_most

__all__ = ["STREAM_SUFFIXES", "ZIP_CONTAINERS", "check_zip", "expand_stream", "members"]

# single-stream compression: model.stl.gz holds one STL (or model.tar.gz a tar of files)
STREAM_SUFFIXES = ("gz", "bz2", "xz")
# formats that are zip archives inside, which their trimesh loaders expand whole
ZIP_CONTAINERS = ("zip", "3mf", "3dxml")
# below this expanded size the ratio is not held against an archive
_RATIO_FLOOR = 1 << 20
_CHUNK = 1 << 20
# the bit of a zip member's flags that says it is encrypted (a password is needed)
_ENCRYPTED = 0x1


def _limits() -> tuple[int, int]:
    # read at each call, so that tests can lower them
    return settings.EXPANDED_LIMIT, settings.EXPANSION_RATIO_LIMIT


def _check_total(path: Path, expanded: int, compressed: int, what: str) -> None:
    limit, ratio = _limits()
    if expanded > limit:
        raise InputError(
            f"{path}: {what} expands to more than {human_size(limit)}, the limit for a model's "
            f"contents (set from this machine's memory; {settings.MEMORY_ENV} changes it)"
        )
    if expanded > _RATIO_FLOOR and expanded > ratio * max(compressed, 1):
        raise InputError(
            f"{path}: {what} expands to more than {ratio} times its compressed size "
            f"({human_size(compressed)} to {human_size(expanded)}): refused as a decompression bomb"
        )


def check_zip(path: Path, data: bytes | None = None) -> None:
    """Refuse a zip archive whose members, by the sizes its central directory declares, expand
    beyond the limits, or that holds an encrypted member. Those sizes bound what can be read:
    Python's zipfile stops a member at its declared size (and a member that holds more fails
    its checksum), so a lie cannot expand further. ``data``: the archive's bytes where they
    are in memory (a member of another archive), else the file is read."""
    # the archive modules are imported where used: a plain model file's drawing needs none
    import zipfile

    limit = settings.MODEL_FILE_LIMIT
    with io.BytesIO(data) if data is not None else open_file(path, limit, "a model file") as fh:
        try:
            with zipfile.ZipFile(fh) as archive:
                infos = archive.infolist()
        except (zipfile.BadZipFile, zipfile.LargeZipFile, ValueError, OSError, EOFError):
            raise InputError(f"{path}: not a readable zip archive") from None
    expanded = sum(info.file_size for info in infos)
    compressed = sum(info.compress_size for info in infos)
    _check_total(path, expanded, compressed, "the archive")
    locked = [info.filename for info in infos if info.flag_bits & _ENCRYPTED]
    if locked:
        raise InputError(f"{path}: {locked[0]} in the archive is encrypted (a password is needed to read it)")


def _decompressor(kind: str):
    if kind == "gz":
        return zlib.decompressobj(16 + zlib.MAX_WBITS)
    if kind == "bz2":
        import bz2

        return bz2.BZ2Decompressor()
    import lzma

    return lzma.LZMADecompressor()


def expand_stream(path: Path, kind: str) -> bytes:
    """The contents of a ``.gz``, ``.bz2`` or ``.xz`` file (``kind`` its suffix), expanded a
    chunk at a time: at no point more than the limit plus one chunk is held, whatever the
    stream claims. Concatenated streams (``cat a.gz b.gz``) expand to their concatenation."""
    import lzma

    limit, ratio = _limits()
    with open_file(path, settings.MODEL_FILE_LIMIT, "a model file") as fh:
        # no more than the limit, should the file grow after its check
        compressed = read_at_most(fh, settings.MODEL_FILE_LIMIT)
    out = bytearray()
    data = compressed
    try:
        while data:
            decompressor = _decompressor(kind)
            # at most a chunk out of each call, however far the input would expand
            if kind == "gz":
                pending = data
                while not decompressor.eof:
                    chunk = decompressor.decompress(pending, _CHUNK)
                    pending = decompressor.unconsumed_tail
                    out += chunk
                    _check_total(path, len(out), len(compressed), "the compressed stream")
                    if not chunk and not pending and not decompressor.eof:
                        raise InputError(f"{path}: the compressed stream ends early")
            else:
                chunk = decompressor.decompress(data, _CHUNK)
                while True:
                    out += chunk
                    _check_total(path, len(out), len(compressed), "the compressed stream")
                    if decompressor.eof:
                        break
                    if decompressor.needs_input:
                        raise InputError(f"{path}: the compressed stream ends early")
                    chunk = decompressor.decompress(b"", _CHUNK)
            data = decompressor.unused_data
    except (zlib.error, OSError, lzma.LZMAError, EOFError, ValueError):
        raise InputError(f"{path}: not a readable {kind} stream") from None
    return bytes(out)


def members(path: Path, ext: str) -> dict[str, bytes]:
    """The files of a model archive, name to contents: the members of a zip (checked by
    ``check_zip`` first, then read a chunk at a time against the same limit), the one file of
    a ``.gz``, ``.bz2`` or ``.xz`` named as the file without that suffix, or the members of
    the tar archive such a stream holds. Directories, links and devices in a tar are skipped."""
    if ext == "zip":
        check_zip(path)
        return _zip_members(path)
    data = expand_stream(path, ext)
    inner = path.stem
    if not inner.lower().endswith(".tar"):
        return {inner: data}
    import tarfile

    try:
        with tarfile.open(fileobj=io.BytesIO(data), mode="r:") as archive:
            return {
                info.name: archive.extractfile(info).read() for info in archive.getmembers() if info.isfile()
            }
    except (tarfile.TarError, OSError, EOFError):
        raise InputError(f"{path}: not a readable tar archive") from None


def _zip_members(path: Path) -> dict[str, bytes]:
    import zipfile

    limit, _ = _limits()
    out: dict[str, bytes] = {}
    total = 0
    with open_file(path, settings.MODEL_FILE_LIMIT, "a model file") as fh:
        try:
            with zipfile.ZipFile(fh) as archive:
                for info in archive.infolist():
                    if info.is_dir():
                        continue
                    parts = []
                    with archive.open(info) as member:
                        while chunk := member.read(_CHUNK):
                            total += len(chunk)
                            if total > limit:
                                _check_total(path, total, 0, "the archive")
                            parts.append(chunk)
                    out[info.filename] = b"".join(parts)
        except (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, ValueError, OSError, EOFError):
            raise InputError(f"{path}: not a readable zip archive") from None
        except NotImplementedError:  # a compression method Python does not have
            raise InputError(f"{path}: the archive uses a compression this reader lacks") from None
    return out
