"""OFF: no up axis of its own (the shape decides), no unit."""

from __future__ import annotations

from pathlib import Path

from blueprint.errors import InputError
from blueprint.scene.formats.base import Format
from blueprint.scene.headers import ASCII_VALUE, read_all, read_head, refuse_count

__all__ = ["FORMAT", "check"]


def check(path: Path, size: int, data: bytes | None = None) -> None:
    """Refuse negative counts, counts the file's ``size`` cannot hold, and a face whose corner
    count is more than the values its line holds."""
    if _check_counts(path, read_head(path, data).decode("latin-1"), size):
        _check_faces(path, read_all(path, data))


def _check_counts(path: Path, text: str, size: int) -> bool:
    """Whether ``text`` begins an OFF header whose counts ``size`` bytes can hold (refused if not)."""
    words: list[str] = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            words += line.split()
        if len(words) >= 4:
            break
    if not words or not words[0].endswith("OFF") or len(words) < 3:
        return False
    try:
        vertices, faces = int(words[1]), int(words[2])
    except ValueError:
        return False
    if vertices < 0 or faces < 0:
        raise InputError(f"{path}: the header declares a negative count ({vertices} vertices, {faces} faces)")
    # a vertex is at least three values, a face its corner count and three corners
    if vertices * 3 * ASCII_VALUE > size:
        raise refuse_count(path, vertices, "vertices", size)
    if vertices * 3 * ASCII_VALUE + faces * 4 * ASCII_VALUE > size:
        raise refuse_count(path, faces, "faces", size)
    return True


def _check_faces(path: Path, data: bytes) -> None:
    """Refuse an OFF face whose corner count is more than the values its line holds (a face
    of 10^9 corners listing three): trimesh reads the first corners and says nothing."""
    lines = (line.split(b"#", 1)[0].split() for line in data.splitlines())
    lines = (words for words in lines if words)
    header = next(lines, [])
    counts = header[1:] if len(header) > 1 else next(lines, [])
    try:
        vertices, faces = int(counts[0]), int(counts[1])
    except (ValueError, IndexError):
        return  # the loader says what is wrong
    for _ in range(vertices):
        if next(lines, None) is None:
            return
    for index in range(faces):
        words = next(lines, None)
        if words is None:
            return
        try:
            corners = int(words[0])
        except ValueError:
            raise InputError(f"{path}: face {index} does not begin with its corner count") from None
        if corners < 1 or corners > len(words) - 1:
            raise InputError(f"{path}: face {index} declares {corners} corners and lists {len(words) - 1}")


FORMAT = Format("OFF", ("off",), up="guess", check=check, common=True)
