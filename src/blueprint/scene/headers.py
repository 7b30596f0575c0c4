"""Counts a model file's header declares, checked against the file's size before any loader
believes them: an ASCII PLY that declares 10^12 faces, or an OFF that claims ten times the faces
it holds, is refused at once instead of being read (or silently drawn short)."""

from __future__ import annotations

from pathlib import Path

from blueprint.errors import InputError
from blueprint.settings import open_file

# the most of a file read to find its header
HEADER_BYTES = 1 << 16
_PLY_SIZES = {
    **dict.fromkeys(("char", "uchar", "int8", "uint8"), 1),
    **dict.fromkeys(("short", "ushort", "int16", "uint16"), 2),
    **dict.fromkeys(("int", "uint", "float", "int32", "uint32", "float32"), 4),
    **dict.fromkeys(("double", "float64"), 8),
}
# the fewest bytes an ASCII value takes: a digit and a separator
_ASCII_VALUE = 2


def check_declared_counts(path: Path, ext: str, size: int, limit: int) -> None:
    """Raise ``InputError`` where the header of a PLY or OFF file declares more elements than
    ``size`` bytes can hold (other formats: nothing to check)."""
    if ext not in ("ply", "off"):
        return
    with open_file(path, limit, "a model file") as fh:
        head = fh.read(HEADER_BYTES)
    text = head.decode("latin-1")
    if ext == "ply":
        _check_ply(path, text, size)
    else:
        _check_off(path, text, size)


def _refuse(path: Path, count: int, what: str, size: int) -> InputError:
    return InputError(
        f"{path}: the header declares {count} {what}, more than the file's {size} bytes can hold"
    )


def _check_ply(path: Path, text: str, size: int) -> None:
    end = text.find("end_header")
    if not text.startswith("ply") or end < 0:
        return  # not a header we can read: the loader says what is wrong
    binary = False
    elements: list[tuple[str, int, int]] = []  # name, count, fewest bytes each
    for line in text[:end].splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] == "format" and len(words) > 1:
            binary = words[1].startswith("binary")
        elif words[0] == "element" and len(words) == 3:
            try:
                count = int(words[2])
            except ValueError:
                raise InputError(f"{path}: element {words[1]!r} has no whole count ({words[2]!r})") from None
            if count < 0:
                raise InputError(f"{path}: element {words[1]!r} has a negative count ({count})")
            elements.append((words[1], count, 0))
        elif words[0] == "property" and elements and len(words) >= 3:
            name, count, each = elements[-1]
            if binary:
                # a list takes at least its count; a scalar its type's size
                kind = words[2] if words[1] == "list" else words[1]
                each += _PLY_SIZES.get(kind, 1)
            else:
                each += _ASCII_VALUE
            elements[-1] = (name, count, each)
    body = size - end
    need = 0
    for name, count, each in elements:
        need += count * max(each, 1)
        if need > body:
            raise _refuse(path, count, f"{name} elements", size)


def _check_off(path: Path, text: str, size: int) -> None:
    words: list[str] = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            words += line.split()
        if len(words) >= 4:
            break
    if not words or not words[0].endswith("OFF") or len(words) < 3:
        return
    try:
        vertices, faces = int(words[1]), int(words[2])
    except ValueError:
        return
    if vertices < 0 or faces < 0:
        raise InputError(f"{path}: the header declares a negative count ({vertices} vertices, {faces} faces)")
    # a vertex is at least three values, a face its corner count and three corners
    if vertices * 3 * _ASCII_VALUE > size:
        raise _refuse(path, vertices, "vertices", size)
    if vertices * 3 * _ASCII_VALUE + faces * 4 * _ASCII_VALUE > size:
        raise _refuse(path, faces, "faces", size)
