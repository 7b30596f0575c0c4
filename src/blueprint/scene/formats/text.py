"""Whole-file passes over the bytes of a text format, for the readers of OBJ, ASCII STL, ASCII
PLY and OFF: lines and words found by byte comparisons, the lines of interest gathered into one
text, and their numbers converted by one ``np.fromstring`` call, which reads them as trimesh's
readers do. No Python object is made per number, nor per line where lines of a kind come in
runs.
"""

from __future__ import annotations

import warnings

import numpy as np

__all__ = [
    "affordable",
    "blanked",
    "gathered",
    "is_ascii",
    "line_words",
    "lines",
    "find_all",
    "only",
    "parse",
    "word_spans",
]

# Runs of lines gathered a slice at a time up to this many a byte of the file; beyond, the
# file's bytes outside them are blanked in one pass instead.
_RUNS_PER_BYTE = 1 / 64


def affordable(data: bytes, lines: bool = True) -> bool:
    """Whether the passes over ``data`` fit the memory budget: they hold a few copies of the
    text and, where they read its ``lines``, some 80 bytes of index a line (a file of nothing
    but newlines holds the most)."""
    from blueprint import settings

    indexed = 80 * data.count(b"\n") if lines else 0
    return indexed + 6 * len(data) <= settings.MEMORY_BUDGET // 2


def is_ascii(buf: np.ndarray) -> bool:
    """Whether the bytes ``buf`` (uint8) are all ASCII."""
    return not len(buf) or int(buf.max()) < 128


def lines(buf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first and one past the last byte of each line of ``buf`` (uint8), the newline left
    out; a file that ends in a newline ends in an empty line."""
    newline = np.flatnonzero(buf == ord("\n"))
    return np.r_[0, newline + 1], np.r_[newline, len(buf)]


def _word_bytes(buf: np.ndarray) -> np.ndarray:
    """(N,) bool: the bytes that are part of a word. Control characters count as spaces, which
    ``bytes.split`` keeps in words: a line that holds one is passed over as blank, where it is
    not read as numbers (which it would end)."""
    return buf > ord(" ")


def line_words(buf: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """(L,) int64: the words of each line (``lines``: its first bytes, in order, covering the
    whole of ``buf``)."""
    word = _word_bytes(buf)
    starting = np.empty(len(buf), np.uint8)
    if len(buf):
        starting[0] = word[0]
        np.greater(word[1:], word[:-1], out=starting[1:])
    counts = np.zeros(len(starts), np.int64)
    inside = starts < len(buf)
    if inside.any():
        # summed in int32 (many times faster than in int64 here); no line holds 2^31 words
        counts[inside] = np.add.reduceat(starting, starts[inside], dtype=np.int32)
    return counts


def word_spans(buf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first and one past the last byte of every word of ``buf``."""
    edges = np.flatnonzero(np.diff(np.r_[False, _word_bytes(buf), False]))
    return edges[0::2], edges[1::2]


def gathered(data: bytes, starts: np.ndarray, ends: np.ndarray, keyword: bytes = b"") -> bytes:
    """The lines ``starts[i]:ends[i]`` of ``data`` (whole lines, in order, each beginning with
    ``keyword``) as one text of their words after the keyword, lines apart: runs of lines that
    follow one another are taken a slice a run."""
    if not len(starts):
        return b""
    follows = np.r_[False, starts[1:] == ends[:-1] + 1]
    first = starts[~follows]
    last = ends[np.r_[np.flatnonzero(~follows)[1:] - 1, len(ends) - 1]]
    if len(first) > _RUNS_PER_BYTE * len(data) + 1024:
        text = blanked(np.frombuffer(data, np.uint8), starts + len(keyword), ends)
        return text
    text = b"\n" + b"\n".join(data[a:b] for a, b in zip(first.tolist(), last.tolist(), strict=True))
    return text.replace(b"\n" + keyword, b"\n" + b" " * len(keyword)) if keyword else text


def blanked(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> bytes:
    """The bytes of ``buf`` with every byte outside the spans ``starts[i]:ends[i]`` (sorted, not
    overlapping) made a space."""
    bounds = np.empty(2 * len(starts) + 2, np.int64)
    bounds[0], bounds[-1] = 0, len(buf)
    bounds[1:-1:2], bounds[2:-1:2] = starts, ends
    # the runs between the bounds: outside, inside, outside, ...
    keep = np.repeat(np.arange(len(bounds) - 1) % 2 == 1, np.diff(bounds))
    out = np.full(len(buf), ord(" "), np.uint8)
    np.copyto(out, buf, where=keep)
    return out.tobytes()


def find_all(buf: np.ndarray, word: bytes, begin: int = 0, end: int | None = None) -> np.ndarray:
    """(K,) int64: where ``word`` begins in ``buf[begin:end]`` (offsets into ``buf``), for a
    word whose first byte is rare in the rest of the text."""
    end = len(buf) if end is None else end
    found = np.flatnonzero(buf[begin : end - len(word) + 1] == word[0]) + begin
    for k in range(1, len(word)):
        found = found[buf[found + k] == word[k]]
    return found


def only(text: bytes, allowed: bytes) -> bool:
    """Whether ``text`` holds no byte but the ``allowed`` ones (and whitespace)."""
    return not text.translate(None, allowed + b" \t\r\n")


def parse(text: bytes, dtype, count: int | None = None) -> np.ndarray | None:
    """The numbers of ``text`` (numbers and whitespace) as ``dtype``, read by ``np.fromstring``
    (as trimesh reads them); None where a word is not a number, or they are not ``count``
    numbers where that is given."""
    with warnings.catch_warnings():
        # a word that is not a number ends the reading early, with a warning
        warnings.simplefilter("error")
        try:
            values = np.fromstring(text, dtype=dtype, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
    return values if count is None or len(values) == count else None
