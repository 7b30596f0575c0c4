"""PLY, ASCII and binary: no up axis of its own (scans lie any way: the shape decides), no unit."""

from __future__ import annotations

from pathlib import Path

from blueprint.errors import InputError
from blueprint.scene.formats.base import Format
from blueprint.scene.headers import ASCII_VALUE, read_head, refuse_count

__all__ = ["FORMAT", "check"]

# the bytes of a binary value, by its PLY type
_SIZES = {
    **dict.fromkeys(("char", "uchar", "int8", "uint8"), 1),
    **dict.fromkeys(("short", "ushort", "int16", "uint16"), 2),
    **dict.fromkeys(("int", "uint", "float", "int32", "uint32", "float32"), 4),
    **dict.fromkeys(("double", "float64"), 8),
}


def check(path: Path, size: int, data: bytes | None = None) -> None:
    """Refuse a header whose element counts are not whole, are negative, or need more bytes
    than the file's ``size`` holds (each value at least its type's size, or two characters)."""
    text = read_head(path, data).decode("latin-1")
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
                each += _SIZES.get(kind, 1)
            else:
                each += ASCII_VALUE
            elements[-1] = (name, count, each)
    body = size - end
    need = 0
    for name, count, each in elements:
        need += count * max(each, 1)
        if need > body:
            raise refuse_count(path, count, f"{name} elements", size)


FORMAT = Format("PLY", ("ply",), up="guess", check=check, common=True)
